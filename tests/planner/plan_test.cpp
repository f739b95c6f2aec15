#include "tripodal/planner/plan.hpp"

#include <catch2/catch.hpp>

#include "tripodal/core/net_loader.hpp"

using namespace tripodal;

namespace {
Plan two_sections() {
  Plan p;
  p.task = "clean";
  p.stages.push_back({{{"PrAutoMove", {{"goal", "A.entry", {}}}}}});
  p.stages.push_back({{{"PrCleaning", {{"section", "A", {}}}}}});
  return p;
}
}  // namespace

TEST_CASE("a sequential plan becomes the paper's process modules composed in series") {
  const PetriNet net = plan_to_net(two_sections());
  CHECK(net.level == NetLevel::high);
  // S0 S1 DONE FAULT X0 X1: each module's success place is the next one's standby
  CHECK(net.places().size() == 6);
  CHECK(net.transitions().size() == 6);  // t0 (start), t1 (success), t2 (fault) per module
  const Place& x1 = net.place(*net.find_place("X1"));
  REQUIRE(x1.process);
  CHECK(x1.process->process == "PrCleaning");
  CHECK(x1.process->params.at(0).value == "A");
  CHECK(net.place(*net.find_place("S0")).initial_tokens == 1);
  CHECK(net.place(*net.find_place("DONE")).outcome == Outcome::success);
  CHECK(net.place(*net.find_place("FAULT")).outcome == Outcome::fault);

  const Transition& ok1 = net.transition(*net.find_transition("X1.t1"));
  CHECK(ok1.event == "X1.success");
  REQUIRE(ok1.outputs.size() == 1);
  CHECK(net.place(ok1.outputs[0].place).id == "DONE");
  const Transition& ok0 = net.transition(*net.find_transition("X0.t1"));
  CHECK(net.place(ok0.outputs.at(0).place).id == "S1");
  const Transition& ko0 = net.transition(*net.find_transition("X0.t2"));
  CHECK(ko0.event == "X0.fault");
  CHECK(net.place(ko0.outputs.at(0).place).id == "FAULT");
  CHECK(net.transition(*net.find_transition("X1.t0")).description == "Planner starts the process PrCleaning");
}

TEST_CASE("a parallel stage forks and joins") {
  Plan p;
  p.stages.push_back({{{"PrAutoMove", {}}, {"PrExplain", {}}}});
  const PetriNet net = plan_to_net(p);
  const Transition& fork = net.transition(*net.find_transition("fork0"));
  REQUIRE(fork.outputs.size() == 2);
  CHECK(net.place(fork.outputs[0].place).id == "S0_0");
  CHECK(net.place(fork.outputs[1].place).id == "S0_1");
  const Transition& join = net.transition(*net.find_transition("join0"));
  REQUIRE(join.inputs.size() == 2);
  CHECK(net.place(join.inputs[0].place).id == "D0_0");
  CHECK(net.place(join.inputs[1].place).id == "D0_1");
  CHECK(net.place(join.outputs.at(0).place).id == "DONE");
  CHECK(net.find_place("X0_1").has_value());
  CHECK(net.transition(*net.find_transition("X0_1.t1")).event == "X0_1.success");
}

TEST_CASE("the plan's net is made of the module nets loaded from configs/petri (Fig. 2 / Table 1)") {
  const PetriNet cleaning = load_net_or_throw(TRIPODAL_SOURCE_DIR "/configs/petri/PrCleaning-module.xml");
  const PetriNet automove = load_net_or_throw(TRIPODAL_SOURCE_DIR "/configs/petri/PrAutoMove-module.xml");
  int asked = 0;
  const ModuleNetOf module_of = [&](std::string_view process) -> const PetriNet* {
    ++asked;
    return process == "PrCleaning" ? &cleaning : process == "PrAutoMove" ? &automove : nullptr;
  };
  Plan p = two_sections();
  p.stages.push_back({{{"PrGlobalLocalization", {}}}});  // no module file: the default module
  const PetriNet net = plan_to_net(p, "plan", module_of);
  CHECK(asked == 3);
  const Place& x1 = net.place(*net.find_place("X1"));
  CHECK(x1.description == "Executing the process PrCleaning");
  REQUIRE(x1.process);
  CHECK(x1.process->params.size() == 1);  // the plan's parameters, not the module's $wheel_type, $section
  CHECK(x1.process->params.at(0).name == "section");
  CHECK(net.transition(*net.find_transition("X1.t2")).description ==
        "Process supervisor (PS) posts fault message \"localization fault\"");
  CHECK(net.transition(*net.find_transition("X1.t2")).event == "X1.fault");
  CHECK(net.transition(*net.find_transition("X0.t2")).description ==
        "Process supervisor (PS) posts fault message \"localization fault\"");
  CHECK(net.transition(*net.find_transition("X2.t2")).description ==
        "Process supervisor (PS) posts the fault message of PrGlobalLocalization");
  // the module's fault places, whatever message they print, are the plan's one FAULT: the
  // planner takes the message from the failing process
  const Place& fault = net.place(*net.find_place("FAULT"));
  CHECK(fault.fault_message == "process failed");
  CHECK(net.places().size() == 3 + 2 + 3);  // S0..S2, DONE, FAULT, X0..X2
  CHECK(net.find_node_where("X1.t2")->str().find("PrCleaning-module.xml") != std::string::npos);
}

TEST_CASE("a module with nodes of its own keeps them, named after its executing place") {
  Diagnostics d;
  const auto m = load_net_from_string(R"(<net id="PrDockModule" level="high">
  <place id="P0" tokens="1"/>
  <place id="P1"><process name="PrDock"/></place>
  <place id="P2" outcome="success"/>
  <place id="P3" outcome="fault" message="battery low"/>
  <place id="P4" outcome="fault" message="docking failed"/>
  <place id="P5" description="Timed out"/>
  <transition id="t0"/>
  <transition id="t1" event="P1.success"/>
  <transition id="t2" event="P1.fault"/>
  <transition id="t3" delay="10min"/>
  <transition id="t4"/>
  <arc source="P0" target="t0"/><arc source="t0" target="P1"/>
  <arc source="P1" target="t1"/><arc source="t1" target="P2"/>
  <arc source="P1" target="t2"/><arc source="t2" target="P3"/>
  <arc source="P1" target="t3"/><arc source="t3" target="P5"/>
  <arc source="P5" target="t4"/><arc source="t4" target="P4"/>
</net>)",
                                      "dock-module.xml", d);
  REQUIRE(m);
  Plan p;
  p.stages.push_back({{{"PrDock", {}}}});
  const PetriNet net = plan_to_net(p, "plan", [&](std::string_view) { return &*m; });
  CHECK(net.place(*net.find_place("X0.P5")).description == "Timed out");
  const Transition& t3 = net.transition(*net.find_transition("X0.t3"));
  CHECK(t3.delay == from_seconds(600.0));
  CHECK(net.place(net.transition(*net.find_transition("X0.t4")).outputs.at(0).place).id == "FAULT");
}

TEST_CASE("a module net the planner cannot compose is refused with located reasons") {
  Diagnostics load;
  const auto bad = load_net_from_string(R"(<net id="Bad" level="low">
  <parameter name="x" type="number" default="1"/>
  <place id="P0" tokens="1"/>
  <place id="P1"><process name="PrAutoMove"/></place>
  <place id="P2" tokens="1"><behavior name="BhStop"/></place>
  <place id="P3" outcome="success"/>
  <transition id="t0" event="localizer.lost"/>
  <transition id="t1" event="P1.success" guard="x &gt; 0"/>
  <arc source="P0" target="t0"/><arc source="t0" target="P1"/>
  <arc source="P1" target="t1"/><arc source="t1" target="P3"/>
  <arc source="P2" target="t1" kind="read"/>
</net>)",
                                        "bad-module.xml", load);
  REQUIRE(bad);
  Diagnostics d;
  check_module_net(*bad, "PrCleaning", d);
  const std::string text = d.str();
  INFO(text);
  CHECK_THAT(text, Catch::Contains("bad-module.xml:1:1: error: process module of PrCleaning: a process module is a high-level net"));
  CHECK_THAT(text, Catch::Contains("bad-module.xml:4:3: error: process module of PrCleaning: place 'P1' runs process 'PrAutoMove'; "
                                   "the module's executing place must run 'PrCleaning'"));
  CHECK_THAT(text, Catch::Contains("bad-module.xml:5:3: error: process module of PrCleaning: place 'P2' binds behavior 'BhStop'"));
  CHECK_THAT(text, Catch::Contains("error: process module of PrCleaning: expected exactly one standby place (the one marked "
                                   "initially), found 2"));
  CHECK_THAT(text, Catch::Contains("error: process module of PrCleaning: expected at least one fault place"));
  CHECK_THAT(text, Catch::Contains("bad-module.xml:7:3: error: process module of PrCleaning: transition 't0' waits for event "
                                   "'localizer.lost'; the planner posts only 'P1.success' and 'P1.fault'"));
  CHECK_THAT(text, Catch::Contains("bad-module.xml:8:3: error: process module of PrCleaning: transition 't1' has a guard"));
  Plan p;
  p.stages.push_back({{{"PrCleaning", {}}}});
  REQUIRE_THROWS_WITH(plan_to_net(p, "plan", [&](std::string_view) { return &*bad; }),
                      Catch::Contains("bad-module.xml:4:3: error: process module of PrCleaning"));
  // and the shipped modules are fine
  Diagnostics ok;
  check_module_net(load_net_or_throw(TRIPODAL_SOURCE_DIR "/configs/petri/PrCleaning-module.xml"), "PrCleaning", ok);
  check_module_net(load_net_or_throw(TRIPODAL_SOURCE_DIR "/configs/petri/PrAutoMove-module.xml"), "PrAutoMove", ok);
  check_module_net(default_module_net("PrWait"), "PrWait", ok);
  CHECK(ok.str().empty());
}

TEST_CASE("an empty plan is already done") {
  const PetriNet net = plan_to_net(Plan{});
  CHECK(net.place(*net.find_place("DONE")).initial_tokens == 1);
  CHECK(to_string(Plan{}) == "(empty plan)");
}
