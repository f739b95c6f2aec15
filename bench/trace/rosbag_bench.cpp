// rosbag2 read speed: an MCAP bag of 2,000 LaserScans (720 beams) and 20,000 Odometry messages,
// written once in memory with zstd chunks and uncompressed; counters MB/s (of the file) and
// messages/s. BM_McapRead walks the records (chunks expanded, CRCs checked); BM_BagToTrace also
// decodes the CDR and writes the trace records, as `tripodal trace convert` does.
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "tripodal/trace/cdr.hpp"
#include "tripodal/trace/mcap.hpp"
#include "tripodal/trace/rosbag.hpp"

namespace {

using namespace tripodal::trace;

constexpr int kScans = 2000;
constexpr int kOdomPerScan = 10;

std::string make_bag(mcap::Compression compression) {
  std::stringbuf buffer;
  mcap::WriterOptions options;
  options.compression = compression;
  mcap::Writer w(std::make_unique<std::ostream>(&buffer), "bench.mcap", options);
  const auto scan_ch = w.add_channel("/scan", "cdr", w.add_schema("sensor_msgs/msg/LaserScan", "ros2msg", ""));
  const auto odom_ch = w.add_channel("/odom", "cdr", w.add_schema("nav_msgs/msg/Odometry", "ros2msg", ""));
  ros::LaserScan scan;
  scan.header.frame_id = "laser";
  scan.angle_min = -3.14f;
  scan.angle_increment = 6.28f / 720;
  scan.range_max = 30.0f;
  scan.ranges.resize(720);
  ros::Odometry odom;
  odom.header.frame_id = "odom";
  odom.child_frame_id = "base_link";
  std::uint64_t t = 1'000'000'000;
  for (int i = 0; i < kScans; ++i) {
    for (std::size_t b = 0; b < scan.ranges.size(); ++b) scan.ranges[b] = 1.0f + static_cast<float>((b * 7 + i) % 500) * 0.01f;
    scan.header.stamp = {static_cast<std::int32_t>(t / 1'000'000'000), static_cast<std::uint32_t>(t % 1'000'000'000)};
    w.write(scan_ch, t, t, ros::encode_cdr(scan));
    for (int k = 0; k < kOdomPerScan; ++k) {
      t += 10'000'000;
      odom.header.stamp = {static_cast<std::int32_t>(t / 1'000'000'000), static_cast<std::uint32_t>(t % 1'000'000'000)};
      odom.pose.position.x = 0.001 * static_cast<double>(i * kOdomPerScan + k);
      w.write(odom_ch, t, t, ros::encode_cdr(odom));
    }
  }
  w.close();
  return buffer.str();
}

const std::string& bag(mcap::Compression compression) {
  static const std::string none = make_bag(mcap::Compression::kNone);
  static const std::string zstd = make_bag(mcap::Compression::kZstd);
  return compression == mcap::Compression::kNone ? none : zstd;
}

void BM_McapRead(benchmark::State& state) {
  const auto compression = static_cast<mcap::Compression>(state.range(0));
  const std::string& bytes = bag(compression);
  std::int64_t messages = 0;
  for (auto _ : state) {
    mcap::Reader reader(std::make_unique<std::istringstream>(bytes), "bench.mcap");
    mcap::Record r;
    while (reader.next(r)) messages += r.opcode == mcap::Opcode::kMessage ? 1 : 0;
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(bytes.size()) * state.iterations());
  state.counters["messages/s"] = benchmark::Counter(static_cast<double>(messages), benchmark::Counter::kIsRate);
  state.counters["file_MB"] = static_cast<double>(bytes.size()) / 1e6;
  state.SetLabel(compression == mcap::Compression::kNone ? "uncompressed" : "zstd");
}
BENCHMARK(BM_McapRead)->Arg(static_cast<int>(mcap::Compression::kNone))->Arg(static_cast<int>(mcap::Compression::kZstd))
    ->Unit(benchmark::kMillisecond);

void BM_BagToTrace(benchmark::State& state) {
  const auto compression = static_cast<mcap::Compression>(state.range(0));
  const std::string& bytes = bag(compression);
  const auto path = std::filesystem::temp_directory_path() / ("tripodal_bench_bag_" + std::to_string(::getpid()) + ".mcap");
  {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  }
  std::int64_t messages = 0;
  for (auto _ : state) {
    BagImportReport report;
    auto reader = read_bag(path, {}, &report);
    messages += static_cast<std::int64_t>(report.messages);
    benchmark::DoNotOptimize(reader);
  }
  std::filesystem::remove(path);
  state.SetBytesProcessed(static_cast<std::int64_t>(bytes.size()) * state.iterations());
  state.counters["messages/s"] = benchmark::Counter(static_cast<double>(messages), benchmark::Counter::kIsRate);
  state.SetLabel(compression == mcap::Compression::kNone ? "uncompressed" : "zstd");
}
BENCHMARK(BM_BagToTrace)->Arg(static_cast<int>(mcap::Compression::kNone))->Arg(static_cast<int>(mcap::Compression::kZstd))
    ->Unit(benchmark::kMillisecond);

}  // namespace
BENCHMARK_MAIN();
