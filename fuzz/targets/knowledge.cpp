// The RKMS knowledge files of the HRI (configs/hri, docs/hri.md): a refused file has every error
// located; a file that loads writes (to_xml) and reloads to the same entries and version, and
// writes again to the same text; the HRI built on it answers its own question forms without
// throwing.
#include "../fuzz_target.hpp"
#include "tripodal/hri/hri_module.hpp"

namespace {

class NoKnowledge final : public tripodal::TaskKnowledge {
 public:
  ListResult list(std::string_view, std::string_view) const override { return {false, {}, "nothing known"}; }
};

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  KnowledgeBase kb;
  try {
    kb = KnowledgeBase::load_from_string(fuzz::as_text(bytes), "fuzz.xml");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.xml");
    return;
  }
  const std::string text = kb.to_xml(kb.version());
  KnowledgeBase again;
  try {
    again = KnowledgeBase::load_from_string(text, "again.xml");
  } catch (const ConfigError& e) {
    fuzz::require(false, "a loaded knowledge base does not reload from its own XML", e.what());
  }
  fuzz::require(again.entries() == kb.entries() && again.version() == kb.version(),
                "a knowledge base reloads to other entries or another version", text);
  fuzz::require(again.to_xml(again.version()) == text, "a knowledge base does not write to a fixed point", text);

  // Every provider an answer names is given, so the module accepts the base.
  AnswerProviders providers;
  for (const auto& e : kb.entries()) {
    for (const auto& p : scan_placeholders(e.answer).placeholders) providers.add(p.name, std::make_unique<FixedProvider>("x"));
  }
  static const TaskLibrary tasks = TaskLibrary::load_from_string(
      "tasks:\n  - name: guide\n    commands: [\"guide me to [the] node {node}\"]\n    plan:\n      - PrAutoMove: { goal: \"{node}\" }\n",
      "fuzz_tasks.yaml");
  const NoKnowledge knowledge;
  HriModule hri(kb, tasks, knowledge, providers, [](const Understanding&) { return std::string(); });
  for (const auto& e : kb.entries()) {
    for (const auto& q : e.questions) (void)hri.handle(q);
  }
}
