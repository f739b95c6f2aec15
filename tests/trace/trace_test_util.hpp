// Helpers shared by the trace tests: temporary files and one sample reading of every kind.
#pragma once

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include "tripodal/trace/trace_record.hpp"

namespace tripodal::trace::test {

/// A file path in the temporary directory, removed when the object goes out of scope.
class TempFile {
 public:
  explicit TempFile(const std::string& stem) {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("tripodal_" + stem + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
  }
  ~TempFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  [[nodiscard]] std::string str() const { return path_.string(); }

 private:
  std::filesystem::path path_;
};

inline std::vector<std::uint8_t> read_all(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(f), std::istreambuf_iterator<char>()};
}

inline void write_all(const std::filesystem::path& p, const std::vector<std::uint8_t>& bytes, std::size_t n) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(n));
}

inline LaserScan sample_scan(Time stamp, std::size_t beams) {
  LaserScan s;
  s.stamp = stamp;
  s.angle_min_rad = -2.0943951023931953;
  s.angle_max_rad = 2.0943951023931953;
  s.angle_increment_rad = (s.angle_max_rad - s.angle_min_rad) / static_cast<double>(beams - 1);
  s.time_increment_s = 1.7361e-5;
  s.scan_time_s = 0.1;
  s.range_min_m = 0.02;
  s.range_max_m = 30.0;
  for (std::size_t i = 0; i < beams; ++i) {
    s.ranges_m.push_back(0.5f + 0.0137f * static_cast<float>(i));
    s.intensities.push_back(static_cast<float>(i % 7) * 100.25f);
  }
  s.ranges_m[1] = INFINITY;  // "no return" as ROS drivers write it survives the round trip
  return s;
}

/// One record of every kind, stamped 1 ms apart starting at `t0`.
inline std::vector<RecordData> one_of_each(Time t0) {
  using std::chrono::milliseconds;
  std::vector<RecordData> v;
  v.emplace_back(sample_scan(t0, 541));
  v.emplace_back(OdometryReading{t0 + milliseconds(1), Pose2D{1.5, -2.25, 0.3}, Twist2D{0.4, 0.0, -0.2}});
  v.emplace_back(SonarReading{t0 + milliseconds(2), 0.26, 0.15, 5.0, {0.3f, 1.25f, 4.75f, 5.5f}});
  v.emplace_back(InfraredReading{t0 + milliseconds(3), {0, 1, 0}, {0.12f, 0.8f}});
  v.emplace_back(BumperReading{t0 + milliseconds(4), 3, 0b101});
  v.emplace_back(BatteryReading{t0 + milliseconds(5), 25.2, -1.75, 0.83, true});
  v.emplace_back(GyroReading{t0 + milliseconds(6), 0.0123, -3.1});
  v.emplace_back(CommandRecord{t0 + milliseconds(7), Twist2D{0.25, 0.0, 0.5}, "BhAvoidObstacle"});
  v.emplace_back(EventRecord{t0 + milliseconds(8), "bumper_hit"});
  return v;
}

}  // namespace tripodal::trace::test
