// Voice for the HRI module of the deliberate layer (paper, Table 3: voice recognition and the
// voice synthesizer), each behind a small interface a robot can replace: SpeechSynthesizer turns
// an answer into audio, SpeechRecognizer turns audio into the words the HRI classifies. The
// implementations here wrap espeak-ng and pocketsphinx when the build found them
// (TRIPODAL_VOICE, docs/hri.md "Voice"); audio is mono 16-bit PCM, read and written as WAV.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/hri/knowledge_base.hpp"

namespace tripodal {

/// Mono 16-bit PCM.
struct AudioClip {
  int sample_rate_hz = 16000;
  std::vector<std::int16_t> samples;
  [[nodiscard]] double duration_s() const noexcept {
    return sample_rate_hz > 0 ? static_cast<double>(samples.size()) / sample_rate_hz : 0.0;
  }
};

class SpeechSynthesizer {
 public:
  virtual ~SpeechSynthesizer() = default;
  /// The spoken `text`. Throws std::runtime_error when the engine fails.
  [[nodiscard]] virtual AudioClip synthesize(std::string_view text) = 0;
};

class SpeechRecognizer {
 public:
  virtual ~SpeechRecognizer() = default;
  /// The rate the recognizer expects; other audio is resampled by recognize().
  [[nodiscard]] virtual int sample_rate_hz() const noexcept = 0;
  struct Result {
    std::string words;  ///< lower case, separated by single spaces; empty for silence
    /// How sure the recognizer is of `words` (0..1): pocketsphinx's posterior probability of the
    /// best path. A closed language model hears any sound as some of its sentences; this is what
    /// tells a visitor's question about something else from one it knows.
    double confidence = 1.0;
    /// Other sentences the recognizer found almost as likely, best first, without `words`
    /// itself: each with the natural log of its path score relative to the best path (<= 0 in
    /// principle; the A* search of a lattice may rank them slightly out of order). The HRI acts on
    /// one of them when the best is a sentence it cannot understand (an n-best list read by the
    /// language understanding, as spoken dialogue systems do). Empty when the recognizer gives none.
    struct Alternative {
      std::string words;
      double log_score = 0.0;
    };
    std::vector<Alternative> alternatives;
  };
  /// What was heard in `audio`.
  [[nodiscard]] virtual Result recognize(const AudioClip& audio) = 0;
};

/// The bytes of a RIFF WAVE file (PCM, 16 bit, mono) holding `clip`: what write_wav writes, and
/// what the monitor sends a touch page to play.
[[nodiscard]] std::string wav_bytes(const AudioClip& clip);
/// Writes a RIFF WAVE file (PCM, 16 bit, mono). Throws std::runtime_error when it cannot.
void write_wav(const std::filesystem::path& file, const AudioClip& clip);
/// Reads a RIFF WAVE file of 16-bit PCM, mono (or the first channel of several). Throws
/// ConfigError at "FILE: at byte N" for what is not such a file.
[[nodiscard]] AudioClip read_wav(const std::filesystem::path& file);

/// `clip` at `rate_hz`, by windowed-sinc interpolation (band-limited: no aliasing of what lies
/// above the new Nyquist frequency into speech).
[[nodiscard]] AudioClip resample(const AudioClip& clip, int rate_hz);

/// Word error rate of `hypothesis` against `reference`: (substitutions + deletions +
/// insertions) / reference words, over the HRI's lower-case words. 0 for two empty texts.
[[nodiscard]] double word_error_rate(std::string_view reference, std::string_view hypothesis);
/// The word-level edit distance behind word_error_rate, and the reference's word count.
struct WordErrors {
  std::size_t errors = 0;
  std::size_t reference_words = 0;
};
[[nodiscard]] WordErrors word_errors(std::string_view reference, std::string_view hypothesis);

/// Text as a speaker would say it, for references and language models: "PSR-1" -> "p s r one",
/// "node 12" -> "node twelve" (numbers up to 999), punctuation dropped, lower case.
[[nodiscard]] std::string spoken_form(std::string_view text);
/// A recognizer's words as the HRI reads typed text: number words become digits ("node one" ->
/// "node 1") and spelled letters before a number join it ("p s r two" -> "psr2").
[[nodiscard]] std::string typed_form(std::string_view words);

/// An ARPA bigram language model of `sentences` (absolute discounting, D = 0.5, backing off to
/// unigrams), over their spoken_form words; words for which `known` returns false are left out.
/// For pocketsphinx: a small model of what visitors say to this robot recognises it far better
/// than the general English one.
[[nodiscard]] std::string arpa_bigram_model(const std::vector<std::string>& sentences,
                                            const std::function<bool(std::string_view)>& known = {});

/// What visitors may say to a robot, for arpa_bigram_model: the base's question forms and keyword
/// phrases, the sentences of its answers that start no task and have no placeholder (what a visitor
/// asks about next uses the answer's words: "information desk", "cafeteria"), and every command form with its optional words left
/// in and out and each {slot} replaced by each of `slot_values` (slots without values are left out of the corpus).
[[nodiscard]] std::vector<std::string> speech_corpus(const KnowledgeBase& base, const std::vector<std::string>& command_forms,
                                                     const std::map<std::string, std::vector<std::string>>& slot_values);

/// espeak-ng's phoneme mnemonics of a word (US English: "dZ'Ini" for "jinny") as the CMU
/// dictionary's ARPAbet phones ("JH IH N IY"); stress and syllable marks are dropped, flaps and
/// glottal stops become T, r-coloured vowels their vowel and R. Nullopt for a mnemonic without
/// a counterpart, or no phone at all.
[[nodiscard]] std::optional<std::string> arpabet_from_espeak(std::string_view mnemonics);

/// How espeak-ng's US English rules pronounce `word`, in ARPAbet (arpabet_from_espeak); nullopt
/// when the build has no espeak-ng or the word has no pronunciation in those phones.
[[nodiscard]] std::optional<std::string> espeak_pronunciation(std::string_view word);

/// True when this build has espeak-ng and pocketsphinx (CMake option TRIPODAL_VOICE).
[[nodiscard]] bool voice_available() noexcept;

struct EspeakOptions {
  std::string voice = "en-us";
  int words_per_minute = 160;
};
/// espeak-ng, synthesising in the calling thread (its engine is one per process: calls from
/// several synthesizers are serialised). Throws std::runtime_error when the build has no
/// espeak-ng or its data cannot be found.
[[nodiscard]] std::unique_ptr<SpeechSynthesizer> make_espeak_synthesizer(const EspeakOptions& options = {});

struct PocketsphinxOptions {
  /// The acoustic model and dictionary (Debian pocketsphinx-en-us).
  std::filesystem::path model_dir = "/usr/share/pocketsphinx/model/en-us";
  /// An ARPA language model text (arpa_bigram_model); empty: the general en-us.lm.bin.
  std::string language_model;
  /// The share (0..1) of the general English model (`model_dir`'s en-us.lm.bin, a trigram of some
  /// 70,000 words) linearly interpolated with `language_model`: 0 decodes with the domain model
  /// alone, which hears every sound as one of its sentences; above 0 a question about something
  /// else is heard as the words it has. Ignored without a `language_model`. Throws
  /// std::invalid_argument outside [0, 1].
  double general_model_weight = 0.0;
  /// Further decoder options, name and value ("-lw", "10"), after the defaults.
  std::vector<std::pair<std::string, std::string>> arguments;
  /// Words the dictionary lacks and their pronunciations in its phones ("jinny" -> "JH IH N IY"),
  /// added to it: a robot's name, its exhibits', its architecture's.
  std::map<std::string, std::string> extra_pronunciations;
};
/// pocketsphinx at 16 kHz. Throws std::runtime_error when the build has no pocketsphinx or the
/// model cannot be loaded.
[[nodiscard]] std::unique_ptr<SpeechRecognizer> make_pocketsphinx_recognizer(const PocketsphinxOptions& options = {});

/// A recognizer's options for what visitors may say (`corpus`, e.g. speech_corpus): the bigram
/// model of it over the dictionary's words and the words the dictionary lacks that espeak-ng can
/// pronounce ("jinny", "tripodal"), which are added to the dictionary; other words are left out.
/// Reads `base.model_dir`'s dictionary; throws std::runtime_error when it cannot.
[[nodiscard]] PocketsphinxOptions recognizer_options(const std::vector<std::string>& corpus, PocketsphinxOptions base = {});

/// The words of the pocketsphinx dictionary in `model_dir` (cmudict-en-us.dict), for
/// arpa_bigram_model's `known`.
[[nodiscard]] std::vector<std::string> pocketsphinx_dictionary_words(const std::filesystem::path& model_dir);

}  // namespace tripodal
