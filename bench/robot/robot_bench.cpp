// The whole robot's periods, measured on the PSR-2 demo robot mid-cleaning on the simulator:
//  - BM_Psr2ReactivePeriod: one cycle of its reactive loop (resources, behaviors, coordinator, omni
//    controller) with eight behaviors active — BhCleaning as its net activates it, plus seven more
//    activated on the loop (following the same path, guarding, turning, stopping);
//  - BM_Psr2SequencingPeriod: one period of its sequencing loop (the reactive loop's reports, the
//    five navigation modules, the supervisor stepping PrCleaning's net, the navigation data out),
//    with no replanning (the coverage path is free of unexpected obstacles).
// Manual timing: the simulator's physics and the other loop run between the timed calls.
#include <benchmark/benchmark.h>

#include <chrono>
#include <fstream>
#include <memory>
#include <sstream>

#include "instructions.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"

namespace {

using namespace tripodal;
using Clock = std::chrono::steady_clock;

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";

struct MidCleaning {
  RobotPlugins plugins;
  SimClock clock;
  std::unique_ptr<Robot> robot;

  MidCleaning() {
    register_all(plugins, std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml")));
    std::ifstream in(kConfigs / "robots/psr2.yaml");
    std::stringstream text;
    text << in.rdbuf();
    std::string yaml = text.str();
    const std::string four = "behaviors: [BhAutoMove, BhCleaning, BhCleaningTwoWheel, BhGlobalLocalization]";
    yaml.replace(yaml.find(four), four.size(),
                 "behaviors: [BhAutoMove, BhCleaning, BhCleaningTwoWheel, BhGlobalLocalization, BhAvoidObstacle, BhBackOff, "
                 "BhRotateInPlace, BhStop]");
    robot = Robot::assemble(load_robot_profile_from_string(yaml, "psr2-bench.yaml", kConfigs / "robots"), plugins, clock);
    if (!robot->command("clean the room 3211").accepted) throw std::runtime_error("task refused");
    while (!robot->behavior_active("BhCleaning")) robot->run_for(std::chrono::milliseconds(100));
    robot->run_for(std::chrono::seconds(20));
  }

  // Seven more behaviors on the loop (the net keeps BhCleaning running); one that finishes is
  // activated again (outside the timed region).
  struct Extra {
    const char* type;
    ParameterValues params;
    BehaviorHandle handle;
  };
  std::vector<Extra> extras{
      {"BhAutoMove", {{"blocked_timeout_s", Value{3600.0}}}, {}},
      {"BhCleaningTwoWheel", {{"blocked_timeout_s", Value{3600.0}}}, {}},
      {"BhGlobalLocalization", {{"timeout_s", Value{3600.0}}}, {}},
      {"BhAvoidObstacle", {}, {}},
      {"BhBackOff", {{"distance_m", Value{9.0}}, {"speed_m_s", Value{0.05}}}, {}},
      {"BhRotateInPlace", {{"angle_rad", Value{90.0}}}, {}},
      {"BhStop", {}, {}},
  };
  void keep_seven_more() {
    ControlLoop& loop = robot->behavior_loop();
    for (Extra& e : extras) {
      const auto status = loop.status(e.handle);
      if (status && *status == BehaviorStatus::running) continue;
      e.handle = loop.activate(plugins.behaviors.create(e.type), e.params, e.type);
    }
  }
};

void BM_Psr2ReactivePeriod(benchmark::State& state) {
  MidCleaning m;
  m.keep_seven_more();
  ControlLoop& loop = m.robot->behavior_loop();
  const Duration period = loop.period();
  Time t = m.clock.now();
  std::int64_t i = 0;
  std::uint32_t fewest_active = 1000;
  (void)loop.step(t);  // the activations join
  for (auto _ : state) {
    if (i % 100 == 0) m.keep_seven_more();
    t += period;
    m.clock.set(t);
    m.robot->hardware()->advance_to(t);
    if (i++ % 5 == 0) m.robot->step_sequencing();  // 50 ms sequencing, 10 ms reactive
    const auto a = Clock::now();
    const CycleReport& r = loop.step(t);
    const auto b = Clock::now();
    if (m.robot->behavior_active("BhCleaning")) fewest_active = std::min(fewest_active, r.active_behaviors);
    state.SetIterationTime(std::chrono::duration<double>(b - a).count());
  }
  state.counters["fewest_active_behaviors"] = fewest_active;
}
BENCHMARK(BM_Psr2ReactivePeriod)->UseManualTime()->Unit(benchmark::kMicrosecond)->Iterations(20000)->Repetitions(5)
    ->ReportAggregatesOnly(true);

void BM_Psr2SequencingPeriod(benchmark::State& state) {
  MidCleaning m;
  ControlLoop& loop = m.robot->behavior_loop();
  const Duration period = loop.period();
  Time t = m.clock.now();
  for (auto _ : state) {
    for (int k = 0; k < 5; ++k) {  // the reactive periods between two sequencing periods
      t += period;
      m.clock.set(t);
      m.robot->hardware()->advance_to(t);
      (void)loop.step(t);
    }
    const auto a = Clock::now();
    m.robot->step_sequencing();
    const auto b = Clock::now();
    state.SetIterationTime(std::chrono::duration<double>(b - a).count());
  }
  state.counters["cleaning"] = m.robot->behavior_active("BhCleaning") ? 1 : 0;
}
BENCHMARK(BM_Psr2SequencingPeriod)->UseManualTime()->Unit(benchmark::kMicrosecond)->Iterations(4000)->Repetitions(5)
    ->ReportAggregatesOnly(true);

// The instruction-count guard's twins (bench/instructions.yaml): callgrind counts inside
// ControlLoop::step and Robot::step_sequencing alone, as the manual timing does.
[[maybe_unused]] const bool kPeriodTwins[] = {
    tripodal::bench::register_instruction_twin("BM_Psr2ReactivePeriod", BM_Psr2ReactivePeriod),
    tripodal::bench::register_instruction_twin("BM_Psr2SequencingPeriod", BM_Psr2SequencingPeriod),
};

}  // namespace

BENCHMARK_MAIN();
