// Proves that one reactive cycle in steady state allocates nothing: resources, eight behaviors,
// the coordinator and a controller, counted with a replaced global operator new over many
// cycles. Its own executable, so the replacement affects no other suite.
#include <catch2/catch.hpp>

#include "../support/counting_new.hpp"
#include "reactive_rig.hpp"
#include "tripodal/behaviors/gesture_behaviors.hpp"
#include "tripodal/board/actuator_behaviors.hpp"

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

TEST_CASE("Fusing and writing command channels allocates nothing (joint, lamp, fog, LCD text, both modes)") {
  for (const CoordinationMode mode : {CoordinationMode::priority, CoordinationMode::weighted_sum}) {
    INFO(to_string(mode));
    JointResource neck("neck");
    neck.publish(JointReading{Time{}, 0.0, 0.0, 0.0, -1.0, 1.0});
    ResourceTable resources;
    resources.add(neck);
    CoordinatorConfig cc;
    cc.mode = mode;
    cc.inputs = {{"BhNeckGesture", 4, Duration{0}},
                 {"BhUvLamp", 3, Duration{0}},
                 {"BhAtomize", 2, Duration{0}},
                 {"BhLcdText", 1, Duration{0}}};
    const Duration none{0};
    cc.channels = {ChannelSpec{"neck", ChannelType::joint_position, ChannelValue::of(0.0), true, none, -1.0, 1.0, "rad", ""},
                   ChannelSpec{"uv_lamp", ChannelType::digital, ChannelValue::of(false), false, none, 0.0, 0.0, "", ""},
                   ChannelSpec{"atomizer", ChannelType::analog, ChannelValue::of(0.0), false, none, 0.0, 1.0, "", ""},
                   ChannelSpec{"atomizer_fan", ChannelType::digital, ChannelValue::of(false), false, none, 0.0, 0.0, "", ""},
                   ChannelSpec{"lcd", ChannelType::text, ChannelValue::of_text(""), false, none, 0.0, 0.0, "", ""}};
    CommandChannels hardware;
    for (const ChannelSpec& c : cc.channels) hardware.add(c);
    ControlLoop loop(ControlLoopOptions{}, resources, CBehaviorCoordinator(cc), nullptr);
    loop.set_command_output(&hardware);
    loop.activate(std::make_unique<BhNeckGesture>(), {{"angle_deg", Value{20.0}}, {"timeout_s", Value{1000.0}}});
    loop.activate(std::make_unique<board::BhUvLamp>(), {});
    loop.activate(std::make_unique<board::BhAtomize>(), {});
    loop.activate(std::make_unique<board::BhLcdText>(), {{"text", Value{std::string("UV ON - KEEP OUT")}}});
    Time now{};
    for (int i = 0; i < 10; ++i) loop.step(now += std::chrono::milliseconds(10));
    const std::size_t before = test::allocations();
    for (int i = 0; i < 10'000; ++i) loop.step(now += std::chrono::milliseconds(10));
    CHECK(test::allocations() - before == 0);
    CHECK(loop.last_cycle().active_behaviors == 4);
    CHECK(hardware.value(0).number > 0.3);
    CHECK(hardware.value(1).on());
    CHECK(hardware.value(2).number == 1.0);
    CHECK(hardware.value(4).text() == "UV ON - KEEP OUT");
    CHECK(hardware.writes(4) == 10'010);
  }
}
