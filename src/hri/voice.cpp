// The voice engines, built when CMake found espeak-ng and pocketsphinx (TRIPODAL_VOICE).
#include <espeak-ng/speak_lib.h>
#include <pocketsphinx.h>
#include <unistd.h>

#include <array>
#include <cstdlib>
#include <fstream>
#include <mutex>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "tripodal/hri/speech.hpp"

namespace tripodal {

bool voice_available() noexcept { return true; }

namespace {

// espeak-ng keeps one engine per process: it is initialised once and every synthesis holds this.
std::mutex& espeak_mutex() {
  static std::mutex m;
  return m;
}

int on_samples(short* wav, int count, espeak_EVENT* events) {
  if (wav != nullptr && count > 0 && events != nullptr && events->user_data != nullptr) {
    auto* out = static_cast<std::vector<std::int16_t>*>(events->user_data);
    out->insert(out->end(), wav, wav + count);
  }
  return 0;  // continue
}

// The engine, initialised once for the process; its sample rate. Call with espeak_mutex() held.
int espeak_engine() {
  static const int rate = espeak_Initialize(AUDIO_OUTPUT_SYNCHRONOUS, 0, nullptr, espeakINITIALIZE_DONT_EXIT);
  if (rate <= 0) throw std::runtime_error("espeak-ng: cannot initialise (is espeak-ng-data installed?)");
  return rate;
}

class EspeakSynthesizer final : public SpeechSynthesizer {
 public:
  explicit EspeakSynthesizer(EspeakOptions options) : options_(std::move(options)) {
    const std::lock_guard lock(espeak_mutex());
    rate_hz_ = espeak_engine();
  }

  AudioClip synthesize(std::string_view text) override {
    const std::lock_guard lock(espeak_mutex());
    if (espeak_SetVoiceByName(options_.voice.c_str()) != EE_OK) {
      throw std::runtime_error("espeak-ng: no voice '" + options_.voice + "'");
    }
    espeak_SetParameter(espeakRATE, options_.words_per_minute, 0);
    espeak_SetSynthCallback(on_samples);
    AudioClip clip;
    clip.sample_rate_hz = rate_hz_;
    const std::string z(text);
    const espeak_ERROR e = espeak_Synth(z.c_str(), z.size() + 1, 0, POS_CHARACTER, 0, espeakCHARS_UTF8, nullptr, &clip.samples);
    if (e != EE_OK || espeak_Synchronize() != EE_OK) throw std::runtime_error("espeak-ng: synthesis failed");
    return clip;
  }

 private:
  EspeakOptions options_;
  int rate_hz_ = 22050;
};

// pocketsphinx reads its models from files only: `contents` in a new temporary file, its name.
std::string temporary_file(const std::string& contents, const std::string& what) {
  char name[] = "/tmp/tripodal_ps_XXXXXX";
  const int fd = ::mkstemp(name);
  if (fd < 0) throw std::runtime_error("pocketsphinx: cannot create a temporary " + what + " file");
  ::close(fd);
  std::ofstream out(name);
  out << contents;
  out.close();
  if (!out) {
    ::unlink(name);
    throw std::runtime_error("pocketsphinx: cannot write the temporary " + what + " file " + name);
  }
  return name;
}

class PocketsphinxRecognizer final : public SpeechRecognizer {
  static constexpr std::size_t kAlternatives = 8;
  static constexpr int kNbestVisits = 40;

 public:
  explicit PocketsphinxRecognizer(const PocketsphinxOptions& options) {
    if (!(options.general_model_weight >= 0.0 && options.general_model_weight <= 1.0)) {
      throw std::invalid_argument("pocketsphinx: general_model_weight is " + std::to_string(options.general_model_weight) +
                                  "; expected a share in [0, 1]");
    }
    const std::string hmm = (options.model_dir / "en-us").string();
    const std::string dict = (options.model_dir / "cmudict-en-us.dict").string();
    std::string lm = (options.model_dir / "en-us.lm.bin").string();
    if (!options.language_model.empty()) {
      lm_file_ = temporary_file(options.language_model, "language model");
      lm = lm_file_;
    }
    std::string dict_path = dict;
    if (!options.extra_pronunciations.empty()) {
      // The model's dictionary and the extra words.
      std::ostringstream text;
      if (std::ifstream in(dict); !(text << in.rdbuf())) {
        remove_files();
        throw std::runtime_error("pocketsphinx: cannot read the dictionary " + dict);
      }
      for (const auto& [word, phones] : options.extra_pronunciations) text << word << ' ' << phones << '\n';
      try {
        dict_file_ = temporary_file(text.str(), "dictionary");
      } catch (const std::runtime_error&) {
        remove_files();
        throw;
      }
      dict_path = dict_file_;
    }
    // argv[0] is the program's name, as for main().
    std::vector<std::string> args = {"tripodal", "-hmm", hmm, "-lm", lm, "-dict", dict_path, "-logfn", "/dev/null",
                                     // Synthesised and clipped audio has runs of exact zeros, whose
                                     // log energy is -inf in the cepstra: a little noise keeps them finite.
                                     "-dither", "yes",
                                     // A fixed seed, so that the dither is the same in every run.
                                     "-seed", "1"};
    for (const auto& [name, value] : options.arguments) {
      args.push_back(name);
      args.push_back(value);
    }
    std::vector<char*> argv;
    argv.reserve(args.size());
    for (auto& a : args) argv.push_back(a.data());
    config_ = cmd_ln_parse_r(nullptr, ps_args(), static_cast<int32>(argv.size()), argv.data(), TRUE);
    if (config_ == nullptr) remove_files();
    if (config_ == nullptr) throw std::runtime_error("pocketsphinx: bad configuration (model in " + options.model_dir.string() + ")");
    decoder_ = ps_init(config_);
    if (decoder_ == nullptr) {
      cmd_ln_free_r(config_);
      remove_files();
      throw std::runtime_error("pocketsphinx: cannot load the model in " + options.model_dir.string());
    }
    if (!options.language_model.empty() && options.general_model_weight > 0.0) {
      const std::string general = (options.model_dir / "en-us.lm.bin").string();
      if (!interpolate(lm, general, options.general_model_weight)) {
        ps_free(decoder_);
        cmd_ln_free_r(config_);
        remove_files();
        throw std::runtime_error("pocketsphinx: cannot interpolate the language model with " + general);
      }
    }
  }
  PocketsphinxRecognizer(const PocketsphinxRecognizer&) = delete;
  PocketsphinxRecognizer& operator=(const PocketsphinxRecognizer&) = delete;
  ~PocketsphinxRecognizer() override {
    ps_free(decoder_);
    cmd_ln_free_r(config_);
    remove_files();
  }

  int sample_rate_hz() const noexcept override { return 16000; }

  Result recognize(const AudioClip& audio) override {
    AudioClip clip = audio.sample_rate_hz == 16000 ? audio : resample(audio, 16000);
    // Cepstral mean normalisation and the silence model need a little silence around the words;
    // a clip cut tight around them (as a synthesiser makes) is padded with a quarter second.
    const std::vector<std::int16_t> pad(4000, 0);
    clip.samples.insert(clip.samples.begin(), pad.begin(), pad.end());
    clip.samples.insert(clip.samples.end(), pad.begin(), pad.end());
    if (ps_start_utt(decoder_) < 0) throw std::runtime_error("pocketsphinx: cannot start an utterance");
    if (!clip.samples.empty() && ps_process_raw(decoder_, clip.samples.data(), clip.samples.size(), FALSE, TRUE) < 0) {
      ps_end_utt(decoder_);
      throw std::runtime_error("pocketsphinx: cannot process the audio");
    }
    ps_end_utt(decoder_);
    std::int32_t score = 0;
    const char* hyp = ps_get_hyp(decoder_, &score);
    Result r;
    if (hyp == nullptr) return {std::string(), 0.0};
    r.words = hyp;
    logmath_t* lmath = ps_get_logmath(decoder_);
    r.confidence = logmath_exp(lmath, ps_get_prob(decoder_));
    // The n-best list by A* over the lattice: a few distinct sentences, the search bounded so a
    // long utterance's lattice cannot cost more than a fraction of its own decoding.
    std::set<std::string> seen{r.words};
    int visited = 0;
    std::optional<std::int32_t> top;  // the A* search's own score of its first sentence
    for (ps_nbest_t* nb = ps_nbest(decoder_); nb != nullptr; nb = ps_nbest_next(nb)) {
      std::int32_t alt_score = 0;
      const char* alt = ps_nbest_hyp(nb, &alt_score);
      if (alt == nullptr || ++visited > kNbestVisits || r.alternatives.size() >= kAlternatives) {
        ps_nbest_free(nb);
        break;
      }
      if (!top) top = alt_score;
      if (!seen.insert(alt).second) continue;
      r.alternatives.push_back({alt, logmath_log_to_ln(lmath, alt_score - *top)});
    }
    return r;
  }

 private:
  // The decoder's search becomes the linear interpolation of the domain model (share 1 - weight)
  // and the general one (weight), over the union of their words that the dictionary has.
  bool interpolate(const std::string& domain_file, const std::string& general_file, double weight) {
    cmd_ln_t* config = ps_get_config(decoder_);
    logmath_t* lmath = ps_get_logmath(decoder_);
    std::array<ngram_model_t*, 2> models{ngram_model_read(config, domain_file.c_str(), NGRAM_AUTO, lmath),
                                         ngram_model_read(config, general_file.c_str(), NGRAM_AUTO, lmath)};
    if (models[0] == nullptr || models[1] == nullptr) {
      for (ngram_model_t* m : models) {
        if (m != nullptr) ngram_model_free(m);
      }
      return false;
    }
    std::array<std::string, 2> names{"domain", "general"};
    std::array<char*, 2> name_ptrs{names[0].data(), names[1].data()};
    const std::array<float32, 2> weights{static_cast<float32>(1.0 - weight), static_cast<float32>(weight)};
    // Some sphinxbase releases retain the models a set is made of, others take them over: with one
    // reference more, the count after the set was made says which, and the set is left the only owner.
    for (ngram_model_t* m : models) ngram_model_retain(m);
    ngram_model_t* set = ngram_model_set_init(config, models.data(), name_ptrs.data(), weights.data(), 2);
    for (ngram_model_t* m : models) {
      if (ngram_model_free(m) > 1 || set == nullptr) ngram_model_free(m);
    }
    if (set == nullptr) return false;
    const bool ok = ps_set_lm(decoder_, "interpolated", set) == 0 && ps_set_search(decoder_, "interpolated") == 0;
    ngram_model_free(set);  // the search holds it
    return ok;
  }

  void remove_files() noexcept {
    if (!lm_file_.empty()) ::unlink(lm_file_.c_str());
    if (!dict_file_.empty()) ::unlink(dict_file_.c_str());
  }

  cmd_ln_t* config_ = nullptr;
  ps_decoder_t* decoder_ = nullptr;
  std::string lm_file_;
  std::string dict_file_;
};

}  // namespace

std::optional<std::string> espeak_pronunciation(std::string_view word) {
  const std::lock_guard lock(espeak_mutex());
  try {
    espeak_engine();
  } catch (const std::runtime_error&) {
    return std::nullopt;
  }
  if (espeak_SetVoiceByName("en-us") != EE_OK) return std::nullopt;
  const std::string text(word);
  const void* at = text.c_str();
  std::string mnemonics;
  // One clause at a time; a word is one clause, but the loop keeps to the documented contract.
  while (at != nullptr) {
    const char* phonemes = espeak_TextToPhonemes(&at, espeakCHARS_UTF8, 0);
    if (phonemes == nullptr) break;
    mnemonics += std::string(phonemes) + " ";
  }
  return arpabet_from_espeak(mnemonics);
}

std::unique_ptr<SpeechSynthesizer> make_espeak_synthesizer(const EspeakOptions& options) {
  return std::make_unique<EspeakSynthesizer>(options);
}

std::unique_ptr<SpeechRecognizer> make_pocketsphinx_recognizer(const PocketsphinxOptions& options) {
  return std::make_unique<PocketsphinxRecognizer>(options);
}

}  // namespace tripodal
