// Replay speed of a CARMEN log through the obstacle-avoidance behavior: the trace is read and
// published into laser and odometry resources on a simulated 20 Hz clock, and every period
// BhAvoidObstacle (full step: clearance over every beam, velocity envelope) guards a cruising
// command in a CBehaviorCoordinator. The log is $TRIPODAL_CARMEN_LOG (e.g. the full
// intel-corrected.log.gz) or, by default, the shipped Intel excerpt. Counter "x_realtime": trace
// duration divided by the wall time of the whole replay.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "tripodal/behaviors/behavior_coordinator.hpp"
#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/testing/behavior_harness.hpp"
#include "tripodal/trace/carmen_import.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_replay.hpp"
#include "tripodal/trace/trace_writer.hpp"

namespace {

using namespace tripodal;
using namespace tripodal::trace;
using namespace std::chrono_literals;

constexpr Duration kPeriod = 50ms;

std::filesystem::path carmen_log() {
  if (const char* env = std::getenv("TRIPODAL_CARMEN_LOG"); env != nullptr && *env != '\0') return env;
  return std::filesystem::path(TRIPODAL_SOURCE_DIR) / "tests/data/trace/intel-excerpt.log";
}

struct Imported {
  std::filesystem::path path = std::filesystem::temp_directory_path() /
                               ("tripodal_bench_behavior_" + std::to_string(::getpid()) + ".trp");
  CarmenImportReport report;
  Imported() {
    TraceWriter w(path, TraceWriterOptions{.flush_every_records = 0});
    report = import_carmen_log(carmen_log(), w);
  }
  ~Imported() {
    std::error_code ec;
    std::filesystem::remove(path, ec);
  }
  Imported(const Imported&) = delete;
  Imported& operator=(const Imported&) = delete;
  [[nodiscard]] double duration_s() const { return to_seconds(report.last_stamp - report.first_stamp); }
};

const Imported& imported() {
  static const Imported i;
  return i;
}

ParameterValues avoid_params() {
  return {{"stop_distance_m", Value{0.3}}, {"slow_distance_m", Value{1.0}}, {"max_speed_m_s", Value{0.5}},
          {"robot_radius_m", Value{0.25}}};
}

// Publishes replayed readings into the two resources the behavior reads.
class ResourceSink final : public TraceSink {
 public:
  LaserResource laser{"front_laser", Duration{0}};
  OdometryResource odom{"odom", Duration{0}};
  void on_laser(const ChannelInfo&, const LaserScan& s) override { laser.publish(s); }
  void on_odometry(const ChannelInfo& c, const OdometryReading& r) override {
    if (c.name == "odom") odom.publish(r);
  }
};

// The reactive loop's work per period, without the test kit's recording.
void BM_ReplayAvoidObstacle(benchmark::State& state) {
  const Imported& im = imported();
  std::uint64_t steps = 0, scans = 0;
  double vx_sum = 0.0;
  for (auto _ : state) {
    ResourceSink sink;
    ResourceTable table;
    table.add(sink.laser);
    table.add(sink.odom);
    NavigationData navi;
    CBehaviorCoordinator coordinator;
    const InputId cruise = coordinator.add_input({.name = "cruise", .priority = 1});
    const InputId safety = coordinator.add_input({.name = "BhAvoidObstacle", .priority = 100, .role = InputRole::safety});
    BhAvoidObstacle avoid;
    TraceReplay replay(std::make_unique<TraceReader>(im.path));
    BehaviorContext ctx{.now = replay.start_time(), .period = kPeriod, .resources = &table, .navi = &navi, .base = {}};
    avoid.activate(avoid_params(), ctx);
    for (Time t = replay.start_time(); !replay.finished(); t += kPeriod) {
      (void)replay.advance_to(t, sink);
      ctx.now = t;
      (void)avoid.step(ctx);
      coordinator.submit(cruise, Twist2D{0.5, 0.0, 0.0}, t);
      coordinator.submit_envelope(safety, *avoid.envelope(), t);
      vx_sum += coordinator.update(t).command.vx_m_s;
      ++steps;
    }
    scans += sink.laser.sequence();
  }
  benchmark::DoNotOptimize(vx_sum);
  state.counters["steps/s"] = benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
  state.counters["scans"] = static_cast<double>(scans) / static_cast<double>(state.iterations());
  state.counters["x_realtime"] = benchmark::Counter(im.duration_s(), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["trace_s"] = im.duration_s();
}
BENCHMARK(BM_ReplayAvoidObstacle)->Unit(benchmark::kMillisecond);

// The same through the test kit: BehaviorHarness (first pass over the file, recording of every
// step with the clearance along the command) as a Catch2 test runs it.
void BM_HarnessAvoidObstacle(benchmark::State& state) {
  const Imported& im = imported();
  std::uint64_t steps = 0;

  // A cruising behavior for the harness (BhAvoidObstacle alone commands nothing).
  class Cruise final : public CBehavior {
   public:
    static const ModuleManifest& static_manifest() {
      static const ModuleManifest m{"BhCruise", Layer::reactive, ModuleKind::behavior, "constant forward command", {}, {"cmd_vel"}, {}};
      return m;
    }

   protected:
    const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
    void on_activate(const ParameterSet&, const BehaviorContext&) override {}
    std::optional<Twist2D> on_step(const BehaviorContext&) noexcept override { return Twist2D{0.5, 0.0, 0.0}; }
  };
  for (auto _ : state) {
    tripodal::testing::BehaviorHarness h({.period = kPeriod});
    h.load_trace(im.path);
    h.attach(std::make_unique<Cruise>(), {}, {.priority = 1});
    h.attach(std::make_unique<BhAvoidObstacle>(), avoid_params(), {.priority = 100, .role = InputRole::safety});
    steps += h.run().steps().size();
  }
  state.counters["steps/s"] = benchmark::Counter(static_cast<double>(steps), benchmark::Counter::kIsRate);
  state.counters["x_realtime"] = benchmark::Counter(im.duration_s(), benchmark::Counter::kIsIterationInvariantRate);
  state.counters["trace_s"] = im.duration_s();
}
BENCHMARK(BM_HarnessAvoidObstacle)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
