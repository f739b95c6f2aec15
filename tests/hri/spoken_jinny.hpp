// Test fixture of the voice tests: Jinny's HRI over the shipped knowledge and guide tasks in the
// exhibit hall (nodes 0 and 1), fixed local providers, a planner double that records the tasks it
// was asked to start, and a recognizer whose model is what Jinny knows (not any test set).
#pragma once

#include <chrono>
#include <memory>
#include <string>
#include <vector>

#include "tripodal/hri/hri_module.hpp"
#include "tripodal/hri/speech.hpp"

namespace tripodal::testing {

class ExhibitHallNodes final : public TaskKnowledge {
 public:
  ListResult list(std::string_view, std::string_view a) const override {
    if (a == "0" || a == "1") return {true, {"node" + std::string(a)}, {}};
    return {false, {}, "unknown node '" + std::string(a) + "' (known: 0, 1)"};
  }
};

struct SpokenJinny {
  KnowledgeBase base = KnowledgeBase::load(TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml");
  TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  ExhibitHallNodes hall;
  SimClock clock;
  AnswerProviders providers = make_providers(clock);
  std::vector<std::string> started;  // the tasks the HRI asked the planner to start
  HriModule hri;

  SpokenJinny() : SpokenJinny(HriOptions{}) {}
  explicit SpokenJinny(HriOptions options)
      : hri{base,
            tasks,
            hall,
            providers,
            [this](const Understanding& u) {
              started.push_back(u.task);
              return std::string();
            },
            std::move(options)} {}

  /// `general_model_weight`: the share of the general English model interpolated with the domain
  /// model (PocketsphinxOptions); 0, the domain model alone.
  [[nodiscard]] std::unique_ptr<SpeechRecognizer> recognizer(double general_model_weight = 0.0) const {
    PocketsphinxOptions o = recognizer_options(speech_corpus(base, tasks.command_forms(), {{"node", {"0", "1"}}}));
    o.general_model_weight = general_model_weight;
    return make_pocketsphinx_recognizer(o);
  }
  // The visitor's voice: of five espeak-ng variants at two rates, tried on every third utterance
  // of utterances.yaml, pocketsphinx's US English model hears klatt at 170 words a minute best
  // (WER 18 % there; the default en-us voice 39 %): synthetic speech is far from its training data.
  [[nodiscard]] static std::unique_ptr<SpeechSynthesizer> visitor() { return make_espeak_synthesizer({"en-us+klatt", 170}); }

 private:
  static AnswerProviders make_providers(const SimClock& clock) {
    AnswerProviders p;
    p.add("time", std::make_unique<ClockTimeProvider>(clock, std::chrono::hours(14)));
    p.add("battery", std::make_unique<BatteryProvider>([] { return 0.8; }));
    p.add("weather", std::make_unique<FixedProvider>("sunny"));
    return p;
  }
};

}  // namespace tripodal::testing
