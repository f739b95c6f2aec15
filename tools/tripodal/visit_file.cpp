// The visit file (docs/guide.md): what a visitor types, says or presses, with the outcomes
// expected, loaded with every problem located.
#include <yaml-cpp/yaml.h>

#include "tripodal_common_internal/yaml_reader.hpp"
#include "visit.hpp"

namespace tripodal::app {

std::string_view to_string(VisitStep::Kind kind) noexcept {
  switch (kind) {
    case VisitStep::Kind::typed: return "typed";
    case VisitStep::Kind::spoken: return "spoken";
    case VisitStep::Kind::button: return "button";
  }
  return "?";
}

namespace {


void read_expect(yaml::Reader& r, const YAML::Node& n, VisitStep& step) {
  if (!r.expect_keys(n, {"outcome", "entry", "task", "task_end"}, "a step's expect")) return;
  if (const YAML::Node v = n["outcome"]) step.expect_outcome = r.choice(v, "expect.outcome", {"answered", "task_started", "task_refused", "not_understood", "refused_input", "confirm_task", "task_cancelled"}).value_or("");
  if (const YAML::Node v = n["entry"]) step.expect_entry = r.text(v, "expect.entry", true).value_or("");
  if (const YAML::Node v = n["task"]) step.expect_task = r.text(v, "expect.task", true).value_or("");
  if (const YAML::Node v = n["task_end"]) step.expect_task_end = r.choice(v, "expect.task_end", {"succeeded", "failed"}).value_or("");
}

Visit walk_visit(std::string_view text, const std::filesystem::path& file) {
  const YAML::Node root = yaml::parse(text, file.string());
  Diagnostics d;
  yaml::Reader r(file.string(), d);
  Visit v;
  v.file = file;
  if (!r.expect_keys(root, {"visit"}, "the visit file")) throw ConfigError(std::move(d));
  const YAML::Node visit = r.require(root, "visit", "the visit file", "visit: {name, steps: [...]}");
  if (visit && r.expect_keys(visit, {"name", "max_duration_s", "steps"}, "visit")) {
    if (const YAML::Node n = visit["name"]) v.name = r.text(n, "visit.name").value_or("");
    if (const YAML::Node n = visit["max_duration_s"]) v.max_duration_s = r.positive(n, "visit.max_duration_s").value_or(v.max_duration_s);
    const YAML::Node steps = r.require(visit, "steps", "visit", "a list of {type | say | press: ..., at_s, after_s, expect}");
    if (steps && r.expect_list(steps, "visit.steps")) {
      for (const auto& item : steps) {
        if (!r.expect_keys(item, {"type", "say", "press", "at_s", "after_s", "expect"}, "a visit step")) continue;
        VisitStep s;
        s.where = r.at(item);
        int given = 0;
        for (const auto& [key, kind] : {std::pair{"type", VisitStep::Kind::typed}, std::pair{"say", VisitStep::Kind::spoken},
                                        std::pair{"press", VisitStep::Kind::button}}) {
          if (const YAML::Node n = item[key]) {
            ++given;
            s.kind = kind;
            s.text = r.text(n, std::string("a step's ") + key, true).value_or("");
          }
        }
        if (given != 1) {
          r.error(item, "a visit step needs exactly one of type: \"REQUEST\", say: \"REQUEST\" or press: BUTTON, got " +
                            std::to_string(given));
        }
        if (const YAML::Node n = item["at_s"]) s.at_s = r.non_negative(n, "at_s");
        if (const YAML::Node n = item["after_s"]) s.after_s = r.non_negative(n, "after_s").value_or(s.after_s);
        if (const YAML::Node n = item["expect"]) read_expect(r, n, s);
        if (given == 1 && !s.text.empty()) v.steps.push_back(std::move(s));
      }
      if (steps.IsSequence() && steps.size() == 0) r.error(steps, "visit.steps is empty: a visit needs at least one step");
    }
  }
  if (d.has_errors()) throw ConfigError(std::move(d));
  return v;
}

}  // namespace

Visit parse_visit(std::string_view text, const std::filesystem::path& file) {
  return yaml::guarded(file.string(), [&] { return walk_visit(text, file); });
}

Visit load_visit(const std::filesystem::path& file) { return parse_visit(yaml::read_file(file), file); }

}  // namespace tripodal::app
