// Answer latency of the HRI (issue 19): one typed utterance through HriModule::handle (the
// planner's matching, typo correction, Xapian BM25 ranking, the answer with its providers) on
// Jinny's base grown to 1,000 entries with generated ones. Target: < 10 ms median. Also the time
// to index such a base (done once, when the module starts or the base changes).
//
//   build/rel/bench/hri/tripodal_hri_bench --benchmark_repetitions=10 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "tripodal/hri/hri_module.hpp"
#include "tripodal/hri/listener.hpp"
#include "tripodal/hri/speech.hpp"

namespace {

using namespace tripodal;
using namespace std::chrono_literals;

// Pronounceable made-up words (seeded): a generated base shares no vocabulary with English, so
// the ranking really searches it rather than matching a few common words.
std::vector<std::string> vocabulary(std::size_t n, std::mt19937& rng) {
  static const char* const kOnsets[] = {"b", "k", "d", "f", "g", "l", "m", "n", "p", "r", "s", "t", "v", "z", "br", "st", "kr"};
  static const char* const kVowels[] = {"a", "e", "i", "o", "u", "ai", "ou"};
  std::vector<std::string> out;
  std::uniform_int_distribution<int> syllables(2, 4);
  std::uniform_int_distribution<std::size_t> onset(0, std::size(kOnsets) - 1);
  std::uniform_int_distribution<std::size_t> vowel(0, std::size(kVowels) - 1);
  while (out.size() < n) {
    std::string w;
    for (int s = syllables(rng); s > 0; --s) w += std::string(kOnsets[onset(rng)]) + kVowels[vowel(rng)];
    out.push_back(w);
  }
  return out;
}

KnowledgeBase generated_base(std::size_t entries) {
  KnowledgeBase base = KnowledgeBase::load(TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml");
  std::mt19937 rng(19);
  const std::vector<std::string> words = vocabulary(4000, rng);
  std::uniform_int_distribution<std::size_t> pick(0, words.size() - 1);
  for (std::size_t i = base.entries().size(); i < entries; ++i) {
    KnowledgeEntry e;
    e.id = "generated" + std::to_string(i);
    e.topic = "the " + words[pick(rng)] + " " + words[pick(rng)];
    for (int k = 0; k < 5; ++k) e.keywords.push_back(words[pick(rng)]);
    e.questions.push_back("What is the " + words[pick(rng)] + " of the " + words[pick(rng)] + "?");
    e.questions.push_back("Where can I see the " + words[pick(rng)] + " " + words[pick(rng)] + "?");
    e.questions.push_back("Tell me about " + e.keywords[0] + " and " + words[pick(rng)] + ".");
    e.answer = "The " + e.keywords[0] + " is shown at stand " + std::to_string(i) + "; it is {time} now.";
    base.put(std::move(e));
  }
  return base;
}

class Hall final : public TaskKnowledge {
 public:
  ListResult list(std::string_view, std::string_view argument) const override {
    return {true, {"node" + std::string(argument)}, {}};
  }
};

void BM_HriAnswer(benchmark::State& state) {
  const KnowledgeBase base = generated_base(static_cast<std::size_t>(state.range(0)));
  const TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  const Hall hall;
  const SimClock clock;
  AnswerProviders providers;
  providers.add("time", std::make_unique<ClockTimeProvider>(clock, 10h));
  providers.add("battery", std::make_unique<BatteryProvider>([] { return 0.8; }));
  providers.add("weather", std::make_unique<FixedProvider>("sunny"));
  HriModule hri(base, tasks, hall, providers, [](const Understanding&) { return std::string(); });
  // A mix as visitors type it: questions of the base, generated entries' keywords, typos,
  // commands, and something the base does not know.
  std::vector<std::string> utterances = {"Introduce yourself.", "How is the wether today?", "guide me to node 1",
                                         "what time is it", "Where is the restroom?", "what is the capital of France",
                                         "show me the cleaning robot", "how much batery do you have"};
  for (std::size_t i = 30; i < base.entries().size(); i += 97) {
    utterances.push_back("tell me about " + base.entries()[i].keywords[1] + " " + base.entries()[i].keywords[2]);
  }
  std::size_t next = 0;
  std::size_t answered = 0;
  for (auto _ : state) {
    const HriReply r = hri.handle(utterances[next]);
    answered += r.kind == HriReply::Kind::answered ? 1 : 0;
    benchmark::DoNotOptimize(r.text.data());
    next = (next + 1) % utterances.size();
  }
  state.counters["entries"] = static_cast<double>(base.entries().size());
  state.counters["answered_share"] = static_cast<double>(answered) / static_cast<double>(state.iterations());
}
// Arg 25: Jinny's own base (nothing generated), as the exhibit hall runs it.
BENCHMARK(BM_HriAnswer)->Arg(1000)->Arg(100)->Arg(25)->Unit(benchmark::kMicrosecond);

// A spoken answer (issue 37): one synthesised utterance recognised by pocketsphinx over the domain
// model interpolated with the general English trigram (weight 0.3, as the spoken visitor tests) and
// handled by HriModule::handle_heard. The speech is synthesised once, before the timing; CPU time
// per utterance is what the robot's one core spends between the visitor's last word and the reply.
void BM_SpokenAnswer(benchmark::State& state) {
  if (!voice_available()) {
    state.SkipWithError("built without espeak-ng and pocketsphinx");
    return;
  }
  const KnowledgeBase base = KnowledgeBase::load(TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml");
  const TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  const Hall hall;
  const SimClock clock;
  AnswerProviders providers;
  providers.add("time", std::make_unique<ClockTimeProvider>(clock, 10h));
  providers.add("battery", std::make_unique<BatteryProvider>([] { return 0.8; }));
  providers.add("weather", std::make_unique<FixedProvider>("sunny"));
  HriModule hri(base, tasks, hall, providers, [](const Understanding&) { return std::string(); });
  PocketsphinxOptions options = recognizer_options(speech_corpus(base, tasks.command_forms(), {{"node", {"0", "1"}}}));
  options.general_model_weight = static_cast<double>(state.range(0)) / 10.0;
  const auto recognizer = make_pocketsphinx_recognizer(options);
  const auto voice = make_espeak_synthesizer({"en-us+klatt", 170});
  std::vector<AudioClip> clips;
  double audio_s = 0.0;
  for (const char* text : {"what time is it", "who built you", "guide me to node one", "where can I get a coffee",
                           "how do you avoid bumping into people", "what is the capital of france"}) {
    clips.push_back(resample(voice->synthesize(text), 16000));
    audio_s += static_cast<double>(clips.back().samples.size()) / 16000.0;
  }
  std::size_t next = 0;
  for (auto _ : state) {
    const SpeechRecognizer::Result heard = recognizer->recognize(clips[next]);
    const HriReply r = hri.handle_heard(heard);
    benchmark::DoNotOptimize(r.text.data());
    next = (next + 1) % clips.size();
  }
  state.counters["audio_s_per_utterance"] = audio_s / static_cast<double>(clips.size());
}
BENCHMARK(BM_SpokenAnswer)->Arg(3)->Arg(0)->Unit(benchmark::kMillisecond)->MeasureProcessCPUTime();

void BM_KnowledgeIndexBuild(benchmark::State& state) {
  const KnowledgeBase base = generated_base(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    KnowledgeIndex index(base);
    benchmark::DoNotOptimize(&index);
  }
}
BENCHMARK(BM_KnowledgeIndexBuild)->Arg(1000)->Unit(benchmark::kMillisecond);

// The listener's segmentation of a microphone stream, fed 20 ms at a time: 60 s of 16 kHz audio,
// room noise with a two-second utterance (a voiced buzz) every five seconds. The counter says how
// many times faster than real time it runs (the recognizer's own cost is apart).
void BM_UtteranceSegmenter(benchmark::State& state) {
  constexpr int kRate = 16000;
  std::vector<std::int16_t> stream;
  std::mt19937 noise(3);
  std::uniform_int_distribution<int> room(-30, 30);
  for (int i = 0; i < 60 * kRate; ++i) {
    const double t = static_cast<double>(i) / kRate;
    const bool speaking = std::fmod(t, 5.0) >= 1.0 && std::fmod(t, 5.0) < 3.0;
    const double voice = speaking ? 6000.0 * std::sin(2.0 * std::numbers::pi * 150.0 * t) : 0.0;
    stream.push_back(static_cast<std::int16_t>(voice + room(noise)));
  }
  std::size_t found = 0;
  for (auto _ : state) {
    UtteranceSegmenter segmenter(kRate);
    found = 0;
    for (std::size_t at = 0; at < stream.size(); at += 320) {
      found += segmenter.feed(std::span<const std::int16_t>(stream).subspan(at, std::min<std::size_t>(320, stream.size() - at))).size();
    }
    found += segmenter.finish().size();
  }
  state.counters["utterances"] = static_cast<double>(found);
  state.counters["x_real_time"] = benchmark::Counter(60.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_UtteranceSegmenter)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
