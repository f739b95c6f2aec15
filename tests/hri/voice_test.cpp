#include <yaml-cpp/yaml.h>
#include <unistd.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <numbers>

#include "tripodal/hri/hri_module.hpp"
#include "tripodal/hri/speech.hpp"

#include "spoken_jinny.hpp"

using namespace tripodal;

namespace {

namespace fs = std::filesystem;

AudioClip tone(double freq_hz, int rate_hz, double seconds, double amplitude = 10000.0) {
  AudioClip c;
  c.sample_rate_hz = rate_hz;
  const auto n = static_cast<std::size_t>(seconds * rate_hz);
  for (std::size_t i = 0; i < n; ++i) {
    c.samples.push_back(static_cast<std::int16_t>(amplitude * std::sin(2.0 * std::numbers::pi * freq_hz * static_cast<double>(i) / rate_hz)));
  }
  return c;
}

double rms(const AudioClip& c, std::size_t skip) {
  double sum = 0.0;
  std::size_t n = 0;
  for (std::size_t i = skip; i + skip < c.samples.size(); ++i, ++n) sum += static_cast<double>(c.samples[i]) * c.samples[i];
  return n == 0 ? 0.0 : std::sqrt(sum / static_cast<double>(n));
}

std::size_t sign_changes(const AudioClip& c) {
  std::size_t n = 0;
  for (std::size_t i = 1; i < c.samples.size(); ++i) n += (c.samples[i - 1] < 0) != (c.samples[i] < 0) ? 1 : 0;
  return n;
}

fs::path temp_file(const std::string& name) {
  return fs::temp_directory_path() / ("tripodal_voice_" + std::to_string(::getpid()) + "_" + name);
}

}  // namespace

TEST_CASE("word error rate counts substitutions, deletions and insertions against the reference") {
  CHECK(word_error_rate("guide me to node one", "guide me to node one") == 0.0);
  CHECK(word_error_rate("guide me to node one", "guide me to note one") == Approx(0.2));
  CHECK(word_error_rate("guide me to node one", "guide to node one please") == Approx(0.4));
  CHECK(word_errors("what time is it", "").errors == 4);
  CHECK(word_error_rate("", "") == 0.0);
  CHECK(word_error_rate("", "noise") == 1.0);
}

TEST_CASE("spoken and typed forms: numbers as words and back, spelled names joined") {
  CHECK(spoken_form("Tell me about PSR-1.") == "tell me about p s r one");
  CHECK(spoken_form("guide me to node 12, how's it?") == "guide me to node twelve how's it");
  CHECK(spoken_form("room 2111") == "room two one one one");
  CHECK(spoken_form("node 345") == "node three hundred forty five");
  CHECK(typed_form("guide me to node one") == "guide me to node 1");
  CHECK(typed_form("tell me about p s r two") == "tell me about psr2");
  CHECK(typed_form("node twenty one and a b") == "node 21 and a b");
}

TEST_CASE("resampling keeps a tone's frequency and level and removes what the new rate cannot hold") {
  const AudioClip in = tone(440.0, 22050, 1.0);
  const AudioClip out = resample(in, 16000);
  CHECK(out.sample_rate_hz == 16000);
  CHECK(out.samples.size() == 16000);
  // 440 Hz: 880 sign changes a second, either rate.
  CHECK(std::abs(static_cast<double>(sign_changes(out)) - 880.0) <= 2.0);
  CHECK(rms(out, 100) == Approx(rms(in, 100)).epsilon(0.02));
  // 10 kHz is above 16 kHz's Nyquist frequency: filtered out, not folded to 6 kHz.
  const AudioClip high = resample(tone(10000.0, 22050, 0.5), 16000);
  CHECK(rms(high, 100) < 0.02 * 10000.0 / std::sqrt(2.0));
}

TEST_CASE("WAV files write and read back, and a broken one is refused at its byte") {
  const AudioClip c = tone(300.0, 16000, 0.1);
  const fs::path file = temp_file("tone.wav");
  write_wav(file, c);
  CHECK(fs::file_size(file) == 44 + 2 * c.samples.size());
  const AudioClip back = read_wav(file);
  CHECK(back.sample_rate_hz == 16000);
  CHECK(back.samples == c.samples);
  {
    const char broken[] = "RIFF\x10\0\0\0WAVEdata\xff\xff\0\0";
    std::ofstream(file, std::ios::binary).write(broken, sizeof broken - 1);
  }
  CHECK_THROWS_WITH(read_wav(file), Catch::Contains(file.string() + ": error: at byte 12: chunk 'data' of 65535 bytes runs past the end of the file"));
  {
    std::ofstream(file, std::ios::binary) << "not audio";
  }
  CHECK_THROWS_WITH(read_wav(file), Catch::Contains("at byte 0: not a RIFF WAVE file"));
  fs::remove(file);
}

TEST_CASE("the bigram language model lists every word and bigram of its corpus, known words only") {
  const std::string arpa = arpa_bigram_model({"guide me to node 1", "guide me home", "xyzzy here"},
                                             [](std::string_view w) { return w != "xyzzy"; });
  // Words: <s> </s> guide me to node one home here = 9; bigrams: <s> guide, guide me, me to, to
  // node, node one, one </s>, me home, home </s>, <s> here, here </s> = 10.
  CHECK_THAT(arpa, Catch::StartsWith("\\data\\\nngram 1=9\nngram 2=10\n"));
  CHECK_THAT(arpa, Catch::Contains(" guide me\n"));
  CHECK_THAT(arpa, Catch::Contains(" node one\n"));
  CHECK_THAT(arpa, !Catch::Contains("xyzzy"));
  CHECK_THAT(arpa, Catch::EndsWith("\\end\\\n"));
}

TEST_CASE("the speech corpus expands optional words and slots of the command forms") {
  KnowledgeBase kb;
  kb.put({"time", "the time", {"clock"}, {"What time is it?"}, "It is {time}.", "", {}});
  const auto corpus = speech_corpus(kb, {"guide me to [the] node {node}", "patrol {rooms...}"}, {{"node", {"0", "1"}}});
  CHECK(corpus == std::vector<std::string>{"What time is it?", "clock", "guide me to node 0", "guide me to node 1",
                                           "guide me to the node 0", "guide me to the node 1",
                                           // polite requests, once per command form
                                           "please guide me to node 0", "could you guide me to node 0",
                                           "would you guide me to node 0", "guide me to node 0 please",
                                           // the answers to "did you ask me to ...?"
                                           "yes", "yeah", "yep", "sure", "ok", "okay", "correct", "right", "go ahead",
                                           "do it", "please do", "no", "nope", "cancel", "wrong", "stop", "don't", "do not",
                                           "yes please", "no thanks"});
}

// The answers' sentences were in the corpus for a while (issue 37, third round): the exhibit hall
// visit's spoken "Thank you" was then heard as "that two" (tripodal_run_cli:guide_visit_exhibit_hall).
TEST_CASE("the speech corpus holds what visitors say, not the robot's answers") {
  KnowledgeBase kb;
  kb.put({"exit", "the way out", {"exit"}, {"Where is the exit?"}, "The exit is behind you. Ask at the desk!", "", {}});
  const auto corpus = speech_corpus(kb, {}, {});
  const auto has = [&](const std::string& s) { return std::find(corpus.begin(), corpus.end(), s) != corpus.end(); };
  CHECK(has("Where is the exit?"));
  CHECK(has("exit"));
  CHECK_FALSE(
      std::any_of(corpus.begin(), corpus.end(), [](const std::string& s) { return s.find("behind you") != std::string::npos; }));
  CHECK_FALSE(has("Ask at the desk"));
}

TEST_CASE("espeak-ng's phoneme mnemonics become the dictionary's ARPAbet phones") {
  CHECK(arpabet_from_espeak("dZ'Ini") == "JH IH N IY");
  CHECK(arpabet_from_espeak("tr'aIp0d@L") == "T R AY P AA D AH L");
  CHECK(arpabet_from_espeak("T'aNks") == "TH AE NG K S");
  CHECK(arpabet_from_espeak("tS'3:tS") == "CH ER CH");
  CHECK(arpabet_from_espeak("b'V?n-") == "B AH T N");            // glottal stop, syllabic n
  CHECK(arpabet_from_espeak("j'i@3") == "Y IY R");               // r-coloured vowels: vowel and R
  CHECK(arpabet_from_espeak("'A@kI2t,EktS3") == "AA R K IH T EH K CH ER");
  CHECK(arpabet_from_espeak("d,Vb@Lj,u: s'i:") == "D AH B AH L Y UW S IY");  // "wc", spelled
  CHECK_FALSE(arpabet_from_espeak("k'a~").has_value());           // a mnemonic with no counterpart
  CHECK_FALSE(arpabet_from_espeak("'  ,").has_value());           // marks only
  CHECK_FALSE(arpabet_from_espeak("").has_value());
}

TEST_CASE("the recognizer's options pronounce the corpus words the dictionary lacks, with espeak-ng", "[voice]") {
  if (!voice_available()) {
    CHECK_FALSE(espeak_pronunciation("jinny").has_value());
    return;
  }
  CHECK(espeak_pronunciation("jinny") == "JH IH N IY");
  CHECK(espeak_pronunciation("tripodal") == "T R AY P AA D AH L");
  const PocketsphinxOptions o = recognizer_options({"Hello Jinny", "tell me about the tripodal architecture", "guide me to node 1"});
  // Dictionary words are not repeated; the robot's name and the architecture's are added.
  CHECK(o.extra_pronunciations == std::map<std::string, std::string>{{"jinny", "JH IH N IY"}, {"tripodal", "T R AY P AA D AH L"}});
  CHECK_THAT(o.language_model, Catch::Contains(" hello jinny\n"));
  CHECK_THAT(o.language_model, Catch::Contains(" the tripodal\n"));
  CHECK_THAT(o.language_model, Catch::Contains(" node one\n"));
  // The recognizer loads the extended dictionary (a word it lacks would make pocketsphinx drop
  // it from the model) and hears the robot's name.
  const auto recognizer = make_pocketsphinx_recognizer(o);
  const auto voice = make_espeak_synthesizer({"en-us+klatt", 170});
  CHECK_THAT(recognizer->recognize(resample(voice->synthesize("hello jinny"), 16000)).words, Catch::EndsWith("jinny"));
}

namespace {

struct RoundTrip {
  std::size_t total = 0;
  std::size_t right = 0;
  std::size_t word_errors = 0;
  std::size_t words = 0;
  std::size_t confirmed = 0;  // right, after the visitor confirmed the task asked about
  [[nodiscard]] double accuracy() const { return total == 0 ? 0.0 : static_cast<double>(right) / static_cast<double>(total); }
};

// Speaks each utterance of `file` (its `spoken` text, else `say`), recognises it, hands what was
// heard to the HRI and compares the reply with the expected outcome; prints the figures and misses.
RoundTrip spoken_round_trip(const std::string& file, SpeechSynthesizer& synthesizer, SpeechRecognizer& recognizer, HriModule& hri) {
  const YAML::Node doc = YAML::LoadFile(TRIPODAL_TEST_DATA_DIR "/hri/" + file);
  RoundTrip rt;
  std::string misses;
  for (const auto& u : doc["utterances"]) {
    const std::string text = u["spoken"] ? u["spoken"].as<std::string>() : u["say"].as<std::string>();
    const AudioClip audio = synthesizer.synthesize(text);
    REQUIRE(audio.duration_s() > 0.3);
    const SpeechRecognizer::Result result = recognizer.recognize(resample(audio, recognizer.sample_rate_hz()));
    const std::string& heard = result.words;
    const WordErrors e = word_errors(spoken_form(text), heard);
    rt.word_errors += e.errors;
    rt.words += e.reference_words;
    const HriReply r = hri.handle_heard(result);
    const std::string acted_on = hri.last_exchange() ? hri.last_exchange()->input : heard;
    const std::string expected = u["outcome"].as<std::string>();
    const std::string expected_task = u["task"] ? u["task"].as<std::string>() : std::string();
    // A task asked about before it starts (heard with little confidence) is understood: the
    // visitor's yes starts it. Counted right, and counted apart.
    const std::string expected_entry = u["entry"] ? u["entry"].as<std::string>() : std::string();
    const bool confirmed = (expected == "task_started" || (expected == "answered" && !expected_task.empty())) &&
                           r.kind == HriReply::Kind::confirm_task && r.task == expected_task && r.entry_id == expected_entry;
    const bool ok = confirmed || (to_string(r.kind) == expected && r.entry_id == expected_entry && r.task == expected_task);
    if (confirmed) ++rt.confirmed;
    if (r.kind == HriReply::Kind::confirm_task) {
      // The visitor answers the question: yes when the task is the one meant, no otherwise.
      (void)hri.handle(confirmed ? "yes" : "no");
    }
    ++rt.total;
    if (ok) {
      ++rt.right;
    } else {
      misses += "  \"" + text + "\" heard \"" + heard + "\" (" + std::to_string(result.confidence) + ")" +
                (acted_on != heard ? ", acted on \"" + acted_on + "\"" : std::string()) + ": " + std::string(to_string(r.kind)) + " " +
                r.entry_id + "\n";
    }
  }
  const double wer = rt.words == 0 ? 0.0 : static_cast<double>(rt.word_errors) / static_cast<double>(rt.words);
  std::cout << "HRI spoken round trip of " << file << " (espeak-ng -> 16 kHz -> pocketsphinx): " << rt.total
            << " utterances, word error rate " << wer * 100.0 << " % (" << rt.word_errors << "/" << rt.words
            << " words), answers right " << rt.right << "/" << rt.total << " = " << rt.accuracy() * 100.0 << " % ("
            << rt.confirmed << " of them a task asked about first)\n"
            << misses;
  return rt;
}

}  // namespace

TEST_CASE("spoken round trip: espeak-ng speaks the utterance set, pocketsphinx recognises it, the HRI answers",
          "[voice]") {
  if (!voice_available()) {
    WARN("built without espeak-ng and pocketsphinx (TRIPODAL_VOICE=OFF): nothing to test");
    return;
  }
  testing::SpokenJinny jinny;
  HriModule& hri = jinny.hri;
  const auto recognizer = jinny.recognizer();
  const auto synthesizer = testing::SpokenJinny::visitor();
  const RoundTrip main_set = spoken_round_trip("utterances.yaml", *synthesizer, *recognizer, hri);
  CHECK(main_set.total >= 60);
  // Measured 86.5 % (77/89, WER 20.9 %; two of them commands asked about first) on Debian 12's espeak-ng 1.51 and pocketsphinx
  // 5prealpha, in a process of its own (espeak-ng's state moves it by about two utterances:
  // docs/hri.md). The floors guard against regressions.
  CHECK(main_set.accuracy() >= 0.80);
  const RoundTrip dev_set = spoken_round_trip("utterances_dev.yaml", *synthesizer, *recognizer, hri);
  CHECK(dev_set.total >= 40);
  // The development set, whose misses guided the changes: 82.5 % (66/80, WER 23.5 %).
  CHECK(dev_set.accuracy() >= 0.75);
  // The held-out set (phrasings nothing was tuned on) measured 72.5 % (29/40, WER 28.3 %).
  const RoundTrip held_out = spoken_round_trip("utterances_heldout.yaml", *synthesizer, *recognizer, hri);
  CHECK(held_out.total >= 40);
  CHECK(held_out.accuracy() >= 0.60);

  // The answer itself, spoken and written as a WAV file a visitor's speaker would play.
  const fs::path wav = temp_file("answer.wav");
  write_wav(wav, synthesizer->synthesize(hri.handle("Introduce yourself.").text));
  const AudioClip answer = read_wav(wav);
  CHECK(answer.duration_s() > 3.0);
  CHECK_THAT(recognizer->recognize(answer).words, Catch::Contains("robot"));
  fs::remove(wav);
}
