#include "tripodal/planner/task_library.hpp"

#include <catch2/catch.hpp>
#include <map>

using namespace tripodal;

namespace {

// The workspace of the paper's experiment: room 3211 split into four sections.
class Workspace final : public TaskKnowledge {
 public:
  ListResult list(std::string_view function, std::string_view argument) const override {
    if (function != "sections") return {false, {}, "no list named '" + std::string(function) + "'"};
    if (argument == "3211") return {true, {"A", "B", "C", "D"}, {}};
    return {false, {}, "unknown room '" + std::string(argument) + "' (known: 3211)"};
  }
};

TaskLibrary shipped() { return TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/service_tasks.yaml"); }

}  // namespace

TEST_CASE("clean the room 3211 alternates PrAutoMove and PrCleaning over the four sections") {
  const auto u = shipped().understand("Clean the room 3211.", Workspace{});
  REQUIRE(u.understood);
  CHECK(u.task == "clean");
  CHECK(u.slots.at("room") == "3211");
  CHECK(to_string(u.plan) ==
        "PrAutoMove(goal=A.entry) -> PrCleaning(section=A) -> PrAutoMove(goal=B.entry) -> PrCleaning(section=B) -> "
        "PrAutoMove(goal=C.entry) -> PrCleaning(section=C) -> PrAutoMove(goal=D.entry) -> PrCleaning(section=D)");
}

TEST_CASE("carry, patrol and guide commands bind multi-word and list slots") {
  const auto lib = shipped();
  const Workspace ws;
  const auto carry = lib.understand("carry the document box from room 2111 to 2133", ws);
  REQUIRE(carry.understood);
  CHECK(carry.slots.at("object") == "document box");
  CHECK(to_string(carry.plan) ==
        "PrAutoMove(goal=2111) -> PrLoad(object=document box) -> PrAutoMove(goal=2133) -> PrUnload(object=document box)");

  const auto patrol = lib.understand("patrol rooms 2111, 2133 and 3211", ws);
  REQUIRE(patrol.understood);
  CHECK(to_string(patrol.plan) == "PrAutoMove(goal=2111) -> PrAutoMove(goal=2133) -> PrAutoMove(goal=3211)");

  const auto guide = lib.understand("guide me to room 2111", ws);
  REQUIRE(guide.understood);
  REQUIRE(guide.plan.stages.size() == 1);
  CHECK(guide.plan.stages[0].parallel());
  CHECK(to_string(guide.plan) == "[PrAutoMove(goal=2111) || PrExplain(topic=way to 2111)]");
}

TEST_CASE("a command that is not understood says how far it got and what is possible") {
  const auto lib = shipped();
  const auto u = lib.understand("clean the kitchen now", Workspace{});
  CHECK_FALSE(u.understood);
  CHECK(u.plan.stages.empty());
  CHECK_THAT(u.explanation, Catch::Contains("not understood: \"clean the kitchen now\""));
  CHECK_THAT(u.explanation, Catch::Contains("understood \"clean the\""));
  CHECK_THAT(u.explanation, Catch::Contains("then \"kitchen\" where \"room\" was expected"));
  CHECK_THAT(u.explanation, Catch::Contains("Possible commands:\n  clean [the] room {room}"));
  CHECK_THAT(u.explanation, Catch::Contains("guide me to [room] {room}"));

  const auto dance = lib.understand("dance for me", Workspace{});
  CHECK_FALSE(dance.understood);
  CHECK_THAT(dance.explanation, Catch::Contains("nothing matched at the start"));
  CHECK_FALSE(lib.understand("", Workspace{}).understood);
}

TEST_CASE("a command understood but not plannable is refused with the knowledge's reason") {
  const auto u = shipped().understand("clean the room 9999", Workspace{});
  CHECK_FALSE(u.understood);
  CHECK(u.task == "clean");
  CHECK_THAT(u.explanation, Catch::Contains("cannot plan it: unknown room '9999' (known: 3211)"));
}

TEST_CASE("malformed task templates are refused with every error located") {
  const char* yaml = R"(tasks:
  - name: clean
    commands: ["clean {room"]
    plan:
      - PrCleaning: { section: "{sector}" }
  - name: clean
    comands: []
    plan: []
  - name: fetch
    commands: ["fetch {thing}"]
    plan:
      - foreach: { var: x, in: "{thing}" }
)";
  try {
    (void)TaskLibrary::load_from_string(yaml, "tasks.yaml");
    FAIL("expected a ConfigError");
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Catch::Contains("tasks.yaml:3:16: error: bad word '{room'"));
    CHECK_THAT(what, Catch::Contains("tasks.yaml:5:32: error: '{sector}' is not captured"));
    CHECK_THAT(what, Catch::Contains("tasks.yaml:6:5: error: duplicate task name 'clean'"));
    CHECK_THAT(what, Catch::Contains("tasks.yaml:7:5: error: unknown key 'comands'"));
    CHECK_THAT(what, Catch::Contains("needs 'plan'"));
    CHECK_THAT(what, Catch::Contains("tasks.yaml:12:9: error: 'foreach' needs 'var', 'in' and 'do'"));
    CHECK(e.diagnostics().error_count() >= 6);
  }
}

TEST_CASE("plan steps and parameters whose keys are not text are located") {
  const char* yaml = R"(tasks:
  - name: clean
    commands: ["clean {room}"]
    plan:
      - {[PrCleaning]: {}}
      - PrAutoMove: {{to: x}: "{room}"}
)";
  try {
    (void)TaskLibrary::load_from_string(yaml, "tasks.yaml");
    FAIL("expected a ConfigError");
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Catch::Contains("tasks.yaml:5:10: error: a plan step (a process name, 'foreach' or 'parallel'): a key must be text, got a list"));
    CHECK_THAT(what, Catch::Contains("tasks.yaml:6:22: error: the parameters of 'PrAutoMove': a key must be text, got a map"));
  }
}

TEST_CASE("unknown process names are refused when a registry is given") {
  TaskLoadOptions options;
  options.is_known_process = [](std::string_view p) { return p == "PrAutoMove"; };
  CHECK_THROWS_WITH(TaskLibrary::load_from_string("tasks:\n  - name: a\n    commands: [go]\n    plan:\n      - PrAutoMov: {}\n",
                                                  "t.yaml", options),
                    Catch::Contains("t.yaml:5:9: error: unknown process 'PrAutoMov'"));
  CHECK_THROWS_WITH(TaskLibrary::load_from_string("tasks: [", "bad.yaml"), Catch::Contains("bad.yaml:1:"));
}
