#include "tripodal/planner/plan.hpp"

#include <catch2/catch.hpp>

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
  // S0 S1 DONE FAULT X0 X1
  CHECK(net.places().size() == 6);
  CHECK(net.transitions().size() == 6);  // start, ok, ko per stage
  const Place& x1 = net.place(*net.find_place("X1"));
  REQUIRE(x1.process);
  CHECK(x1.process->process == "PrCleaning");
  CHECK(x1.process->params.at(0).value == "A");
  CHECK(net.place(*net.find_place("S0")).initial_tokens == 1);
  CHECK(net.place(*net.find_place("DONE")).outcome == Outcome::success);
  CHECK(net.place(*net.find_place("FAULT")).outcome == Outcome::fault);

  const Transition& ok1 = net.transition(*net.find_transition("ok1"));
  CHECK(ok1.event == "X1.success");
  REQUIRE(ok1.outputs.size() == 1);
  CHECK(net.place(ok1.outputs[0].place).id == "DONE");
  const Transition& ok0 = net.transition(*net.find_transition("ok0"));
  CHECK(net.place(ok0.outputs.at(0).place).id == "S1");
  CHECK(net.transition(*net.find_transition("ko0")).event == "X0.fault");
}

TEST_CASE("a parallel stage forks and joins") {
  Plan p;
  p.stages.push_back({{{"PrAutoMove", {}}, {"PrExplain", {}}}});
  const PetriNet net = plan_to_net(p);
  const Transition& start = net.transition(*net.find_transition("start0"));
  CHECK(start.outputs.size() == 2);
  const Transition& join = net.transition(*net.find_transition("join0"));
  REQUIRE(join.inputs.size() == 2);
  CHECK(net.place(join.inputs[0].place).id == "D0_0");
  CHECK(net.place(join.inputs[1].place).id == "D0_1");
  CHECK(net.place(join.outputs.at(0).place).id == "DONE");
  CHECK(net.find_place("X0_1").has_value());
}

TEST_CASE("an empty plan is already done") {
  const PetriNet net = plan_to_net(Plan{});
  CHECK(net.place(*net.find_place("DONE")).initial_tokens == 1);
  CHECK(to_string(Plan{}) == "(empty plan)");
}
