// The scores of tools/tripodal/localization_commands.cpp: stamps that cannot measure time give no
// "N s apart" pairs (pairs by travel instead), an empty set is "no pairs", and the whole path is
// scored after the best rigid alignment.
#include <catch2/catch.hpp>
#include <cmath>

#include "tripodal/navi/trajectory_metrics.hpp"

using namespace tripodal;
using namespace tripodal::navi;

namespace {

std::vector<Time> stamps_every(double step_s, std::size_t n, double start_s = 100.0) {
  std::vector<Time> t;
  for (std::size_t i = 0; i < n; ++i) t.push_back(time_from_seconds(start_s + step_s * static_cast<double>(i)));
  return t;
}

// A path along x, 0.5 m per scan, turning slowly.
std::vector<Pose2D> path(std::size_t n) {
  std::vector<Pose2D> p;
  for (std::size_t i = 0; i < n; ++i) p.push_back({0.5 * static_cast<double>(i), 0.0, 0.01 * static_cast<double>(i)});
  return p;
}

}  // namespace

TEST_CASE("trajectory metrics: stamps that cannot measure time are refused with the reason") {
  CHECK(check_stamps(stamps_every(0.2, 50)).usable);
  // belgioioso: every scan stamped alike; freiburg-campus: all 0
  const StampCheck constant = check_stamps(std::vector<Time>(40, time_from_seconds(1018930000.0)));
  CHECK_FALSE(constant.usable);
  CHECK_THAT(constant.why, Catch::Contains("all 40 scans stamped"));
  CHECK_FALSE(check_stamps(std::vector<Time>(40, Time{})).usable);
  // csail: two values (the stamps printed with six digits)
  std::vector<Time> two(40, time_from_seconds(1134860000.0));
  for (std::size_t i = 20; i < two.size(); ++i) two[i] = time_from_seconds(1134870000.0);
  const StampCheck c = check_stamps(two);
  CHECK_FALSE(c.usable);
  CHECK_THAT(c.why, Catch::Contains("38 of 39 steps"));
  // infinite-corridor: small steps, then a wrap to 4.29e9 s
  std::vector<Time> wrapped = stamps_every(0.3, 40, -5.0);
  for (std::size_t i = 30; i < wrapped.size(); ++i) wrapped[i] = time_from_seconds(4294970000.0 + static_cast<double>(i));
  const StampCheck w = check_stamps(wrapped);
  CHECK_FALSE(w.usable);
  CHECK_THAT(w.why, Catch::Contains("a wrap"));
  // fhw: 1.6 s per scan and one pause of 229 s: a hole, not a wrap (its pairs are refused)
  std::vector<Time> paused = stamps_every(1.6, 40);
  for (std::size_t i = 20; i < paused.size(); ++i) paused[i] += from_seconds(229.0);
  CHECK(check_stamps(paused).usable);
  CHECK_FALSE(check_stamps({}).usable);
}

TEST_CASE("trajectory metrics: no time pairs on broken stamps, pairs by travel instead, and no pairs is said") {
  const std::vector<Pose2D> ref = path(60);
  std::vector<Pose2D> est = ref;
  for (Pose2D& p : est) p.x_m *= 1.02;  // 2 % long
  const std::vector<Time> broken(60, Time{});
  const PosePairs by_time = pairs_by_time(broken, 10.0);
  CHECK(by_time.empty());
  const PoseErrors none = relative_errors(est, ref, by_time);
  CHECK(none.empty());
  CHECK(none.format() == "no pairs");  // never "0.000 m"
  // by travel: 5 m is 10 scans of 0.5 m
  const PosePairs by_travel = pairs_by_travel(ref, 5.0);
  REQUIRE(by_travel.size() == 50);
  CHECK(by_travel.front() == std::pair<std::size_t, std::size_t>{0, 10});
  const PoseErrors e = relative_errors(est, ref, by_travel);
  CHECK(e.mean_m() == Approx(0.1).epsilon(0.01));  // 2 % of 5 m
  CHECK_THAT(e.format(), Catch::StartsWith("0.100 m (p95 0.100)") && Catch::EndsWith("50 pairs"));
}

TEST_CASE("trajectory metrics: a pair across a hole in the log is not a pair N s apart") {
  std::vector<Time> t = stamps_every(1.0, 30);
  for (std::size_t i = 15; i < t.size(); ++i) t[i] += from_seconds(40.0);  // 41 s between scans 14 and 15
  REQUIRE(check_stamps(t).usable);
  const PosePairs p = pairs_by_time(t, 10.0);
  for (const auto& [i, j] : p) CHECK(to_seconds(t[j] - t[i]) <= 15.0);
  // 0..4 pair with 10..14, 15..19 with 25..29; 5..14 would pair across the hole and are left out
  CHECK(p.size() == 10);
}

TEST_CASE("trajectory metrics: the whole path after the best rigid alignment ignores the frame, not a bend") {
  const std::vector<Pose2D> ref = path(40);
  // the same path in another frame: aligned, no error; joined at the start, no error either
  std::vector<Pose2D> moved;
  const Pose2D frame{3.0, -2.0, 0.7};
  for (const Pose2D& p : ref) moved.push_back(compose(frame, p));
  CHECK(errors_aligned(moved, ref).mean_m() < 1e-9);
  CHECK(errors_aligned(moved, ref).mean_rad() < 1e-9);
  CHECK(errors_from_start(moved, ref).mean_m() < 1e-9);
  // a start 0.1 rad off: joined at the start the error grows along the path, aligned it does not
  std::vector<Pose2D> bent = ref;
  const Pose2D turn{0.0, 0.0, 0.1};
  for (std::size_t i = 1; i < bent.size(); ++i) bent[i] = compose(turn, ref[i]);
  bent[0] = ref[0];
  CHECK(errors_aligned(bent, ref).mean_m() < 0.1);
  CHECK(errors_from_start(bent, ref).mean_m() > 0.9);
  // a real bend half-way shows in both
  std::vector<Pose2D> kinked = ref;
  for (std::size_t i = 20; i < kinked.size(); ++i) kinked[i] = compose(ref[20], compose(turn, compose(inverse(ref[20]), ref[i])));
  CHECK(errors_aligned(kinked, ref).p95_m() > 0.2);
  CHECK(errors_aligned(std::vector<Pose2D>{}, {}).empty());
}
