// Proves that the whole PSR-2 demo robot's reactive loop allocates nothing in steady state: the
// robot of configs/robots/psr2.yaml on the simulator, mid-cleaning (BhCleaning following the
// coverage planner's path, the laser and bumpers read every cycle, the omni controller driving the
// wheels), counted with a replaced global operator new over 10,000 reactive periods. The sequencing
// loop (planning, the supervisor) and the simulator may allocate: only the loop's cycles are counted.
// The same on the wall-clock runtime (Robot::start): the behavior loop's own thread, counted per
// thread, whole cycles (the simulator's physics and the resource snapshot's hand-over included).
// Its own executable, so the replacement affects no other suite.
#include <atomic>
#include <catch2/catch.hpp>
#include <memory>
#include <thread>

#include "../support/counting_new.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/navi/planning_modules.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

using namespace tripodal;

TEST_CASE("The PSR-2 robot's reactive loop allocates nothing over 10,000 periods mid-cleaning", "[robot][alloc]") {
  const std::filesystem::path configs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";
  RobotPlugins plugins;
  register_all(plugins, std::make_shared<sim::World>(sim::load_world(configs / "worlds/workspace.yaml")));
  SimClock clock;
  const auto robot = Robot::assemble(load_robot_profile(configs / "robots/psr2.yaml"), plugins, clock);
  REQUIRE(robot->command("clean the room 3211").accepted);
  // Into the first section's coverage, past the first seconds of it.
  while (!robot->behavior_active("BhCleaning") && clock.now() < time_from_seconds(300)) robot->run_for(std::chrono::milliseconds(100));
  REQUIRE(robot->behavior_active("BhCleaning"));
  robot->run_for(std::chrono::seconds(20));

  // The same order as Robot::run_until (hardware, sequencing when due, then the reactive loop),
  // with only the reactive cycles counted.
  ControlLoop& loop = robot->behavior_loop();
  auto& sim = dynamic_cast<sim::SimHardware&>(*robot->hardware()).simulator();
  const auto* coverage = robot->module<navi::CCoveragePlanner>();
  REQUIRE(coverage->progress().count("A") == 1);
  const double progress_before = coverage->progress().at("A").done_m;
  const double distance_before = sim.distance_m();
  const std::uint64_t cycles_before = loop.cycles();
  const Duration period = loop.period();
  const auto sequencing_every = from_seconds(0.05) / period;  // the profile's sequencing period
  std::size_t in_loop = 0;
  Time t = clock.now();
  for (int i = 0; i < 10'000; ++i) {
    t += period;
    clock.set(t);
    robot->hardware()->advance_to(t);
    if (i % sequencing_every == 0) robot->step_sequencing();
    const std::size_t before = test::allocations();
    (void)loop.step(t);
    in_loop += test::allocations() - before;
  }
  CHECK(in_loop == 0);
  CHECK(loop.cycles() - cycles_before == 10'000);
  // The cycles did real work: the robot kept cleaning along its path.
  CHECK(robot->behavior_active("BhCleaning"));
  CHECK(sim.distance_m() - distance_before > 5.0);  // 100 s at up to 0.3 m/s
  CHECK(coverage->progress().at("A").done_m > progress_before + 5.0);
  CHECK(loop.last_cycle().controller_status != ControlStatus::hardware_fault);
}

namespace {

// Polled by the behavior loop at the start of every cycle, on the loop's own thread: the
// allocations that thread made since the previous poll are one whole cycle of the wall-clock
// runtime — the hardware advanced, the loop's step, the hand-over of the resources to the
// sequencing layer's snapshot.
class AllocationProbe final : public BumperResource {
 public:
  static const ModuleManifest& manifest_of() {
    static const ModuleManifest m = [] {
      ModuleManifest x = resource_manifest<BumperReading>();
      x.name = "AllocationProbe";
      return x;
    }();
    return m;
  }
  explicit AllocationProbe(std::string name) : BumperResource(std::move(name), Duration{0}, manifest_of()) {}
  std::atomic<bool> armed{false};
  std::atomic<std::size_t> counted{0};
  std::atomic<std::size_t> cycles{0};

 protected:
  void on_poll(Time) noexcept override {
    const std::size_t now = test::thread_allocations();
    if (armed.load(std::memory_order_acquire)) {
      if (primed_) {
        counted.fetch_add(now - last_, std::memory_order_relaxed);
        cycles.fetch_add(1, std::memory_order_release);
      }
      primed_ = true;
    } else {
      primed_ = false;
    }
    last_ = now;
  }

 private:
  bool primed_ = false;
  std::size_t last_ = 0;
};

}  // namespace

TEST_CASE("The PSR-2 robot's reactive thread allocates nothing mid-cleaning on the wall-clock runtime",
          "[robot][alloc][threads]") {
  // The same robot on its own threads (Robot::start) at 10 times real time: the allocations of the
  // behavior loop's thread counted over 2,000 whole cycles, the simulator's physics and the
  // snapshot's hand-over included; the sequencing thread allocates as it likes meanwhile.
  const std::filesystem::path configs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";
  RobotPlugins plugins = builtin_plugins(std::make_shared<sim::World>(sim::load_world(configs / "worlds/workspace.yaml")));
  AllocationProbe* probe = nullptr;
  plugins.resources.add(AllocationProbe::manifest_of(), [&probe](const ResourceConfig& c) {
    auto p = std::make_unique<AllocationProbe>(c.name);
    probe = p.get();
    return p;
  });
  RobotProfile profile = load_robot_profile(configs / "robots/psr2.yaml");
  ModuleEntry entry;
  entry.kind = ModuleKind::resource;
  entry.name = "probe";
  entry.type = "AllocationProbe";
  profile.resources.push_back(entry);
  ScaledClock clock(10.0);
  const auto robot = Robot::assemble(profile, plugins, clock);
  REQUIRE(probe != nullptr);
  REQUIRE(robot->command("clean the room 3211").accepted);
  std::atomic<bool> cleaning{false};
  RealtimeOptions ro;
  ro.after_sequencing = [&](Time) { cleaning.store(robot->behavior_active("BhCleaning")); };
  robot->start(ro);
  auto wait_until = [](const auto& done, std::chrono::seconds limit) {
    const auto end = std::chrono::steady_clock::now() + limit;
    while (!done() && std::chrono::steady_clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(10));
    return done();
  };
  const bool reached = wait_until([&] { return cleaning.load(); }, std::chrono::seconds(120));
  // Past the first seconds of the section (every buffer at its steady size), then counted.
  const Time counted_from = clock.now() + std::chrono::seconds(20);
  wait_until([&] { return clock.now() >= counted_from; }, std::chrono::seconds(60));
  probe->armed.store(true, std::memory_order_release);
  const bool counted =
      wait_until([&] { return probe->cycles.load(std::memory_order_acquire) >= 2000; }, std::chrono::seconds(120));
  probe->armed.store(false, std::memory_order_release);
  const bool still_cleaning = cleaning.load();
  robot->stop();
  REQUIRE(reached);
  REQUIRE(counted);
  CHECK(probe->counted.load() == 0);
  CHECK(still_cleaning);
  CHECK(dynamic_cast<sim::SimHardware&>(*robot->hardware()).simulator().distance_m() > 5.0);
}
