// What a robot's HRI offers beyond its own microphones (hri area): the touch screen's questions and
// the RKMS's web administration reach it through HriService. The monitor finds it among the
// robot's modules (a CModule that also derives from HriService), so the knowledge file is named
// once, in the robot profile. StoreBackedHri is the ready implementation: an HriModule over a
// KnowledgeStore, indexed anew as soon as the store changes.
#pragma once

#include <cstdint>
#include <memory>
#include <mutex>
#include <string_view>

#include "tripodal/hri/hri_module.hpp"
#include "tripodal/hri/knowledge_store.hpp"
#include "tripodal/hri/speech.hpp"

namespace tripodal {

class HriService {
 public:
  virtual ~HriService() = default;
  HriService() = default;
  HriService(const HriService&) = delete;
  HriService& operator=(const HriService&) = delete;

  /// The robot's knowledge (the web administration edits it).
  [[nodiscard]] virtual KnowledgeStore& knowledge_store() = 0;
  /// A typed input (the touch screen), handled as HriModule::handle does, against the knowledge
  /// as it is now. Call it from the thread that may start tasks (the robot's). Never throws.
  virtual HriReply ask(std::string_view utterance) = 0;
  /// The robot's voice; nullptr when it has none (a build without TRIPODAL_VOICE).
  [[nodiscard]] virtual SpeechSynthesizer* voice() noexcept = 0;
  /// What the HRI displays now: the robot's internal state (task, process, fault) and the last
  /// input with its answer (the monitor's HRI panel). Call it from the thread that calls ask().
  [[nodiscard]] virtual HriDisplay display() = 0;
};

/// An HriModule over a KnowledgeStore: ask() first compares the store's version with the one the
/// module was indexed at and indexes the store's base anew when it moved, so an edit is answered
/// from at once. Indexing costs about 1 ms for Jinny's 25 entries, 45 ms for 1,000 (docs/hri.md).
class StoreBackedHri final : public HriService {
 public:
  /// The store, tasks, task knowledge and providers must outlive this object. Throws ConfigError
  /// when an answer of the store's base names a provider `providers` lacks (as HriModule does).
  StoreBackedHri(KnowledgeStore& store, const TaskLibrary& tasks, const TaskKnowledge& knowledge,
                 const AnswerProviders& providers, TaskStarter start_task, HriOptions options = {},
                 std::unique_ptr<SpeechSynthesizer> voice = nullptr);

  [[nodiscard]] KnowledgeStore& knowledge_store() override { return store_; }
  HriReply ask(std::string_view utterance) override;
  [[nodiscard]] SpeechSynthesizer* voice() noexcept override { return voice_.get(); }
  [[nodiscard]] HriDisplay display() override;

  /// The module as of the store's current version (indexed anew if needed), for the inputs ask()
  /// does not cover (handle_heard). Not locked: call it from the thread that calls ask(). A base
  /// that cannot be indexed (a hand-edited file naming a provider the application lacks) keeps the
  /// previous module answering and is reported in index_error().
  HriModule& module();
  /// The version the current module was indexed at.
  [[nodiscard]] std::uint64_t indexed_version() const noexcept { return indexed_version_; }
  /// Why the latest version could not be indexed (empty when it was).
  [[nodiscard]] const std::string& index_error() const noexcept { return index_error_; }

 private:
  KnowledgeStore& store_;
  const TaskLibrary& tasks_;
  const TaskKnowledge& knowledge_;
  const AnswerProviders& providers_;
  TaskStarter start_task_;
  HriOptions options_;
  std::unique_ptr<SpeechSynthesizer> voice_;
  std::mutex mutex_;  // one input at a time: HriModule is not thread-safe
  std::unique_ptr<HriModule> module_;
  std::uint64_t indexed_version_ = 0;
  std::uint64_t tried_version_ = 0;
  std::string index_error_;
};

}  // namespace tripodal
