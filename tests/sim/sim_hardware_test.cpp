// The simulator as a robot's hardware built from the profile's hardware entry (SimHardware's
// HardwareConfig constructor): the world and seed rules, the located refusals, and an application
// hardware type deriving from it.
#include <catch2/catch.hpp>

#include <memory>
#include <string>

#include "sim_test_util.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;
using namespace tripodal::sim;

namespace {

HardwareConfig entry(const ControllerConfig* base, const ParameterValues& given = {}, std::string type = "sim") {
  HardwareConfig c;
  c.type = std::move(type);
  c.where = {"robot.yaml", 13, 3};
  c.parameters = ParameterSet::resolve(SimHardware::static_manifest(), given);
  c.base = base;
  return c;
}

std::shared_ptr<const World> seeded_room(std::uint64_t seed) {
  World w = test::room_world(40, 40, {1.0, 1.0, 0.0});
  w.seed = seed;
  return std::make_shared<const World>(std::move(w));
}

// An application's hardware: the simulated base and a device of its own updated after each step.
class CountingBase final : public SimHardware {
 public:
  using SimHardware::SimHardware;
  int advances = 0;

 private:
  void on_advance_to(Time now) noexcept override {
    SimHardware::on_advance_to(now);
    ++advances;
  }
};

}  // namespace

TEST_CASE("SimHardware from a hardware entry: the given world, the world's seed unless the entry sets one",
          "[sim]") {
  const ControllerConfig base = test::differential_base();
  const auto world = seeded_room(42);
  CHECK(SimHardware(entry(&base), world).seed() == 42);
  CHECK(SimHardware(entry(&base, {{"seed", Value{7.0}}}), world).seed() == 7);
  const SimHardware hw(entry(&base), world);
  CHECK(hw.simulator().world().grid.width() == 40);
  CHECK(hw.true_pose(Time{})->x_m == Approx(1.0));
}

TEST_CASE("SimHardware from a hardware entry refuses, located, a robot without base or world", "[sim]") {
  const ControllerConfig base = test::differential_base();
  REQUIRE_THROWS_WITH(SimHardware(entry(nullptr), seeded_room(1)),
                      Catch::Contains("robot.yaml:13:3: error: hardware 'sim' needs the robot's base controller"));
  REQUIRE_THROWS_WITH(SimHardware(entry(&base, {}, "sim_with_beacon")),
                      Catch::Contains("robot.yaml:13:3: error: hardware 'sim_with_beacon' needs a world: "
                                      "parameters: {world: FILE}"));
}

TEST_CASE("An application's hardware derived from SimHardware moves with the simulated base", "[sim]") {
  const ControllerConfig base = test::differential_base();
  CountingBase hw(entry(&base), seeded_room(3));
  CHECK(&hw.wheels() == &hw.simulator());
  hw.advance_to(time_from_seconds(0.1));
  hw.advance_to(time_from_seconds(0.2));
  CHECK(hw.advances == 2);
  CHECK(hw.simulator().now() == time_from_seconds(0.2));
}
