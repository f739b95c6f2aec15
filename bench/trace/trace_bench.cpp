// Trace import, read and replay speed. The CARMEN log comes from $TRIPODAL_CARMEN_LOG (e.g. the full
// intel-corrected.log.gz) or, by default, the shipped Intel excerpt. Counters: records/s, and for
// replay "x_realtime": trace duration divided by the wall time to read and deliver every record.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "tripodal/trace/carmen_import.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_replay.hpp"
#include "tripodal/trace/trace_writer.hpp"

namespace {

using namespace tripodal;
using namespace tripodal::trace;

std::filesystem::path carmen_log() {
  if (const char* env = std::getenv("TRIPODAL_CARMEN_LOG"); env != nullptr && *env != '\0') return env;
  return std::filesystem::path(TRIPODAL_SOURCE_DIR) / "tests/data/trace/intel-excerpt.log";
}

std::filesystem::path temp_path(const char* stem) {
  return std::filesystem::temp_directory_path() /
         (std::string("tripodal_bench_") + stem + "_" + std::to_string(::getpid()) + ".trp");
}

// The imported trace, made once and shared by the read and replay benchmarks.
struct Imported {
  std::filesystem::path path = temp_path("replay");
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
};

const Imported& imported() {
  static const Imported i;
  return i;
}

void BM_ImportCarmen(benchmark::State& state) {
  const auto out = temp_path("import");
  std::uint64_t records = 0;
  for (auto _ : state) {
    TraceWriter w(out, TraceWriterOptions{.flush_every_records = 0});
    const auto r = import_carmen_log(carmen_log(), w);
    records += r.laser_scans + r.odometry_readings + r.laser_poses;
    w.close();
  }
  state.counters["records/s"] = benchmark::Counter(static_cast<double>(records), benchmark::Counter::kIsRate);
  std::error_code ec;
  std::filesystem::remove(out, ec);
}
BENCHMARK(BM_ImportCarmen)->Unit(benchmark::kMillisecond);

void BM_ReadTrace(benchmark::State& state) {
  const auto& im = imported();
  std::uint64_t records = 0;
  std::uint64_t bytes = 0;
  for (auto _ : state) {
    TraceReader r(im.path);
    TraceRecord rec;
    while (r.next(rec)) ++records;
    bytes += r.offset();
    benchmark::DoNotOptimize(rec);
  }
  state.counters["records/s"] = benchmark::Counter(static_cast<double>(records), benchmark::Counter::kIsRate);
  state.SetBytesProcessed(static_cast<std::int64_t>(bytes));
}
BENCHMARK(BM_ReadTrace)->Unit(benchmark::kMillisecond);

// A sink that touches every range, as a behavior reading the scan would.
class ConsumingSink final : public TraceSink {
 public:
  double closest = 0;
  std::uint64_t odometry = 0;
  void on_laser(const ChannelInfo&, const LaserScan& scan) override {
    float m = scan.ranges_m.empty() ? 0.0f : scan.ranges_m.front();
    for (const float r : scan.ranges_m) m = r < m ? r : m;
    closest += m;
  }
  void on_odometry(const ChannelInfo&, const OdometryReading& r) override {
    odometry += r.pose.x_m > 0 ? 1 : 0;
  }
};

void BM_ReplayTrace(benchmark::State& state) {
  const auto& im = imported();
  const double duration_s = to_seconds(im.report.last_stamp - im.report.first_stamp);
  std::uint64_t records = 0;
  ConsumingSink sink;
  for (auto _ : state) {
    TraceReplay replay(std::make_unique<TraceReader>(im.path));
    // Driven as a 100 Hz simulated control loop would drive it.
    Time t = replay.start_time();
    while (!replay.finished()) {
      t += std::chrono::milliseconds(10);
      records += replay.advance_to(t, sink);
    }
  }
  benchmark::DoNotOptimize(sink.closest);
  state.counters["records/s"] = benchmark::Counter(static_cast<double>(records), benchmark::Counter::kIsRate);
  state.counters["x_realtime"] = benchmark::Counter(duration_s, benchmark::Counter::kIsIterationInvariantRate);
  state.counters["trace_s"] = duration_s;
}
BENCHMARK(BM_ReplayTrace)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
