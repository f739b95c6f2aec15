#include "tripodal/hri/hri_service.hpp"

#include <utility>

namespace tripodal {

StoreBackedHri::StoreBackedHri(KnowledgeStore& store, const TaskLibrary& tasks, const TaskKnowledge& knowledge,
                               const AnswerProviders& providers, TaskStarter start_task, HriOptions options,
                               std::unique_ptr<SpeechSynthesizer> voice)
    : store_(store),
      tasks_(tasks),
      knowledge_(knowledge),
      providers_(providers),
      start_task_(std::move(start_task)),
      options_(std::move(options)),
      voice_(std::move(voice)) {
  // An answer naming a provider the robot lacks would make the next index refuse the whole base:
  // the store refuses such an entry when it is edited, at its field.
  store_.set_validator([&providers](const KnowledgeEntry& e) {
    std::vector<KnowledgeFieldError> out;
    for (const AnswerPlaceholder& p : scan_placeholders(e.answer).placeholders) {
      if (providers.find(p.name) != nullptr) continue;
      std::string known;
      for (const auto& n : providers.names()) known += (known.empty() ? "{" : ", {") + n + "}";
      out.push_back({"answer", "the answer names {" + p.name + "}, which this robot does not provide (it has: " +
                                   (known.empty() ? std::string("none") : known) + ")"});
    }
    return out;
  });
  const KnowledgeBase base = store_.base();
  module_ = std::make_unique<HriModule>(base, tasks_, knowledge_, providers_, start_task_, options_);
  indexed_version_ = tried_version_ = base.version();
}

HriModule& StoreBackedHri::module() {
  const std::uint64_t now = store_.version();
  if (now != tried_version_) {
    tried_version_ = now;
    const KnowledgeBase base = store_.base();
    try {
      auto next = std::make_unique<HriModule>(base, tasks_, knowledge_, providers_, start_task_, options_);
      next->restore_display(module_->display());
      module_ = std::move(next);
      indexed_version_ = base.version();
      index_error_.clear();
    } catch (const std::exception& e) {
      // The previous module keeps answering. The validator above refuses such edits, so only a
      // file edited by hand and reloaded gets here.
      index_error_ = e.what();
    }
  }
  return *module_;
}

HriDisplay StoreBackedHri::display() {
  const std::lock_guard lock(mutex_);
  return module_->display();
}

HriReply StoreBackedHri::ask(std::string_view utterance) {
  const std::lock_guard lock(mutex_);
  return module().handle(utterance);
}

}  // namespace tripodal
