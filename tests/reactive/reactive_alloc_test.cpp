// Proves that one reactive cycle in steady state allocates nothing: resources, eight behaviors,
// the coordinator and a controller, counted with a replaced global operator new over many
// cycles. Its own executable, so the replacement affects no other suite.
#include <catch2/catch.hpp>

#include "reactive_rig.hpp"
#include "../support/counting_new.hpp"

using namespace tripodal;

TEST_CASE("A steady-state reactive cycle allocates nothing (8 behaviors, both modes, both bases)") {
  for (const bool omni : {false, true}) {
    for (const CoordinationMode mode : {CoordinationMode::priority, CoordinationMode::weighted_sum}) {
      INFO((omni ? "omni " : "differential ") << to_string(mode));
      test::ReactiveRig rig(omni ? test::omni_base_psr() : test::differential_base(), mode);
      rig.activate_eight();
      // Warm-up: the activations join the loop, the laser table is built, events are handed over.
      for (int i = 0; i < 10; ++i) rig.cycle();
      REQUIRE(rig.loop->last_cycle().active_behaviors == 8);
      const std::size_t before = test::allocations();
      std::uint64_t limited = 0;
      for (int i = 0; i < 10'000; ++i) {
        const CycleReport& r = rig.cycle();
        limited += r.coordinator.safety_limited ? 1 : 0;
      }
      const std::size_t during = test::allocations() - before;
      CHECK(during == 0);
      CHECK(rig.loop->cycles() == 10'010);
      // The cycles did real work: the base moved and behaviors are still running.
      CHECK(rig.loop->last_cycle().active_behaviors >= 6);
      CHECK(rig.hardware->writes() == 10'010);  // the controller drove the wheels every cycle
      CHECK(limited > 0);  // the obstacle guards took part
    }
  }
}

TEST_CASE("Supervisor-side changes applied by the loop allocate nothing on the loop's side") {
  test::ReactiveRig rig(test::differential_base(), CoordinationMode::priority);
  rig.activate_eight();
  for (int i = 0; i < 10; ++i) rig.cycle();
  NavigationData navi;
  std::vector<Pose2D> path(100);
  navi.path = path;
  navi.localized = true;
  // Prepared outside the counted region: setters copy on the caller's side.
  rig.loop->set_navigation(navi);
  rig.loop->set_lock("pause", true, rig.clock.now());
  const std::size_t before = test::allocations();
  const CycleReport& r = rig.cycle();  // applies the path copy and the lock
  CHECK(test::allocations() == before);
  CHECK(r.coordinator.locked);
}
