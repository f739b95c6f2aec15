// BehaviorSet: the supervisor driving real CBehavior instances (the built-in behaviors of the
// reactive layer) — parameter conversion, failures at activation, stepping, the watchdog.
#include "tripodal/processes/behavior_set.hpp"

#include <catch2/catch.hpp>

#include "../support/builtin_registries.hpp"
#include "doubles.hpp"
#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/processes/process_supervisor.hpp"

using namespace tripodal;
using namespace tripodal::test;

namespace {

// One place binding `behavior` with `params`; "<behavior>.done" succeeds; failures are unhandled.
CProcess single(const std::string& behavior, std::vector<BindingParam> params) {
  PetriNet net;
  net.id = "Pr" + behavior;
  net.add_place(place("P0", 1));
  Place p1 = place("P1");
  p1.behavior = BehaviorBinding{behavior, std::move(params)};
  net.add_place(std::move(p1));
  Place ok = place("P2");
  ok.outcome = Outcome::success;
  net.add_place(std::move(ok));
  net.add_transition(transition("t0"));
  net.add_transition(transition("t1", behavior + ".done"));
  arcs(net, {{"P0", "t0"}, {"t0", "P1"}, {"P1", "t1"}, {"t1", "P2"}});
  ProcessDefinition d;
  d.name = net.id;
  d.net = std::move(net);
  return CProcess(std::move(d));
}

struct Rig {
  SimClock clock;
  BehaviorSet set{clock};
  CProcessSupervisor supervisor;
  explicit Rig(SupervisorOptions o = {}) : supervisor(set, clock, o) {
    set.add(test::builtin_behaviors(), "BhRotateInPlace");
    set.add(test::builtin_behaviors(), "BhStop");
  }
};

}  // namespace

TEST_CASE("BehaviorSet holds registry behaviors by name", "[processes]") {
  Rig rig;
  CHECK(rig.set.names() == std::vector<std::string>{"BhRotateInPlace", "BhStop"});
  CHECK(rig.set.has("BhStop"));
  CHECK_FALSE(rig.set.has("BhFly"));
  REQUIRE_THROWS_AS(rig.set.add(test::builtin_behaviors(), "BhStop"), std::invalid_argument);
  REQUIRE_THROWS_AS(rig.set.add(test::builtin_behaviors(), "BhFly"), ConfigError);
  REQUIRE_THROWS_WITH(rig.set.add(test::builtin_behaviors(), "BhStpo"),
                      Catch::Contains("unknown behavior type 'BhStpo'; known: ") && Catch::Contains("did you mean 'BhStop'?"));
}

TEST_CASE("Text parameters from a net are converted to the manifest's types", "[processes]") {
  Rig rig;
  // angle_rad is a number in BhRotateInPlace's manifest; the net writes it as text. The behavior
  // then fails for its own reason (no odometry resource in this context), not for the parameter.
  CProcess p = single("BhRotateInPlace", {{"angle_rad", "1.5", {}}});
  REQUIRE(rig.supervisor.start("X0", p, {}));
  rig.supervisor.step();
  rig.clock.advance(from_seconds(0.1));
  rig.supervisor.step();
  auto r = rig.supervisor.take_results();
  REQUIRE(r.size() == 1);
  CHECK(r[0].message == "behavior BhRotateInPlace failed: no odometry resource");
}

TEST_CASE("A parameter the behavior's manifest rejects fails the activation, not the loop", "[processes]") {
  Rig rig;
  CProcess p = single("BhRotateInPlace", {{"angle_rad", "a lot", {}}});
  REQUIRE(rig.supervisor.start("X0", p, {}));
  REQUIRE_NOTHROW(rig.supervisor.step());
  auto r = rig.supervisor.take_results();
  REQUIRE(r.size() == 1);
  CHECK_THAT(r[0].message, Catch::StartsWith("behavior BhRotateInPlace failed: activation threw: ") &&
                               Catch::Contains("angle_rad"));
}

TEST_CASE("Active behaviors are stepped by the loop and stopped with their place", "[processes]") {
  Rig rig;
  CProcess p = single("BhStop", {});
  REQUIRE(rig.supervisor.start("X0", p, {}));
  rig.supervisor.step();
  REQUIRE(rig.set.find("BhStop")->running());
  int commands = 0;
  BehaviorContext ctx;
  rig.set.step_active(ctx, [&](std::string_view name, const std::optional<Twist2D>& cmd) {
    CHECK(name == "BhStop");
    REQUIRE(cmd);
    CHECK(*cmd == Twist2D{});
    ++commands;
  });
  CHECK(commands == 1);
  CHECK(rig.supervisor.stop("X0"));
  CHECK_FALSE(rig.set.find("BhStop")->running());
  rig.set.step_active(ctx, [&](std::string_view, const std::optional<Twist2D>&) { ++commands; });
  CHECK(commands == 1);
}

TEST_CASE("A behavior the loop stops stepping trips the supervisor's watchdog", "[processes]") {
  SupervisorOptions o;
  o.behavior_watchdog = from_seconds(0.3);
  Rig rig(o);
  CProcess p = single("BhStop", {});
  REQUIRE(rig.supervisor.start("X0", p, {}));
  rig.supervisor.step();
  BehaviorContext ctx;
  for (int i = 0; i < 3; ++i) {  // stepped for 0.3 s ...
    rig.clock.advance(from_seconds(0.1));
    rig.set.step_active(ctx, {});
    rig.supervisor.step();
  }
  CHECK(rig.supervisor.take_results().empty());
  for (int i = 0; i < 5; ++i) {  // ... then the loop hangs
    rig.clock.advance(from_seconds(0.1));
    rig.supervisor.step();
  }
  auto r = rig.supervisor.take_results();
  REQUIRE(r.size() == 1);
  CHECK(r[0].message == "behavior BhStop failed: stopped answering (no step for 0.400 s)");
  CHECK(to_seconds(r[0].finished) == Approx(0.7));
}
