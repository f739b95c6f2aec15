// Test support (monitor tests): an HRI module for a robot profile, type "TestHri", that holds a
// KnowledgeStore on its `knowledge` parameter and answers through StoreBackedHri, so the monitor
// finds the robot's knowledge through the runtime (Robot::module<HriService>()) as it would the
// application's own HRI module. Tasks go nowhere: the PSR-2 the tests use runs no guide tasks.
#pragma once

#include <filesystem>
#include <memory>
#include <string>

#include "tripodal/hri/hri_service.hpp"
#include "tripodal/processes/module.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal::testing_hri {

class NoNodes final : public TaskKnowledge {
 public:
  ListResult list(std::string_view, std::string_view) const override { return {false, {}, "this test robot knows no nodes"}; }
};

class TestHri final : public CModule, public HriService {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = ManifestBuilder("TestHri", ModuleKind::hri, Layer::deliberate)
                                        .description("the RKMS knowledge and the HRI for the monitor's tests")
                                        .parameter(parameter::text("knowledge", std::nullopt, "the RKMS knowledge file"))
                                        .parameter(parameter::text("tasks", std::nullopt, "task templates the HRI understands"))
                                        .build();
    return m;
  }

  KnowledgeStore& knowledge_store() override { return hri_->knowledge_store(); }
  HriReply ask(std::string_view utterance) override {
    asked_ += 1;
    return hri_->ask(utterance);
  }
  SpeechSynthesizer* voice() noexcept override { return hri_->voice(); }
  HriDisplay display() override { return hri_->display(); }
  [[nodiscard]] int asked() const noexcept { return asked_; }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override {
    store_ = std::make_unique<KnowledgeStore>(params.string("knowledge"));
    tasks_ = std::make_unique<TaskLibrary>(TaskLibrary::load(params.string("tasks")));
    providers_.add("time", std::make_unique<FixedProvider>("14:05"));
    providers_.add("battery", std::make_unique<FixedProvider>("82 percent"));
    providers_.add("weather", std::make_unique<FixedProvider>("sunny, 27 degrees"));
    std::unique_ptr<SpeechSynthesizer> voice;
    if (voice_available()) voice = make_espeak_synthesizer();
    hri_ = std::make_unique<StoreBackedHri>(*store_, *tasks_, nodes_, providers_,
                                            [](const Understanding&) { return std::string("this test robot runs no guide tasks"); },
                                            HriOptions{}, std::move(voice));
  }

 private:
  std::unique_ptr<KnowledgeStore> store_;
  std::unique_ptr<TaskLibrary> tasks_;
  NoNodes nodes_;
  AnswerProviders providers_;
  std::unique_ptr<StoreBackedHri> hri_;
  int asked_ = 0;
};

/// The profile's `hri:` section with one TestHri on `knowledge` (Jinny's tasks).
inline void add_test_hri(RobotProfile& profile, const std::filesystem::path& knowledge, const std::filesystem::path& source_dir) {
  ModuleEntry e;
  e.kind = ModuleKind::hri;
  e.name = "hri";
  e.type = "TestHri";
  e.parameters["knowledge"] = knowledge.string();
  e.parameters["tasks"] = (source_dir / "configs/tasks/jinny_guide.yaml").string();
  e.where = SourceLocation{"test profile", 1, 1};
  profile.hri.push_back(std::move(e));
}

}  // namespace tripodal::testing_hri
