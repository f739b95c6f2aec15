// Shared by the dds tests: the domain each test case uses, a unique topic namespace, a CDR writer
// for the golden bytes, and a message of each type with every field set.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "tripodal/dds/messages.hpp"
#include "tripodal/dds/participant.hpp"

namespace tripodal::dds::test {

// ctest runs test cases as separate processes, two at a time: each test case has its own domain
// (base + its number, the base from TRIPODAL_DDS_TEST_DOMAIN or 150) and the process id in its
// topic namespace, so parallel runs never see each other's samples.
inline std::uint32_t test_domain(std::uint32_t number) {
  std::uint32_t base = 150;
  if (const char* env = std::getenv("TRIPODAL_DDS_TEST_DOMAIN")) base = static_cast<std::uint32_t>(std::atoi(env));
  return base + number;
}
inline std::string test_namespace() { return "tripodal_test_" + std::to_string(::getpid()); }

inline ParticipantOptions test_options(std::uint32_t number) {
  ParticipantOptions o;
  o.domain_id = test_domain(number);
  o.participant_lease = std::chrono::milliseconds(1000);
  return o;
}

// XCDR1 little endian as a reader of the rules writes it: the encapsulation header 00 01 00 00
// (CDR_LE, no options), then each primitive aligned to its size counted from the end of the
// header; a string is its length with the NUL, its bytes and the NUL; a sequence its length then
// its elements; a fixed array its elements only.
class CdrWriter {
 public:
  CdrWriter() : bytes_{0x00, 0x01, 0x00, 0x00} {}
  CdrWriter& u8(std::uint8_t v) { return raw(&v, 1); }
  CdrWriter& i8(std::int8_t v) { return raw(&v, 1); }
  CdrWriter& i32(std::int32_t v) { return aligned(&v, 4); }
  CdrWriter& u32(std::uint32_t v) { return aligned(&v, 4); }
  CdrWriter& f32(float v) { return aligned(&v, 4); }
  CdrWriter& f64(double v) { return aligned(&v, 8); }
  CdrWriter& str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size() + 1));
    raw(s.data(), s.size());
    return u8(0);
  }
  CdrWriter& time(const msg::Time& t) { return i32(t.sec).u32(t.nanosec); }
  CdrWriter& header(const msg::Header& h) { return time(h.stamp).str(h.frame_id); }
  CdrWriter& pose(const msg::Pose& p) {
    return f64(p.position.x).f64(p.position.y).f64(p.position.z).f64(p.orientation.x).f64(p.orientation.y)
        .f64(p.orientation.z).f64(p.orientation.w);
  }
  CdrWriter& twist(const msg::Twist& t) {
    return f64(t.linear.x).f64(t.linear.y).f64(t.linear.z).f64(t.angular.x).f64(t.angular.y).f64(t.angular.z);
  }
  template <class V>
  CdrWriter& f64s(const V& values) {
    for (double v : values) f64(v);
    return *this;
  }
  const std::vector<std::uint8_t>& bytes() const { return bytes_; }

 private:
  CdrWriter& aligned(const void* p, std::size_t n) {
    while ((bytes_.size() - 4) % n != 0) bytes_.push_back(0);
    return raw(p, n);
  }
  CdrWriter& raw(const void* p, std::size_t n) {
    // This host is little endian (x86-64, arm64), so memory order is CDR_LE order.
    const auto* b = static_cast<const std::uint8_t*>(p);
    bytes_.insert(bytes_.end(), b, b + n);
    return *this;
  }
  std::vector<std::uint8_t> bytes_;
};

// Samples with every field set to a value of its own, so a field out of place shows.
inline msg::Header sample_header(const char* frame) { return {{1700000123, 456789}, frame}; }

inline msg::PoseWithCovariance sample_pose_cov(double base) {
  msg::PoseWithCovariance p;
  p.pose = {{base + 1.5, base - 2.25, 0.125}, {0.0, 0.0, 0.38268343236, 0.92387953251}};
  for (std::size_t i = 0; i < 36; ++i) p.covariance[i] = base + static_cast<double>(i) * 0.01;
  return p;
}

inline msg::String sample_string() { return {"hello tripodal"}; }
inline msg::Twist sample_twist() { return {{0.35, -0.05, 0.0}, {0.0, 0.0, 0.7}}; }
inline msg::PoseWithCovarianceStamped sample_pose() { return {sample_header("map"), sample_pose_cov(10.0)}; }
inline msg::Odometry sample_odometry() {
  msg::Odometry o{sample_header("odom"), "base_link", sample_pose_cov(3.0), {}};
  o.twist.twist = sample_twist();
  for (std::size_t i = 0; i < 36; ++i) o.twist.covariance[i] = -static_cast<double>(i);
  return o;
}
inline msg::LaserScan sample_scan() {
  msg::LaserScan s{sample_header("laser"), -2.0F, 2.0F, 0.5F, 0.0001F, 0.1F, 0.05F, 30.0F, {}, {}};
  s.ranges = {1.0F, 1.5F, 2.25F, 30.5F, 0.0F, 4.0F, 5.5F, 6.0F, 7.25F};
  s.intensities = {100.0F, 50.0F};
  return s;
}
inline msg::JointState sample_joint_state() {
  return {sample_header("base"), {"wheel_1", "wheel_2", "wheel_3"}, {0.5, -1.25, 2.0}, {3.5, -0.75, 0.0}, {}};
}
inline msg::SimStep sample_sim_step() {
  return {{78, 900000000}, sample_twist(), 7801, {0.5}};
}
inline msg::SimState sample_sim_state() {
  return {{78, 900000000}, 4.5,   -2.25, 1.5, 30.125, 7801, 783,       7802,     2,      0.125,  -1.5,  24.5,
          -1.25,           0.875, 5,     4,   15,     true, {0, 1, 0}, {"neck"}, {0.25}, {-0.5}, {0.5}, {"hello", "help"}};
}
inline msg::OccupancyGrid sample_grid() {
  msg::OccupancyGrid g{sample_header("map"), {{1700000000, 5}, 0.05F, 4, 3, {{-1.0, -2.0, 0.0}, {}}}, {}};
  g.data = {0, 100, -1, 50, 0, 0, 100, -1, 0, 1, 2, 3};
  return g;
}
inline msg::Event sample_event() { return {{12, 34}, "seed001", "laser", "liveliness_lost", "no scan for 0.5 s", 2}; }
inline msg::TaskCommand sample_task() { return {{56, 78}, "seed002", 7, "start", "clean 3211 3212"}; }

}  // namespace tripodal::dds::test
