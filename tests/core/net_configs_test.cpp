// The paper's configuration nets as shipped in configs/petri/, replayed through the narratives of
// section 3.1 with the scenario scripts in configs/petri/scenarios/: normal completion, a
// temporary localization loss (the robot pauses, then completes) and a persistent loss that
// reaches the fault place "localization fault" — for both wheel types.
#include <catch2/catch.hpp>

#include <filesystem>

#include "tripodal/core/engine.hpp"
#include "tripodal/core/event_script.hpp"
#include "tripodal/core/net_loader.hpp"
#include "tripodal/core/net_simulation.hpp"

using namespace tripodal;
using namespace std::string_literals;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs" / "petri";

PetriNet load_config(const char* name) {
  Diagnostics d;
  auto net = load_net(kConfigs / name, d);
  INFO(d.str());
  REQUIRE(net.has_value());
  CHECK(d.empty());  // no errors and no structural warnings either
  return std::move(*net);
}

SimulationResult simulate(const PetriNet& net, const ParameterValues& params, const std::string& script) {
  NetSimulation sim(net, params);
  return sim.run(load_event_script(kConfigs / "scenarios" / script));
}

std::vector<std::string> fired(const SimulationResult& r) {
  std::vector<std::string> out;
  for (const auto& e : r.trace) {
    if (e.kind == TraceEntry::Kind::firing) out.push_back(e.name + "@" + std::to_string(to_seconds(e.time)).substr(0, 4));
  }
  return out;
}

const std::string& describe(const PetriNet& net, const char* id) {
  if (auto p = net.find_place(id)) return net.place(*p).description;
  return net.transition(*net.find_transition(id)).description;
}

}  // namespace

TEST_CASE("configs: PrCleaning low level is Fig. 3 / Table 2") {
  const PetriNet net = load_config("PrCleaning.xml");
  CHECK(net.id == "PrCleaning");
  CHECK(net.level == NetLevel::low);
  CHECK(net.places().size() == 9);
  CHECK(net.transitions().size() == 8);
  CHECK(describe(net, "P0") == "Idle (Standby)");
  CHECK(describe(net, "P1") == "Execute behavior BhCleaning");
  CHECK(describe(net, "P2") == "Execute behavior BhCleaningTwoWheel");
  CHECK(describe(net, "P3") == "State: Normal localization (Localizer updates a robot position periodically.)");
  CHECK(describe(net, "P6") == "Fault: behavior BhCleaning is failed due to localization fault");
  CHECK(describe(net, "P8") == "Fault: behavior BhCleaningTwoWheel is failed due to localization fault");
  CHECK(describe(net, "t0") == "Start behavior BhCleaning");
  CHECK(describe(net, "t5") == "PS terminates the behavior BhCleaning due to the failure of localization");
  CHECK(net.place(1).behavior->behavior == "BhCleaning");
  CHECK(net.place(2).behavior->behavior == "BhCleaningTwoWheel");
  CHECK(net.transition(*net.find_transition("t3")).event == "localizer.lost");
  CHECK(net.transition(*net.find_transition("t2")).event == "localizer.ok");
  CHECK(net.transition(*net.find_transition("t4")).event == "BhCleaning.done");
  CHECK(net.transition(*net.find_transition("t6")).event == "BhCleaningTwoWheel.done");
  for (const char* fault : {"P6", "P8"}) {
    const Place& p = net.place(*net.find_place(fault));
    CHECK(p.outcome == Outcome::fault);
    CHECK(p.fault_message == "localization fault");
  }
}

TEST_CASE("configs: the process modules are Fig. 2 / Table 1 and its PrAutoMove twin") {
  const PetriNet module = load_config("PrCleaning-module.xml");
  CHECK(module.level == NetLevel::high);
  CHECK(describe(module, "P0") == "Standby");
  CHECK(describe(module, "P1") == "Executing the process PrCleaning");
  CHECK(describe(module, "P2") == "Completing the process PrCleaning");
  CHECK(describe(module, "P3") == "Fault: The full coverage is failed due to localization fault");
  CHECK(describe(module, "t2") == "Process supervisor (PS) posts fault message \"localization fault\"");
  CHECK(module.place(1).process->process == "PrCleaning");
  CHECK(module.place(1).process->params.at(0).value == "$wheel_type");
  const PetriNet auto_module = load_config("PrAutoMove-module.xml");
  CHECK(auto_module.place(1).process->process == "PrAutoMove");

  for (const PetriNet* net : {&module, &auto_module}) {
    const ParameterValues params = net == &module ? ParameterValues{{"wheel_type", Value{"omni"s}}}
                                                  : ParameterValues{{"goal", Value{"section2"s}}};
    const SimulationResult ok = simulate(*net, params, "module-success.events");
    CHECK(ok.outcome == Outcome::success);
    CHECK(ok.outcome_place == "P2");
    const SimulationResult fault = simulate(*net, params, "module-fault.events");
    CHECK(fault.outcome == Outcome::fault);
    CHECK(fault.outcome_place == "P3");
    CHECK(fault.fault_message == "localization fault");
  }
}

TEST_CASE("configs: PrCleaning narratives for both wheel types") {
  const PetriNet net = load_config("PrCleaning.xml");
  struct Base {
    std::string wheel_type, start, behavior_place, done, timeout, success, fault;
  };
  for (const Base& b : {Base{"omni", "t0", "P1", "t4", "t5", "P5", "P6"},
                        Base{"differential", "t1", "P2", "t6", "t7", "P7", "P8"}}) {
    INFO(b.wheel_type);
    const ParameterValues params{{"wheel_type", Value{b.wheel_type}}};

    const SimulationResult normal = simulate(net, params, "PrCleaning-" + b.wheel_type + "-normal.events");
    CHECK(fired(normal) == std::vector<std::string>{b.start + "@0.00", b.done + "@60.0"});
    CHECK(normal.outcome == Outcome::success);
    CHECK(normal.outcome_place == b.success);

    const SimulationResult temporary = simulate(net, params, "PrCleaning-" + b.wheel_type + "-temporary-loss.events");
    CHECK(fired(temporary) == std::vector<std::string>{b.start + "@0.00", "t3@20.0", "t2@26.0", b.done + "@60.0"});
    CHECK(temporary.outcome == Outcome::success);
    CHECK(temporary.outcome_place == b.success);

    const SimulationResult persistent = simulate(net, params, "PrCleaning-" + b.wheel_type + "-persistent-loss.events");
    CHECK(fired(persistent) == std::vector<std::string>{b.start + "@0.00", "t3@20.0", b.timeout + "@30.0"});
    CHECK(persistent.outcome == Outcome::fault);
    CHECK(persistent.outcome_place == b.fault);
    CHECK(persistent.fault_message == "localization fault");
    CHECK(persistent.end_time == time_from_seconds(30.0));
  }
}

TEST_CASE("configs: while localization is lost the robot pauses and cannot complete") {
  const PetriNet net = load_config("PrCleaning.xml");
  Engine engine(net, {{"wheel_type", Value{"omni"s}}});
  const auto P = [&](const char* id) { return *net.find_place(id); };
  engine.step(time_from_seconds(0.0));
  CHECK(engine.tokens(P("P1")) == 1);
  engine.step(time_from_seconds(20.0), {"localizer.lost"});
  CHECK(engine.tokens(P("P4")) == 1);
  // The behavior reports completion during the pause: not accepted (the coverage is not sure).
  const StepResult& paused = engine.step(time_from_seconds(22.0), {"BhCleaning.done"});
  CHECK(paused.firings == 0);
  CHECK(paused.unconsumed_events == std::vector<std::string>{"BhCleaning.done"});
  CHECK(engine.tokens(P("P1")) == 1);
  CHECK(engine.next_deadline() == time_from_seconds(30.0));
  engine.step(time_from_seconds(25.0), {"localizer.ok"});  // recovered before the fault delay
  CHECK(engine.next_deadline() == std::nullopt);
  engine.step(time_from_seconds(40.0), {"BhCleaning.done"});
  CHECK(engine.outcome().outcome == Outcome::success);
  CHECK(engine.outcome().place_id == "P5");
}

TEST_CASE("configs: PrAutoMove narratives") {
  const PetriNet net = load_config("PrAutoMove.xml");
  CHECK(describe(net, "P1") == "Execute behavior BhAutoMove");
  CHECK(net.place(1).behavior->params.at(0).value == "$goal");
  const ParameterValues params{{"goal", Value{"section2"s}}};
  const SimulationResult normal = simulate(net, params, "PrAutoMove-normal.events");
  CHECK(fired(normal) == std::vector<std::string>{"t0@0.00", "t3@30.0"});
  CHECK(normal.outcome_place == "P4");
  const SimulationResult temporary = simulate(net, params, "PrAutoMove-temporary-loss.events");
  CHECK(fired(temporary) == std::vector<std::string>{"t0@0.00", "t2@8.00", "t1@12.0", "t3@30.0"});
  CHECK(temporary.outcome == Outcome::success);
  const SimulationResult persistent = simulate(net, params, "PrAutoMove-persistent-loss.events");
  CHECK(fired(persistent) == std::vector<std::string>{"t0@0.00", "t2@8.00", "t4@18.0"});
  CHECK(persistent.outcome == Outcome::fault);
  CHECK(persistent.outcome_place == "P5");
  CHECK(persistent.fault_message == "localization fault");
  // the fault the `path blocked` rule of configs/tasks/recovery.yaml matches
  const SimulationResult blocked = simulate(net, params, "PrAutoMove-path-blocked.events");
  CHECK(fired(blocked) == std::vector<std::string>{"t0@0.00", "t5@12.0"});
  CHECK(blocked.outcome_place == "P6");
  CHECK(blocked.fault_message == "path blocked");
}

TEST_CASE("configs: PrCleaning without its wheel type is refused") {
  const PetriNet net = load_config("PrCleaning.xml");
  REQUIRE_THROWS_WITH(Engine(net), Catch::Contains("wheel_type"));
}

TEST_CASE("configs: the complete example of docs/net-format.md loads and runs") {
  Diagnostics d;
  const auto net = load_net(std::filesystem::path(TRIPODAL_SOURCE_DIR) / "docs" / "examples" / "net-format-example.xml", d);
  INFO(d.str());
  REQUIRE(net.has_value());
  CHECK(d.empty());
  Engine engine(*net, {{"room", Value{"2111"s}}});
  const auto P = [&](const char* id) { return *net->find_place(id); };
  engine.step(time_from_seconds(0.0));
  CHECK(engine.tokens(P("P2")) == 1);
  CHECK(engine.tokens(P("P3")) == 1);  // fog defaults to true
  engine.step(time_from_seconds(1.0), {"bumper.hit", "bumper.hit"});
  CHECK_FALSE(net->find_place("bumps"));  // "bumps" is P4's name; ids are what arcs and lookups use
  CHECK(engine.tokens(P("P4")) == 2);
  engine.set_fact("disinfectant_empty", Value{true});
  engine.step(time_from_seconds(1.2));
  CHECK(engine.outcome().outcome == Outcome::none);
  engine.step(time_from_seconds(1.5));
  CHECK(engine.outcome().outcome == Outcome::fault);
  CHECK(engine.outcome().message == "disinfectant empty");
}
