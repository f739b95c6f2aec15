#include <zlib.h>

#include <catch2/catch.hpp>
#include <numbers>
#include <sstream>

#include "trace_test_util.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/trace/carmen_import.hpp"
#include "tripodal/trace/trace_reader.hpp"

using namespace tripodal;
using namespace tripodal::trace;
using namespace tripodal::trace::test;

namespace {

const std::string kExcerpt = std::string(TRIPODAL_TEST_DATA_DIR) + "/trace/intel-excerpt.log";

struct Imported {
  CarmenImportReport report;
  std::vector<LaserScan> scans;
  std::vector<OdometryReading> odometry;
  std::vector<OdometryReading> laser_poses;
};

Imported import_and_read(const std::filesystem::path& log, const CarmenImportOptions& options = {}) {
  TempFile out("carmen");
  Imported result;
  {
    TraceWriter w(out.path());
    result.report = import_carmen_log(log, w, options);
  }
  TraceReader r(out.path());
  TraceRecord rec;
  while (r.next(rec)) {
    const auto& name = r.channel(rec.channel).name;
    if (name == "front_laser") result.scans.push_back(std::get<LaserScan>(rec.data));
    else if (name == "odom") result.odometry.push_back(std::get<OdometryReading>(rec.data));
    else if (name == "laser_pose") result.laser_poses.push_back(std::get<OdometryReading>(rec.data));
    else FAIL("unexpected channel " << name);
  }
  CHECK(r.state() == ReadState::kEnd);
  return result;
}

Imported import_text(const std::string& text, const CarmenImportOptions& options = {}) {
  TempFile log("carmen_text");
  {
    std::ofstream f(log.path());
    f << text;
  }
  return import_and_read(log.path(), options);
}

CarmenImportOptions as_logged() {
  CarmenImportOptions o;
  o.recover_anchored_odometry = false;
  return o;
}

// A FLASER line of 4 beams at 2 m with the given laser pose and stamp (odom fields = the pose, as
// in the corrected logs).
std::string flaser(const Pose2D& p, double stamp) {
  std::ostringstream s;
  s.precision(9);
  s << "FLASER 4 2 2 2 2 " << p.x_m << ' ' << p.y_m << ' ' << p.theta_rad << ' ' << p.x_m << ' ' << p.y_m << ' '
    << p.theta_rad << ' ' << stamp << " host " << stamp << "\n";
  return s.str();
}

std::string odom(const Pose2D& p, double stamp) {
  std::ostringstream s;
  s.precision(9);
  s << "ODOM " << p.x_m << ' ' << p.y_m << ' ' << p.theta_rad << " 0 0 0 " << stamp << " host " << stamp << "\n";
  return s.str();
}

Pose2D lerp(const Pose2D& a, const Pose2D& b, double f) {
  return {a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m), a.theta_rad + f * (b.theta_rad - a.theta_rad)};
}

bool near(const Pose2D& a, const Pose2D& b, double tol = 1e-6) {
  return std::abs(a.x_m - b.x_m) < tol && std::abs(a.y_m - b.y_m) < tol &&
         std::abs(wrap_angle(a.theta_rad - b.theta_rad)) < tol;
}

}  // namespace

TEST_CASE("the Intel excerpt imports with the counts of its lines") {
  const Imported im = import_and_read(kExcerpt, as_logged());
  // grep -c '^FLASER' / '^ODOM' on the excerpt: 30 and 659.
  CHECK(im.report.laser_scans == 30);
  CHECK(im.report.odometry_readings == 659);
  CHECK(im.scans.size() == 30);
  CHECK(im.odometry.size() == 659);
  CHECK(im.laser_poses.size() == 30);
  CHECK(im.report.lines == 722);
  CHECK(im.report.comments == 2);
  CHECK(im.report.params.size() == 2);
  CHECK(im.report.params[0] == std::pair<std::string, std::string>{"robot_frontlaser_offset", "0.0"});
  CHECK(im.report.skipped.at("NEFF") == 29);
  // Each FLASER is followed by an ODOM stamped 0 (the corrected pose): those step backwards.
  CHECK(im.report.backwards_steps == 117);
  CHECK(im.report.odometry_echoes == 29);
  CHECK(im.report.odometry == CarmenOdometry::kAnchored);
  CHECK(im.report.first_stamp == time_from_seconds(0.000246));
}

TEST_CASE("FLASER beams follow CARMEN's angle convention and keep their ranges") {
  const Imported im = import_and_read(kExcerpt);
  REQUIRE(im.scans.size() >= 2);
  const LaserScan& s = im.scans[1];  // line 187 of the excerpt
  REQUIRE(s.ranges_m.size() == 180);
  // 180 beams: 1 degree apart from -90 degrees, the last at +89 degrees (CARMEN readlog.c).
  CHECK(s.angle_min_rad == Approx(-std::numbers::pi / 2));
  CHECK(s.angle_increment_rad == Approx(std::numbers::pi / 180));
  CHECK(s.angle_max_rad == Approx(89.0 * std::numbers::pi / 180));
  CHECK(s.range_max_m == 80.0);
  CHECK(s.intensities.empty());
  CHECK(s.ranges_m[0] == 1.72f);
  CHECK(s.ranges_m[1] == 1.66f);
  CHECK(s.ranges_m[90] == 1.15f);
  CHECK(s.ranges_m[179] == 2.15f);
  CHECK(s.stamp == time_from_seconds(35.1051));
  CHECK(im.laser_poses[1].pose == Pose2D{0.68231, -0.100086, -0.938803});
  CHECK(im.laser_poses[1].stamp == s.stamp);
  // 81.83 m readings (no return on the Intel SICK) lie beyond range_max: "no return" by contract.
  const LaserScan& first = im.scans[0];
  CHECK(first.ranges_m[110] == 81.83f);
  CHECK(first.ranges_m[110] > first.range_max_m);
}

TEST_CASE("ODOM lines become odometry readings with twist, backwards stamps are clamped") {
  const Imported im = import_and_read(kExcerpt, as_logged());
  // Line 173: ODOM ... 33.1085; line 174: ODOM 0.698035 -0.0132843 -0.460915 0 0 0 32.9068 (backwards);
  // line 175: FLASER at 32.9068; line 176: ODOM 0.600266 -0.0320327 -0.354665 0 0 0 0 (backwards).
  // All three are clamped to 33.1085, the latest stamp seen before them.
  const auto it = std::find_if(im.odometry.begin(), im.odometry.end(),
                               [](const auto& o) { return o.pose.x_m == 0.600266; });
  REQUIRE(it != im.odometry.end());
  CHECK(it->stamp == time_from_seconds(33.1085));
  CHECK(std::prev(it)->pose == Pose2D{0.698035, -0.0132843, -0.460915});
  CHECK(std::prev(it)->stamp == time_from_seconds(33.1085));
  CHECK(im.scans[0].stamp == time_from_seconds(33.1085));
  for (std::size_t i = 1; i < im.odometry.size(); ++i) CHECK(im.odometry[i].stamp >= im.odometry[i - 1].stamp);

  const Imported t = import_text("ODOM 1 2 0.5 0.3 -0.1 0 10.5 host 10.5\n");
  REQUIRE(t.odometry.size() == 1);
  CHECK(t.odometry[0].pose == Pose2D{1, 2, 0.5});
  CHECK(t.odometry[0].twist == Twist2D{0.3, 0.0, -0.1});
  CHECK(t.odometry[0].stamp == time_from_seconds(10.5));
}

TEST_CASE("re-anchored odometry: the echoes are dropped and the wheel odometry is chained again") {
  // The wheel odometry the robot had, and the corrected poses of its scans (off by a growing drift).
  const std::vector<Pose2D> wheel{{0, 0, 0}, {0.5, 0, 0.1}, {1.0, 0.1, 0.3}, {1.4, 0.3, 0.7}, {1.6, 0.7, 1.2}};
  const std::vector<Pose2D> ref{{0.1, 0, 0}, {0.58, 0.05, 0.12}, {1.05, 0.2, 0.36}, {1.4, 0.45, 0.8}, {1.55, 0.9, 1.35}};
  // As the corrected logs write it: after each scan an ODOM equal to its corrected pose (stamp 0),
  // then the wheel motion since, added onto that pose; two readings between scans.
  std::string log;
  Pose2D anchor_log, anchor_wheel;
  bool anchored = false;
  double t = 1.0;
  for (std::size_t k = 0; k < wheel.size(); ++k) {
    for (int h = 1; h <= 2; ++h) {
      // the wheel pose half-way and at the scan, as the log would show it
      const Pose2D w = k == 0 ? wheel[0] : lerp(wheel[k - 1], wheel[k], 0.5 * h);
      log += odom(anchored ? compose(anchor_log, compose(inverse(anchor_wheel), w)) : w, t += 0.1);
    }
    log += flaser(ref[k], t);
    log += odom(ref[k], 0.0);  // the echo
    log += "NEFF 15\n";
    anchor_log = ref[k];
    anchor_wheel = wheel[k];
    anchored = true;
  }
  const Imported im = import_text(log);
  CHECK(im.report.odometry == CarmenOdometry::kRecovered);
  CHECK(im.report.odometry_echoes == wheel.size());
  CHECK_THAT(im.report.odometry_note(), Catch::Contains("re-anchored odometry recovered"));
  REQUIRE(im.odometry.size() == 2 * wheel.size());
  // The odometry at each scan (the reading before it) is the wheel odometry, drift and all.
  for (std::size_t k = 0; k < wheel.size(); ++k) CHECK(near(im.odometry[2 * k + 1].pose, wheel[k]));
  // No echo stamped 0 is left to step backwards.
  CHECK(im.report.backwards_steps == 0);

  // Read as logged (the old reading), the odometry at each scan is one scan's motion off the reference.
  const Imported raw = import_text(log, as_logged());
  CHECK(raw.report.odometry == CarmenOdometry::kAnchored);
  REQUIRE(raw.odometry.size() == 3 * wheel.size());
  CHECK_FALSE(near(raw.odometry[3 * 4 + 1].pose, wheel[4], 0.05));
}

TEST_CASE("odometry that repeats the previous scan's pose is no odometry") {
  // orebro: after each scan its echo, and nothing until the next scan.
  std::string log = odom({0, 0, 0}, 0.0);
  for (int k = 0; k < 6; ++k) {
    const Pose2D p{0.5 * k, 0.1 * k, 0.2 * k};
    log += flaser(p, 0.0);
    log += odom(p, 0.0);
  }
  const Imported im = import_text(log);
  CHECK(im.report.odometry == CarmenOdometry::kNone);
  CHECK(im.report.moving_scans == 5);
  CHECK(im.report.still_odometry_scans == 5);
  CHECK_THAT(im.report.odometry_note(), Catch::Contains("no odometry in this log"));

  const Imported none = import_text(flaser({0, 0, 0}, 1.0) + flaser({1, 0, 0}, 2.0));
  CHECK(none.report.odometry == CarmenOdometry::kNone);
  CHECK_THAT(none.report.odometry_note(), Catch::Contains("no ODOM message"));
}

TEST_CASE("a raw log with an ODOM after each scan that moved on is left as logged") {
  std::string log;
  for (int k = 0; k < 5; ++k) {
    log += flaser({0.3 * k, 0, 0}, k + 0.0);
    log += odom({0.3 * k + 0.01, 0, 0}, k + 0.5);
  }
  const Imported im = import_text(log);
  CHECK(im.report.odometry == CarmenOdometry::kRaw);
  CHECK(im.report.odometry_echoes == 0);
  REQUIRE(im.odometry.size() == 5);
  CHECK(im.odometry[4].pose == Pose2D{1.21, 0, 0});
}

TEST_CASE("the gzip-compressed excerpt imports like the plain one") {
  const Imported plain = import_and_read(kExcerpt);
  const Imported gz = import_and_read(kExcerpt + ".gz");
  REQUIRE(gz.scans.size() == plain.scans.size());
  CHECK(gz.scans == plain.scans);
  CHECK(gz.odometry == plain.odometry);
}

TEST_CASE("ROBOTLASER1 uses the scanner configuration of the line") {
  // 5 beams from -0.5 rad, 0.25 rad apart, max 30 m, with 5 remissions.
  const Imported im = import_text(
      "ROBOTLASER1 0 -0.5 1.0 0.25 30.0 0.01 0 5 1.0 2.0 3.0 4.0 5.0 5 10 20 30 40 50 "
      "1.0 2.0 0.1 0.9 1.9 0.1 0.2 0.3 0.5 0.6 0.7 1234.5 host 1234.6\n");
  REQUIRE(im.scans.size() == 1);
  const LaserScan& s = im.scans[0];
  CHECK(s.angle_min_rad == -0.5);
  CHECK(s.angle_increment_rad == 0.25);
  CHECK(s.angle_max_rad == Approx(0.5));
  CHECK(s.range_max_m == 30.0);
  CHECK(s.ranges_m == std::vector<float>{1, 2, 3, 4, 5});
  CHECK(s.intensities == std::vector<float>{10, 20, 30, 40, 50});
  CHECK(s.stamp == time_from_seconds(1234.5));
  CHECK(im.laser_poses[0].pose == Pose2D{1.0, 2.0, 0.1});
}

TEST_CASE("361-beam FLASER scans are 0.5 degree apart over 180 degrees") {
  std::ostringstream line;
  line << "FLASER 361";
  for (int i = 0; i < 361; ++i) line << " 2.5";
  line << " 0 0 0 0 0 0 1.13486e+09 b21 1.13486e+09\n";
  const Imported im = import_text(line.str());
  REQUIRE(im.scans.size() == 1);
  CHECK(im.scans[0].angle_increment_rad == Approx(std::numbers::pi / 360));
  CHECK(im.scans[0].angle_max_rad == Approx(std::numbers::pi / 2));
}

TEST_CASE("malformed lines are all reported with file:line:column") {
  TempFile log("carmen_bad");
  {
    std::ofstream f(log.path());
    f << "# comment\n"
         "ODOM 1 2 x 0 0 0 10.0 host 10.0\n"
         "FLASER 3 1.0 2.0\n"
         "ODOM 1 2 3 0 0 0 11.0 host 11.0 extra\n"
         "FLASER abc\n"
         "FLASER 2 1.0 2.0 0 0\n"
         "ODOM 1 2 3 0 0 0 12.0 host 12.0\n"
         "SYNC tag 1.0 host 1.0\n";
  }
  TempFile out("carmen_bad_out");
  TraceWriter w(out.path());
  const std::string name = log.str();
  try {
    import_carmen_log(log.path(), w);
    FAIL("expected a ConfigError");
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Catch::Contains(name + ":2:10: error: ODOM theta 'x' is not a finite number"));
    CHECK_THAT(what, Catch::Contains(name + ":3:8: error: FLASER num_readings 3 exceeds the 2 fields left on the line"));
    CHECK_THAT(what, Catch::Contains(name + ":4:33: error: ODOM has 1 unexpected fields after logger_timestamp"));
    CHECK_THAT(what, Catch::Contains(name + ":5:8: error: FLASER num_readings 'abc' is not a count"));
    CHECK_THAT(what, Catch::Contains(name + ":6:21: error: FLASER line ends before the theta field"));
    CHECK(e.diagnostics().error_count() == 5);
  }
}

TEST_CASE("unknown messages are skipped and counted") {
  std::istringstream in("SYNC tag 1.0 host 1.0\nTRUEPOS 1 2 3 4 5 6 1.0 h 1.0\nSYNC x 2 h 2\n\n");
  TempFile out("carmen_skip");
  TraceWriter w(out.path());
  const auto report = import_carmen_log(in, "in.log", w);
  CHECK(report.skipped.at("SYNC") == 2);
  CHECK(report.skipped.at("TRUEPOS") == 1);
  CHECK(report.blank_lines == 1);
  CHECK(report.laser_scans == 0);
}

TEST_CASE("a missing log is an I/O error, a damaged gzip stream too") {
  TempFile out("carmen_io");
  TraceWriter w(out.path());
  CHECK_THROWS_AS(import_carmen_log(std::filesystem::path("/nonexistent/x.log.gz"), w), TraceIoError);
  // The excerpt's gzip stream cut in half.
  auto gz = read_all(kExcerpt + ".gz");
  TempFile cut("carmen_cut.gz");
  write_all(cut.path(), gz, gz.size() / 2);
  CHECK_THROWS_AS(import_carmen_log(cut.path(), w), TraceIoError);
}

TEST_CASE("a line longer than the limit is reported at the limit, the lines after it still import") {
  std::string text = "ODOM 1 2 3 0 0 0 10.0 host 10.0\nPARAM robot_name ";
  text.append(kCarmenMaxLineBytes, 'x');
  text += "\nODOM 1 2 3 0 0 0 11.0 host 11.0\nFLASER zz\n";
  std::istringstream in(text);
  TempFile out("carmen_long");
  TraceWriter w(out.path());
  try {
    import_carmen_log(in, "long.log", w);
    FAIL("expected a ConfigError");
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    CHECK_THAT(what, Catch::Contains("long.log:2:1048577: error: line longer than 1048576 bytes"));
    CHECK_THAT(what, Catch::Contains("long.log:4:8: error: FLASER num_readings 'zz' is not a count"));
    CHECK(e.diagnostics().error_count() == 2);
  }
}
