#include "tripodal/planner/recovery.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tripodal/core/event_script.hpp"
#include "tripodal/core/net_loader.hpp"
#include "tripodal/core/net_simulation.hpp"

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
    CHECK_THAT(w, Catch::Contains("r.yaml:3:11: error: 'then': expected one of retry, skip, abort, end; got 'restart'"));
    CHECK_THAT(w, Catch::Contains("r.yaml:4:18: error: 'max_retries': expected a whole number from 0 to 1000000, got '-1'"));
    CHECK_THAT(w, Catch::Contains("r.yaml:5:15: error: an inserted step must be a map"));
    CHECK_THAT(w, Catch::Contains("r.yaml:6:5: error: unknown key 'colour' in a recovery rule; expected one of: fault, process, insert, then, max_retries"));
    CHECK_THAT(w, Catch::Contains("r.yaml:5:5: error: a recovery rule: missing 'fault'"));
  }
}

TEST_CASE("recovery rules whose process or parameter keys are not text are located") {
  const char* yaml = "recovery:\n  - fault: x\n    insert:\n      - {[PrA]: {}}\n      - PrB: {[k]: v, n: 1}\n";
  try {
    (void)RecoveryPolicy::load_from_string(yaml, "k.yaml");
    FAIL("expected ConfigError");
  } catch (const ConfigError& e) {
    const std::string w = e.what();
    CHECK_THAT(w, Catch::Contains("k.yaml:4:10: error: an inserted step (the process name): a key must be text, got a list"));
    CHECK_THAT(w, Catch::Contains("k.yaml:5:15: error: the parameters of 'PrB': a key must be text, got a list"));
    CHECK(e.diagnostics().error_count() == 2);
  }
}

namespace {

PetriNet shipped_net(const char* file) { return load_net_or_throw(std::string(TRIPODAL_SOURCE_DIR "/configs/petri/") + file); }

// A process net with one fault place per message, each marked by its own event from P1, and one
// more fault place ("never posted") that no transition can mark.
PetriNet net_posting(const std::string& id, const std::vector<std::string>& messages) {
  std::string xml = "<net id=\"" + id + "\" level=\"low\">\n<place id=\"P0\" tokens=\"1\"/>\n<place id=\"P1\"/>\n"
                    "<place id=\"OK\" outcome=\"success\"/>\n<place id=\"DEAD\" outcome=\"fault\" message=\"never posted\"/>\n"
                    "<transition id=\"t0\"/>\n<transition id=\"ok\" event=\"done\"/>\n"
                    "<arc source=\"P0\" target=\"t0\"/>\n<arc source=\"t0\" target=\"P1\"/>\n"
                    "<arc source=\"P1\" target=\"ok\"/>\n<arc source=\"ok\" target=\"OK\"/>\n"
                    "<transition id=\"never\"/>\n<arc source=\"never\" target=\"DEAD\"/>\n<place id=\"NOWHERE\"/>\n"
                    "<arc source=\"NOWHERE\" target=\"never\"/>\n";
  for (std::size_t i = 0; i < messages.size(); ++i) {
    const std::string f = "F" + std::to_string(i), t = "f" + std::to_string(i);
    xml += "<place id=\"" + f + "\" outcome=\"fault\" message=\"" + messages[i] + "\"/>\n<transition id=\"" + t +
           "\" event=\"e" + std::to_string(i) + "\"/>\n<arc source=\"P1\" target=\"" + t + "\"/>\n<arc source=\"" + t +
           "\" target=\"" + f + "\"/>\n";
  }
  Diagnostics d;
  LoadOptions lo;
  lo.structural_warnings = false;
  auto net = load_net_from_string(xml + "</net>\n", id + ".xml", d, lo);
  REQUIRE(net);
  return *net;
}

}  // namespace

TEST_CASE("the fault messages a net can post: its fault places that can be marked") {
  CHECK(postable_fault_messages(net_posting("P", {"path blocked", "localization fault", "path blocked"})) ==
        std::vector<std::string>{"path blocked", "localization fault"});
  CHECK(postable_fault_messages(shipped_net("PrAutoMove.xml")) == std::vector<std::string>{"localization fault", "path blocked"});
  CHECK(postable_fault_messages(shipped_net("PrCleaning.xml")) == std::vector<std::string>{"localization fault"});
  CHECK(postable_fault_messages(shipped_net("PrWait.xml")).empty());
}

TEST_CASE("end runs the inserted processes and drops the rest of the plan (the home button)") {
  const auto policy = RecoveryPolicy::load(TRIPODAL_SOURCE_DIR "/configs/tasks/disinfection_recovery.yaml");
  Plan plan;
  plan.task = "disinfect";
  plan.stages.push_back({{{"PrDisinfection", {{"section", "A", {}}}}}});
  plan.stages.push_back({{{"PrAutoMove", {{"goal", "B.entry", {}}}}}});
  const auto home = policy.decide(plan.stages[0].steps[0], "home button: sent to the dock", 0);
  CHECK(home.action == RecoveryAction::end);
  CHECK(home.reason == "fault \"home button: sent to the dock\" of PrDisinfection: insert PrDockCharge, then end the task (1/1)");
  CHECK(to_string(RecoveryPolicy::remaining_plan(plan, 0, home)) == "PrDockCharge()");
  // The low battery charges and takes the same section up again, then the rest.
  const auto low = policy.decide(plan.stages[0].steps[0], "battery low: disinfection ended safely", 0);
  CHECK(low.action == RecoveryAction::retry);
  CHECK(to_string(RecoveryPolicy::remaining_plan(plan, 0, low)) ==
        "PrDockCharge() -> PrDisinfection(section=A) -> PrAutoMove(goal=B.entry)");
}

TEST_CASE("every shipped recovery rule matches a fault a shipped net posts, and inserts a process that has a net") {
  const PetriNet automove = shipped_net("PrAutoMove.xml"), cleaning = shipped_net("PrCleaning.xml"),
                 global = shipped_net("PrGlobalLocalization.xml"), wait = shipped_net("PrWait.xml"),
                 back_off = shipped_net("PrBackOff.xml"), disinfection = shipped_net("PrDisinfection.xml"),
                 dock = shipped_net("PrDockCharge.xml"), reconnect = shipped_net("PrBoardReconnect.xml");
  const std::vector<ProcessNet> nets{{"PrAutoMove", &automove},         {"PrCleaning", &cleaning},
                                     {"PrGlobalLocalization", &global}, {"PrWait", &wait},
                                     {"PrBackOff", &back_off},          {"PrDisinfection", &disinfection},
                                     {"PrDockCharge", &dock},           {"PrBoardReconnect", &reconnect}};
  for (const char* file :
       {"recovery.yaml", "jinny_recovery.yaml", "disinfection_recovery.yaml", "disinfection_devices_recovery.yaml"}) {
    INFO(file);
    Diagnostics d;
    check_recovery_rules(RecoveryPolicy::load(std::string(TRIPODAL_SOURCE_DIR "/configs/tasks/") + file), nets, d);
    CHECK(d.str().empty());
  }
}

TEST_CASE("recovery rules that can never match are reported at the rule, with what the nets post") {
  const RecoveryPolicy policy = RecoveryPolicy::load_from_string(R"(recovery:
  - fault: path blocked
    process: PrAutoMove
    insert:
      - PrWait: {}
    then: retry
  - fault: Localization Fault
    insert:
      - PrGlobalLocalization: {}
  - fault: never posted
    then: abort
  - fault: battery low
    process: PrDock
    then: abort
  - fault: "module localizer failed: scan matcher crashed"
    then: abort
)",
                                                                 "rules.yaml");
  // PrAutoMove as it was before its "path blocked" fault place; no PrWait, no PrDock
  const PetriNet automove = net_posting("PrAutoMove", {"localization fault"});
  const PetriNet cleaning = net_posting("PrCleaning", {"localization fault", "cleaning failed"});
  const PetriNet global = net_posting("PrGlobalLocalization", {});
  const std::vector<ProcessNet> nets{{"PrAutoMove", &automove}, {"PrCleaning", &cleaning}, {"PrGlobalLocalization", &global}};
  Diagnostics d;
  check_recovery_rules(policy, nets, d);
  INFO(d.str());
  REQUIRE(d.error_count() == 4);
  const auto& all = d.all();
  CHECK(all[0].str() ==
        "rules.yaml:2:5: error: recovery rule for \"path blocked\" of PrAutoMove can never match: the net of PrAutoMove does "
        "not post this fault message (it posts \"localization fault\" (PrAutoMove))");
  CHECK(all[1].str() == "rules.yaml:2:5: error: recovery rule for \"path blocked\" of PrAutoMove inserts process 'PrWait', "
                        "which has no net here");
  // "Localization Fault" matches case-insensitively; "never posted" is a fault place no firing marks
  CHECK(all[2].str() ==
        "rules.yaml:10:5: error: recovery rule for \"never posted\" can never match: no net posts this fault message (the nets "
        "post \"localization fault\" (PrAutoMove, PrCleaning), \"cleaning failed\" (PrCleaning))");
  CHECK(all[3].str() == "rules.yaml:12:5: error: recovery rule for \"battery low\" of PrDock names process 'PrDock', which "
                        "has no net here");
  // the supervisor's own messages are not the nets' to post
  CHECK(is_supervisor_fault_message("module localizer failed: scan matcher crashed"));
  CHECK(is_supervisor_fault_message("behavior BhAutoMove failed: unknown goal"));
  CHECK(is_supervisor_fault_message("stopped: cancelled"));
  CHECK_FALSE(is_supervisor_fault_message("path blocked"));
  CHECK_FALSE(is_supervisor_fault_message("behavior failed"));
}

TEST_CASE("Jinny backs off, then waits, then retries PrAutoMove after 'path blocked'", "[safety]") {
  const auto policy = RecoveryPolicy::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_recovery.yaml");
  Plan plan;
  plan.task = "explain";
  plan.stages.push_back({{{"PrAutoMove", {{"goal", "node0", {}}}}}});
  plan.stages.push_back({{{"PrExplain", {{"topic", "the robot at node 0", {}}}}}});
  const auto d = policy.decide(plan.stages[0].steps[0], "path blocked", 0);
  CHECK(d.action == RecoveryAction::retry);
  CHECK(d.reason == "fault \"path blocked\" of PrAutoMove: insert PrBackOff, PrWait, then retry (1/3)");
  CHECK(to_string(RecoveryPolicy::remaining_plan(plan, 0, d)) ==
        "PrBackOff() -> PrWait() -> PrAutoMove(goal=node0) -> PrExplain(topic=the robot at node 0)");
  CHECK(policy.decide(plan.stages[0].steps[0], "path blocked", 3).action == RecoveryAction::abort);
}

TEST_CASE("PrBackOff succeeds when BhBackOff is done or failed, and after 8 s when held", "[safety]") {
  const PetriNet net = shipped_net("PrBackOff.xml");
  CHECK(postable_fault_messages(net).empty());  // a best effort: it never fails the task
  const auto run = [&](const char* script) {
    NetSimulation sim(net, {});
    return sim.run(parse_event_script(script, "back_off.script"));
  };
  const SimulationResult done = run("1.5 BhBackOff.done\n");
  CHECK(done.outcome == Outcome::success);
  CHECK(to_seconds(done.end_time) == Approx(1.5));
  const SimulationResult failed = run("0.2 BhBackOff.failed\n");
  CHECK(failed.outcome == Outcome::success);
  CHECK(to_seconds(failed.end_time) == Approx(0.2));
  // Held by the safety behavior (something behind as well): nothing comes, the delay ends it.
  const SimulationResult held = run("");
  CHECK(held.outcome == Outcome::success);
  CHECK(to_seconds(held.end_time) == Approx(8.0));
}

// --- include: a robot's rules file shares a family's rules -----------------------------------------

namespace {

// A folder of rules files for one test, removed after it.
class RulesDir {
 public:
  RulesDir() : path_(std::filesystem::temp_directory_path() / ("tripodal_recovery_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path_);
  }
  ~RulesDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  RulesDir(const RulesDir&) = delete;
  RulesDir& operator=(const RulesDir&) = delete;
  std::filesystem::path write(const std::string& name, const std::string& text) const {
    std::ofstream(path_ / name) << text;
    return path_of(name);
  }
  [[nodiscard]] std::filesystem::path path_of(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

}  // namespace

TEST_CASE("include: the included file's rules follow the file's own, which win for the same fault") {
  const RulesDir dir;
  dir.write("family.yaml", R"(recovery:
  - fault: battery low
    process: PrDisinfection
    insert:
      - PrDockCharge: {}
    then: retry
  - fault: path blocked
    then: abort
)");
  const auto robot = dir.write("robot.yaml", R"(include: [family.yaml]
recovery:
  - fault: path blocked
    insert:
      - PrWait: {}
    then: retry
)");
  const RecoveryPolicy policy = RecoveryPolicy::load(robot);
  REQUIRE(policy.rules().size() == 3);
  CHECK(policy.rules()[0].fault == "path blocked");
  CHECK(policy.rules()[1].fault == "battery low");
  CHECK(policy.rules()[1].where.str().find("family.yaml:2:5") != std::string::npos);  // located in its own file
  const ProcessStep drive{"PrAutoMove", {}};
  CHECK(policy.decide(drive, "path blocked", 0).action == RecoveryAction::retry);  // the robot's rule
  Plan plan;
  plan.task = "disinfect";
  plan.stages.push_back({{{"PrDisinfection", {}}}});
  const auto low = policy.decide(plan.stages[0].steps[0], "battery low", 0);
  CHECK(to_string(RecoveryPolicy::remaining_plan(plan, 0, low)) == "PrDockCharge() -> PrDisinfection()");
  // A file of includes only.
  CHECK(RecoveryPolicy::load(dir.write("only.yaml", "include: [family.yaml]\n")).rules().size() == 2);
}

TEST_CASE("include: a missing file and a file that includes itself are errors at the entry") {
  const RulesDir dir;
  dir.write("a.yaml", "include: [b.yaml]\nrecovery: []\n");
  dir.write("b.yaml", "include: [a.yaml]\nrecovery: []\n");
  const auto missing = dir.write("missing.yaml", "recovery: []\ninclude:\n  - nowhere.yaml\n");
  CHECK_THROWS_WITH(RecoveryPolicy::load(missing), Catch::Contains("missing.yaml:3:5: error: include: no recovery rules file") &&
                                                       Catch::Contains("nowhere.yaml"));
  CHECK_THROWS_WITH(
      RecoveryPolicy::load(dir.path_of("a.yaml")),
      Catch::Contains("b.yaml:1:11: error: include: ") && Catch::Contains("includes itself (a.yaml -> b.yaml -> a.yaml)"));
  CHECK_THROWS_WITH(RecoveryPolicy::load(dir.write("bad.yaml", "include: family.yaml\nrecovery: []\n")),
                    Catch::Contains("bad.yaml:1:10") && Catch::Contains("'include'"));
}

TEST_CASE("the lidar profile's rules file includes the disinfection rules: low battery, home button, blocked drive") {
  const auto policy = RecoveryPolicy::load(TRIPODAL_SOURCE_DIR "/configs/tasks/disinfection_devices_recovery.yaml");
  const ProcessStep disinfection{"PrDisinfection", {{"section", "A", {}}}};
  const auto low = policy.decide(disinfection, "battery low: disinfection ended safely", 0);
  CHECK(low.action == RecoveryAction::retry);
  CHECK(low.reason ==
        "fault \"battery low: disinfection ended safely\" of PrDisinfection: insert PrDockCharge, then retry (1/6)");
  CHECK(policy.decide(disinfection, "home button: sent to the dock", 0).action == RecoveryAction::end);
  CHECK(policy.decide({"PrAutoMove", {}}, "path blocked", 0).action == RecoveryAction::retry);
  CHECK(policy.decide({"PrAutoMove", {}}, "module board failed: link lost", 0).action == RecoveryAction::retry);
}
