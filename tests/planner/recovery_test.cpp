#include "tripodal/planner/recovery.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;

namespace {
RecoveryPolicy shipped() { return RecoveryPolicy::load(TRIPODAL_SOURCE_DIR "/configs/tasks/recovery.yaml"); }

Plan cleaning_plan() {
  Plan p;
  p.task = "clean";
  p.stages.push_back({{{"PrAutoMove", {{"goal", "A.entry", {}}}}}});
  p.stages.push_back({{{"PrCleaning", {{"section", "A", {}}}}}});
  p.stages.push_back({{{"PrAutoMove", {{"goal", "B.entry", {}}}}}});
  return p;
}
}  // namespace

TEST_CASE("a localization fault inserts global localization and retries the failed module") {
  const auto policy = shipped();
  const Plan plan = cleaning_plan();
  const auto d = policy.decide(plan.stages[1].steps[0], "Localization fault", 0);
  CHECK(d.action == RecoveryAction::retry);
  REQUIRE(d.rule != nullptr);
  CHECK(d.reason == "fault \"Localization fault\" of PrCleaning: insert PrGlobalLocalization, then retry (1/2)");
  const Plan rest = RecoveryPolicy::remaining_plan(plan, 1, d);
  CHECK(to_string(rest) == "PrGlobalLocalization() -> PrCleaning(section=A) -> PrAutoMove(goal=B.entry)");
}

TEST_CASE("the retry limit makes the task fail with a report") {
  const auto policy = shipped();
  const ProcessStep cleaning{"PrCleaning", {}};
  CHECK(policy.decide(cleaning, "localization fault", 1).action == RecoveryAction::retry);
  const auto d = policy.decide(cleaning, "localization fault", 2);
  CHECK(d.action == RecoveryAction::abort);
  CHECK_THAT(d.reason, Catch::Contains("retry limit reached") && Catch::Contains("max_retries 2"));
  CHECK(RecoveryPolicy::remaining_plan(cleaning_plan(), 1, d).stages.empty());
}

TEST_CASE("process-specific rules and faults without a rule") {
  const auto policy = shipped();
  CHECK(policy.decide({"PrAutoMove", {}}, "path blocked", 0).insert.at(0).process == "PrWait");
  const auto none = policy.decide({"PrCleaning", {}}, "path blocked", 0);
  CHECK(none.action == RecoveryAction::abort);
  CHECK(none.rule == nullptr);
  CHECK(none.reason == "no recovery rule for fault \"path blocked\" of PrCleaning");
}

TEST_CASE("skip goes on after the failed stage") {
  RecoveryDecision d;
  d.action = RecoveryAction::skip;
  CHECK(to_string(RecoveryPolicy::remaining_plan(cleaning_plan(), 1, d)) == "PrAutoMove(goal=B.entry)");
}

TEST_CASE("malformed recovery rules are located") {
  const char* yaml = "recovery:\n  - fault: x\n    then: restart\n    max_retries: -1\n  - insert: [ PrA ]\n    colour: red\n";
  try {
    (void)RecoveryPolicy::load_from_string(yaml, "r.yaml");
    FAIL("expected ConfigError");
  } catch (const ConfigError& e) {
    const std::string w = e.what();
    CHECK_THAT(w, Catch::Contains("r.yaml:3:11: error: 'then': expected one of retry, skip, abort; got 'restart'"));
    CHECK_THAT(w, Catch::Contains("r.yaml:4:18: error: 'max_retries': expected a whole number from 0 to 1000000, got '-1'"));
    CHECK_THAT(w, Catch::Contains("r.yaml:5:15: error: an inserted step must be a map"));
    CHECK_THAT(w, Catch::Contains("r.yaml:6:5: error: unknown key 'colour' in a recovery rule; expected one of: fault, process, insert, then, max_retries"));
    CHECK_THAT(w, Catch::Contains("r.yaml:5:5: error: a recovery rule: missing 'fault'"));
  }
}
