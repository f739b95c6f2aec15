// Issue 37, item 2: the visitor corpus spoken by several espeak-ng voices and speeds, with room
// noise mixed in at a few signal-to-noise ratios, recognised by pocketsphinx with the domain model
// interpolated with the general English one, and handled by the HRI: word error rate and answers
// right per kind (answer, command, refusal, out of domain), and the property that no spoken input
// starts a task other than the one it asked for. The suite runs a small subset with floors; the
// whole grid is the hidden test "[.spoken-eval]" (docs/hri.md gives the command).
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>

#include "spoken_jinny.hpp"
#include "tripodal/hri/hri_module.hpp"
#include "tripodal/hri/speech.hpp"

using namespace tripodal;

namespace {

namespace fs = std::filesystem;

struct Utterance {
  std::string text;  // as spoken: the `spoken` field, else `say`
  std::string outcome;
  std::string entry;
  std::string task;
};

std::vector<Utterance> load_set(const std::string& file, std::size_t stride) {
  const YAML::Node doc = YAML::LoadFile(TRIPODAL_TEST_DATA_DIR "/hri/" + file);
  std::vector<Utterance> out;
  std::size_t i = 0;
  for (const auto& u : doc["utterances"]) {
    if (i++ % stride != 0) continue;
    out.push_back({u["spoken"] ? u["spoken"].as<std::string>() : u["say"].as<std::string>(), u["outcome"].as<std::string>(),
                   u["entry"] ? u["entry"].as<std::string>() : std::string(),
                   u["task"] ? u["task"].as<std::string>() : std::string()});
  }
  return out;
}

// The four kinds, from the expected outcome.
std::string kind_of(const Utterance& u) {
  if (u.outcome == "answered") return "answer";
  if (u.outcome == "task_started") return "command";
  if (u.outcome == "task_refused") return "refusal";
  return "out of domain";
}
const std::vector<std::string> kKinds = {"answer", "command", "refusal", "out of domain"};

// Room noise made by sox (a crowd's pink noise over ventilation's brown rumble, band-limited to
// 60 Hz..4 kHz), repeatable (-R); nullopt when sox is not installed.
std::optional<AudioClip> room_noise(double seconds) {
  const fs::path file = fs::temp_directory_path() / ("tripodal_room_noise_" + std::to_string(::getpid()) + ".wav");
  const std::string command = "sox -R -n -r 16000 -b 16 -c 1 '" + file.string() + "' synth " + std::to_string(seconds) +
                              " pinknoise mix brownnoise highpass 60 lowpass 4000 2>/dev/null";
  // NOLINTNEXTLINE(cert-env33-c): the test runs sox, a fixed command line
  if (std::system(command.c_str()) != 0 || !fs::exists(file)) return std::nullopt;
  AudioClip noise = read_wav(file);
  fs::remove(file);
  return noise;
}

// The level of the speech in `clip`: the RMS over its 20 ms frames within 30 dB of the loudest
// (an active speech level: the pauses between words do not lower it).
double speech_rms(const AudioClip& clip) {
  const std::size_t frame = static_cast<std::size_t>(clip.sample_rate_hz) / 50;
  std::vector<double> energies;
  for (std::size_t at = 0; at + frame <= clip.samples.size(); at += frame) {
    double e = 0.0;
    for (std::size_t i = at; i < at + frame; ++i) e += static_cast<double>(clip.samples[i]) * clip.samples[i];
    energies.push_back(e / static_cast<double>(frame));
  }
  if (energies.empty()) return 0.0;
  const double loudest = *std::max_element(energies.begin(), energies.end());
  double sum = 0.0;
  std::size_t n = 0;
  for (const double e : energies) {
    if (e >= loudest * 1e-3) {
      sum += e;
      ++n;
    }
  }
  return std::sqrt(sum / static_cast<double>(n));
}

// `speech` (16 kHz) with half a second of room before and after and the room's noise throughout,
// scaled so the speech is `snr_db` above it; clipped to 16 bits as a microphone's converter would.
AudioClip in_the_room(const AudioClip& speech, const AudioClip& noise, double snr_db, std::size_t offset) {
  AudioClip out;
  out.sample_rate_hz = speech.sample_rate_hz;
  const std::size_t pad = static_cast<std::size_t>(speech.sample_rate_hz) / 2;
  out.samples.assign(speech.samples.size() + 2 * pad, 0);
  double noise_energy = 0.0;
  for (const std::int16_t s : noise.samples) noise_energy += static_cast<double>(s) * s;
  const double noise_rms = std::sqrt(noise_energy / static_cast<double>(std::max<std::size_t>(1, noise.samples.size())));
  const double gain = noise_rms > 0.0 ? speech_rms(speech) / std::pow(10.0, snr_db / 20.0) / noise_rms : 0.0;
  for (std::size_t i = 0; i < out.samples.size(); ++i) {
    double v = gain * noise.samples[(offset + i) % noise.samples.size()];
    if (i >= pad && i - pad < speech.samples.size()) v += speech.samples[i - pad];
    out.samples[i] = static_cast<std::int16_t>(std::clamp(std::lround(v), -32768L, 32767L));
  }
  return out;
}

struct Condition {
  std::string voice = "en-us+klatt";
  int words_per_minute = 170;
  std::optional<double> snr_db;  // none: clean
  [[nodiscard]] std::string name() const {
    return voice + " " + std::to_string(words_per_minute) + " wpm, " +
           (snr_db ? std::to_string(static_cast<int>(*snr_db)) + " dB SNR" : std::string("clean"));
  }
};

struct Figures {
  std::map<std::string, std::pair<std::size_t, std::size_t>> per_kind;  // right, of
  std::size_t word_errors = 0;
  std::size_t words = 0;
  std::size_t wrong_tasks = 0;
  std::size_t asked_first = 0;  // right after the visitor's yes
  std::string misses;
  [[nodiscard]] std::size_t right() const {
    std::size_t r = 0;
    for (const auto& [kind, f] : per_kind) r += f.first;
    return r;
  }
  [[nodiscard]] std::size_t total() const {
    std::size_t n = 0;
    for (const auto& [kind, f] : per_kind) n += f.second;
    return n;
  }
  [[nodiscard]] double accuracy() const {
    return total() == 0 ? 0.0 : static_cast<double>(right()) / static_cast<double>(total());
  }
  [[nodiscard]] double wer() const { return words == 0 ? 0.0 : static_cast<double>(word_errors) / static_cast<double>(words); }
};

// Speaks each utterance in `condition`, recognises it, hands it to a fresh Jinny (so no question is
// left open from the one before) and scores the reply as voice_test.cpp's round trip does: a task
// asked about first is right when it is the one meant, and the visitor answers yes then (no
// otherwise). Every task the planner is asked to start is checked against the one meant.
Figures speak(const std::vector<Utterance>& set, const Condition& condition, SpeechRecognizer& recognizer,
              const std::optional<AudioClip>& noise, const HriOptions& options = {}) {
  const auto voice = make_espeak_synthesizer({condition.voice, condition.words_per_minute});
  Figures f;
  std::size_t offset = 0;
  for (const auto& u : set) {
    AudioClip audio = resample(voice->synthesize(u.text), 16000);
    if (condition.snr_db && noise) {
      audio = in_the_room(audio, *noise, *condition.snr_db, offset);
      offset += 7919 * 3;  // another stretch of the room for the next utterance
    }
    const SpeechRecognizer::Result heard = recognizer.recognize(audio);
    const WordErrors e = word_errors(spoken_form(u.text), heard.words);
    f.word_errors += e.errors;
    f.words += e.reference_words;
    testing::SpokenJinny jinny(options);
    const HriReply r = jinny.hri.handle_heard(heard);
    const bool meant_task = u.outcome == "task_started" || (u.outcome == "answered" && !u.task.empty());
    const bool confirmed = meant_task && r.kind == HriReply::Kind::confirm_task && r.task == u.task && r.entry_id == u.entry;
    const bool ok = confirmed || (to_string(r.kind) == u.outcome && r.entry_id == u.entry && r.task == u.task);
    if (r.kind == HriReply::Kind::confirm_task) (void)jinny.hri.handle(confirmed ? "yes" : "no");
    for (const auto& started : jinny.started) {
      if (started != u.task) ++f.wrong_tasks;
    }
    if (confirmed) ++f.asked_first;
    auto& [right, of] = f.per_kind[kind_of(u)];
    ++of;
    if (ok) {
      ++right;
    } else {
      std::ostringstream miss;
      miss << "  [" << kind_of(u) << "] \"" << u.text << "\" heard \"" << heard.words << "\" (" << heard.confidence
           << "): " << to_string(r.kind) << " " << r.entry_id << " " << r.task << "\n";
      f.misses += miss.str();
    }
  }
  return f;
}

std::string row(const std::string& set, const Condition& c, const Figures& f) {
  std::ostringstream out;
  out << std::fixed << std::setprecision(1) << "| " << set << " | " << c.name() << " | " << f.wer() * 100.0 << " % | "
      << f.right() << "/" << f.total() << " = " << f.accuracy() * 100.0 << " %";
  for (const auto& k : kKinds) {
    const auto it = f.per_kind.find(k);
    out << " | "
        << (it == f.per_kind.end() ? std::string("-")
                                   : std::to_string(it->second.first) + "/" + std::to_string(it->second.second));
  }
  out << " | " << f.wrong_tasks << " |";
  return out.str();
}

// The share of the general English model in the recognizer's language model (docs/hri.md "Speech
// beyond the base's words"); chosen on the development part.
constexpr double kGeneralWeight = 0.3;

}  // namespace

TEST_CASE("spoken visitors: a subset heard through the interpolated model, clean and in room noise", "[voice]") {
  if (!voice_available()) {
    WARN("built without espeak-ng and pocketsphinx (TRIPODAL_VOICE=OFF): nothing to test");
    return;
  }
  testing::SpokenJinny jinny;
  const auto recognizer = jinny.recognizer(kGeneralWeight);
  // Every ninth utterance of both parts: 58 of 513 since the third development batch (50 of 441 before).
  std::vector<Utterance> subset = load_set("visitors_dev.yaml", 9);
  for (auto& u : load_set("visitors_heldout.yaml", 9)) subset.push_back(std::move(u));
  REQUIRE(subset.size() >= 45);
  const Figures clean = speak(subset, {}, *recognizer, std::nullopt);
  std::cout << row("visitors, every 9th", {}, clean) << "\n" << clean.misses;
  CHECK(clean.wrong_tasks == 0);
  CHECK(clean.accuracy() >= 0.55);  // measured 36/58 = 62.1 %, WER 18.4 % (issue 37, third round; 31/50, 17.3 % before)
  CHECK(clean.wer() <= 0.25);
  const std::optional<AudioClip> noise = room_noise(20.0);
  if (!noise) {
    WARN("sox is not installed: the room-noise part is skipped (scripts/install-deps.sh installs it)");
    return;
  }
  const Condition noisy{"en-us+klatt", 170, 10.0};
  const Figures in_noise = speak(subset, noisy, *recognizer, noise);
  std::cout << row("visitors, every 9th", noisy, in_noise) << "\n" << in_noise.misses;
  CHECK(in_noise.wrong_tasks == 0);
  CHECK(in_noise.accuracy() >= 0.35);  // measured 23/58 = 39.7 %, WER 33.7 % (24/50 = 48 %, WER 32.4 % before)
}

TEST_CASE("spoken visitors: the whole grid of voices, speeds and noise (a long evaluation)", "[.spoken-eval]") {
  if (!voice_available()) return;
  // TRIPODAL_SPOKEN_EVAL_WEIGHT overrides the general model's share, TRIPODAL_SPOKEN_EVAL_STRIDE
  // takes every n-th utterance (1: all).
  const char* weight_env = std::getenv("TRIPODAL_SPOKEN_EVAL_WEIGHT");  // NOLINT(concurrency-mt-unsafe)
  const char* stride_env = std::getenv("TRIPODAL_SPOKEN_EVAL_STRIDE");  // NOLINT(concurrency-mt-unsafe)
  const char* grid_env = std::getenv("TRIPODAL_SPOKEN_EVAL_GRID");      // NOLINT(concurrency-mt-unsafe)
  const double weight = weight_env != nullptr ? std::stod(weight_env) : kGeneralWeight;
  const std::size_t stride = stride_env != nullptr ? std::stoul(stride_env) : 1;
  const std::string grid = grid_env != nullptr ? grid_env : "all";
  // TRIPODAL_SPOKEN_EVAL_MIN_CONFIDENCE: HriOptions::min_recognition_confidence; TRIPODAL_SPOKEN_EVAL_SETS:
  // "dev" for the development part alone.
  HriOptions options;
  if (const char* c = std::getenv("TRIPODAL_SPOKEN_EVAL_MIN_CONFIDENCE"))
    options.min_recognition_confidence = std::stod(c);              // NOLINT(concurrency-mt-unsafe)
  const char* sets_env = std::getenv("TRIPODAL_SPOKEN_EVAL_SETS");  // NOLINT(concurrency-mt-unsafe)
  std::vector<std::string> files = {"visitors_dev.yaml", "visitors_heldout.yaml"};
  if (sets_env != nullptr && std::string(sets_env) == "dev") files.pop_back();
  testing::SpokenJinny jinny;
  const auto recognizer = jinny.recognizer(weight);
  const std::optional<AudioClip> noise = room_noise(60.0);
  std::vector<Condition> conditions = {{}};
  if (grid == "all" || grid == "voices") {
    for (const Condition& c : std::vector<Condition>{{"en-us+klatt", 130, {}},
                                                     {"en-us+klatt", 210, {}},
                                                     {"en-us", 160, {}},
                                                     {"en-us+m3", 170, {}},
                                                     {"en-us+f3", 170, {}}}) {
      conditions.push_back(c);
    }
  }
  if ((grid == "all" || grid == "noise") && noise) {
    for (const double snr : {20.0, 10.0, 5.0}) conditions.push_back({"en-us+klatt", 170, snr});
  }
  std::cout << "general model weight " << weight << ", min_recognition_confidence " << options.min_recognition_confidence
            << ", every " << stride << " utterance(s)\n"
            << "| set | voice, speed, noise | WER | right | answer | command | refusal | out of domain | wrong tasks |\n";
  for (const auto& c : conditions) {
    for (const std::string& file : files) {
      const Figures f = speak(load_set(file, stride), c, *recognizer, noise, options);
      std::cout << row(file, c, f) << "\n" << std::flush;
      if (std::getenv("TRIPODAL_SPOKEN_EVAL_MISSES") != nullptr) std::cout << f.misses;  // NOLINT(concurrency-mt-unsafe)
      CHECK(f.wrong_tasks == 0);
    }
  }
}

TEST_CASE("spoken bad input: another language and a stream at the wrong rate are never a task", "[voice]") {
  if (!voice_available()) {
    WARN("built without espeak-ng and pocketsphinx (TRIPODAL_VOICE=OFF): nothing to test");
    return;
  }
  const auto recognizer = testing::SpokenJinny().recognizer(kGeneralWeight);
  auto nothing_started = [&recognizer](const AudioClip& audio, const std::string& what) {
    testing::SpokenJinny jinny;
    const SpeechRecognizer::Result heard = recognizer->recognize(audio);
    const HriReply r = jinny.hri.handle_heard(heard);
    INFO(what << ": heard \"" << heard.words << "\" (" << heard.confidence << "): " << to_string(r.kind) << " " << r.text);
    CHECK(jinny.started.empty());
    CHECK(r.kind != HriReply::Kind::task_started);
    // A question asked about a task is dropped by the visitor's no, and nothing starts.
    if (r.kind == HriReply::Kind::confirm_task) {
      (void)jinny.hri.handle_heard({"no", 0.9, {}});
      CHECK(jinny.started.empty());
    }
  };
  // German, French and Spanish, each asking to be guided to node one or where the restroom is.
  const std::vector<std::pair<std::string, std::string>> foreign = {{"de", "Bitte führen Sie mich zum Knoten eins."},
                                                                    {"de", "Wo ist die Toilette?"},
                                                                    {"fr", "Conduisez-moi au noeud un, s'il vous plaît."},
                                                                    {"es", "¿Dónde está el baño, por favor?"}};
  for (const auto& [voice, text] : foreign)
    nothing_started(resample(make_espeak_synthesizer({voice, 160})->synthesize(text), 16000), voice + ": " + text);
  // A 16-bit stream at the wrong rate: 22,050 Hz speech declared as 16 kHz (slow, a fifth lower)
  // and as 44.1 kHz (twice as fast, an octave higher); the recognizer resamples what it is told.
  const auto visitor = testing::SpokenJinny::visitor();
  for (const std::string text : {"what time is it", "thank you jinny", "hello there robot"}) {
    AudioClip slow = visitor->synthesize(text);
    AudioClip fast = slow;
    slow.sample_rate_hz = 16000;
    fast.sample_rate_hz = 44100;
    nothing_started(slow, text + " at the wrong rate (slow)");
    nothing_started(fast, text + " at the wrong rate (fast)");
  }
}

TEST_CASE("the general model's share is refused outside [0, 1], by name", "[voice]") {
  if (!voice_available()) return;
  PocketsphinxOptions o;
  o.language_model = arpa_bigram_model({"guide me to node 1"});
  for (const double w : {-0.1, 1.5}) {
    o.general_model_weight = w;
    CHECK_THROWS_WITH(make_pocketsphinx_recognizer(o),
                      Catch::Contains("general_model_weight is") && Catch::Contains("expected a share in [0, 1]"));
  }
}
