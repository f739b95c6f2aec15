// Runs a control loop (BhStop -> coordinator -> differential controller on ideal wheels) on its
// own thread at absolute deadlines of the steady clock, then prints period jitter, execution time
// and overruns. Usage: tripodal_loop_jitter [seconds=10] [rate_hz=1000] [fifo_priority=0] [cpu=-1]
#include <cstdio>
#include <cstdlib>
#include <thread>

#include "reactive_rig.hpp"

using namespace tripodal;

int main(int argc, char** argv) {
  const double seconds = argc > 1 ? std::atof(argv[1]) : 10.0;
  const double rate_hz = argc > 2 ? std::atof(argv[2]) : 1000.0;
  const int priority = argc > 3 ? std::atoi(argv[3]) : 0;
  const int cpu = argc > 4 ? std::atoi(argv[4]) : -1;
  if (!(seconds > 0.0) || !(rate_hz > 0.0)) {
    std::fprintf(stderr, "usage: %s [seconds] [rate_hz] [fifo_priority] [cpu]\n", argv[0]);
    return 2;
  }
  ControllerConfig base = test::differential_base();
  base.period = from_seconds(1.0 / rate_hz);
  ResourceTable resources;
  OdometryResource odom("odom");
  resources.add(odom);
  IdealWheelHardware hw(2, base.period);
  CoordinatorConfig cc;
  cc.inputs = {{"BhStop", 0, std::chrono::milliseconds(0)}};
  ControlLoopOptions o;
  o.name = "jitter";
  o.period = base.period;
  ControllerRegistry controllers;
  register_builtin_controllers(controllers);
  BehaviorRegistry behaviors;
  register_behaviors(behaviors);
  ControlLoop loop(o, resources, CBehaviorCoordinator(cc), controllers.create(base, hw));
  loop.set_odometry_output(&odom);
  loop.activate(behaviors.create("BhStop"), {});

  SteadyClock clock;
  LoopRunner runner(loop, clock, LoopTimingOptions{priority, cpu});
  runner.start();
  std::this_thread::sleep_for(std::chrono::duration<double>(seconds));
  runner.stop();

  const LoopStatistics& s = runner.statistics();
  const auto us = [](Duration d) { return static_cast<long long>(d.count() / 1000); };
  const auto expected = static_cast<long long>(seconds * rate_hz);
  std::printf("rate %.0f Hz for %.1f s, SCHED_FIFO %s (asked %d)\n", rate_hz, seconds,
              runner.realtime_granted() ? "granted" : "not granted", priority);
  std::printf("cycles %llu (expected about %lld), overruns %llu, skipped ticks %llu\n",
              static_cast<unsigned long long>(s.cycles()), expected, static_cast<unsigned long long>(s.overruns()),
              static_cast<unsigned long long>(s.skipped_ticks()));
  std::printf("jitter (wake - deadline): mean %.1f us, median %lld us, p99 %lld us, p99.9 %lld us, max %lld us\n",
              s.mean_jitter_us(), us(s.jitter_quantile(0.5)), us(s.jitter_quantile(0.99)), us(s.jitter_quantile(0.999)),
              us(s.max_jitter()));
  std::printf("execution: median %lld us, p99 %lld us, max %lld us\n", us(s.execution_quantile(0.5)),
              us(s.execution_quantile(0.99)), us(s.max_execution()));
  return 0;
}
