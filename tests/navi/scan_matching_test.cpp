#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <numbers>
#include <random>
#include <vector>

#include "navi_test_util.hpp"
#include "tripodal/navi/map_builder.hpp"
#include "tripodal/navi/map_io.hpp"
#include "tripodal/navi/mapping_module.hpp"
#include "tripodal/navi/scan_matcher.hpp"
#include "tripodal/navi/scan_matching_localizer.hpp"
#include "tripodal/sim/ray_caster.hpp"

using namespace tripodal;
using namespace tripodal::navi;

namespace {

// A 10 m x 8 m room, 5 cm cells, with an L-shaped partition and two boxes placed so that no
// rotation or mirror of the room looks like itself (the global search has one answer).
OccupancyGrid room() {
  OccupancyGrid g(200, 160, 0.05, Pose2D{-1.0, -2.0, 0.0}, Occupancy::free);
  auto block = [&](int x0, int y0, int x1, int y1) {
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) g.set_state({x, y}, Occupancy::occupied);
    }
  };
  block(0, 0, 199, 1);
  block(0, 158, 199, 159);
  block(0, 0, 1, 159);
  block(198, 0, 199, 159);
  block(120, 60, 121, 159 - 40);  // the partition's long leg
  block(120, 60, 160, 61);        // its foot
  block(30, 110, 45, 125);        // a cupboard
  block(60, 20, 64, 24);          // a bin
  return g;
}

// A 180-degree scanner with 181 beams, as the CARMEN logs' SICK.
LaserScan scan_at(const sim::SolidMap& solid, const Pose2D& pose, double max_range_m = 20.0) {
  LaserScan s;
  s.angle_min_rad = -std::numbers::pi / 2;
  s.angle_increment_rad = std::numbers::pi / 180.0;
  s.angle_max_rad = std::numbers::pi / 2;
  s.range_min_m = 0.05;
  s.range_max_m = max_range_m;
  s.ranges_m.resize(181);
  for (std::size_t i = 0; i < s.ranges_m.size(); ++i) {
    const double a = pose.theta_rad + s.angle_min_rad + static_cast<double>(i) * s.angle_increment_rad;
    const double r = solid.cast({pose.x_m, pose.y_m}, a, max_range_m);
    s.ranges_m[i] = static_cast<float>(std::isfinite(r) ? r : max_range_m);
  }
  return s;
}

double distance(const Pose2D& a, const Pose2D& b) { return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m); }

// The true path: a loop through the room, 0.1 m and up to 0.08 rad per scan.
Pose2D true_pose(int k) {
  const double t = 0.02 * k;
  return {2.5 + 1.5 * std::cos(t), 2.0 + 1.2 * std::sin(t), wrap_angle(t + std::numbers::pi / 2)};
}

// Odometry that drifts: 4 % too long and a heading bias of 0.004 rad per scan.
struct DriftingOdometry {
  Pose2D odom{};
  Pose2D last_truth{};
  bool started = false;
  Pose2D read(const Pose2D& truth) {
    if (!started) {
      started = true;
      last_truth = truth;
      odom = truth;
      return odom;
    }
    Pose2D d = compose(inverse(last_truth), truth);
    d.x_m *= 1.04;
    d.y_m *= 1.04;
    d.theta_rad += 0.004;
    odom = compose(odom, d);
    last_truth = truth;
    return odom;
  }
};

Time at(int k) { return time_from_seconds(0.1 * k); }

}  // namespace

TEST_CASE("ScanMatcher: a scan taken at a pose matches back to it, and the covariance follows the geometry",
          "[navi][scan_matching]") {
  const OccupancyGrid g = room();
  const sim::SolidMap solid(g);
  ScanMatcher m(g);
  const Pose2D truth{3.0, 1.0, 0.3};
  REQUIRE(m.set_scan(scan_at(solid, truth)) > 150);
  CHECK(m.quality_at(truth) > 0.8);
  const ScanMatch r = m.match({truth.x_m + 0.15, truth.y_m - 0.12, truth.theta_rad + 0.1});
  // The test room's map is one of solid cells, matched here with the default surface model of
  // scanned maps (the cell centre): half a cell (2.5 cm) of bias is the model's, the rest the
  // matcher's. The next test has the face model.
  CHECK(distance(r.pose, truth) < 0.05);
  CHECK(std::abs(wrap_angle(r.pose.theta_rad - truth.theta_rad)) < 0.015);
  CHECK(r.quality > 0.8);
  CHECK(r.covariance[0] > 0.0);
  CHECK(r.covariance[4] > 0.0);
  CHECK(r.covariance[8] > 0.0);
  CHECK(std::sqrt(r.covariance[0]) < 0.1);

  // a long corridor (walls along x only, open ends beyond the range) leaves x uncertain
  OccupancyGrid corridor(400, 40, 0.05, {}, Occupancy::free);
  for (int x = 0; x < 400; ++x) {
    corridor.set_state({x, 0}, Occupancy::occupied);
    corridor.set_state({x, 39}, Occupancy::occupied);
  }
  const sim::SolidMap csolid(corridor);
  ScanMatcher cm(corridor);
  const Pose2D c_truth{10.0, 1.0, 0.0};
  cm.set_scan(scan_at(csolid, c_truth, 4.0));
  const ScanMatch cr = cm.match(c_truth);
  CHECK(cr.covariance[0] > 4.0 * cr.covariance[4]);
}

TEST_CASE("ScanMatcher: on a map of solid cells, no bias towards the nearer walls", "[navi][scan_matching]") {
  // Poses close to one wall, far from the others: most points lie on the near wall. The ray
  // caster stops a beam at the face of the first occupied cell; a field peaking at that cell's
  // centre (the surface model of maps built from scans) pulls such matches half a cell (2.5 cm)
  // towards the near wall, the face model does not.
  const OccupancyGrid g = room();
  const sim::SolidMap solid(g);
  const auto mean_error = [&](bool at_face) {
    ScanMatcherOptions o;
    o.surface_at_cell_face = at_face;
    ScanMatcher m(g, o);
    double sum = 0.0;
    int n = 0;
    for (const Pose2D truth : {Pose2D{0.4, 2.0, std::numbers::pi}, Pose2D{3.0, -1.3, -std::numbers::pi / 2},
                               Pose2D{4.0, 5.5, std::numbers::pi / 2}, Pose2D{8.6, 0.5, 0.0},
                               Pose2D{0.35, 4.5, 2.8}, Pose2D{6.0, -1.4, -1.2}}) {
      REQUIRE(m.set_scan(scan_at(solid, truth)) > 150);
      const ScanMatch r = m.match({truth.x_m + 0.04, truth.y_m - 0.03, truth.theta_rad + 0.02});
      const double e = distance(r.pose, truth);
      INFO("at face " << at_face << ", pose (" << truth.x_m << ", " << truth.y_m << ", " << truth.theta_rad
                      << "): off by " << e << " m");
      CHECK(std::abs(wrap_angle(r.pose.theta_rad - truth.theta_rad)) < 0.01);
      if (at_face) CHECK(e < 0.035);
      sum += e;
      ++n;
    }
    return sum / n;
  };
  const double face = mean_error(true), centre = mean_error(false);
  INFO("mean error: face model " << face << " m, centre model " << centre << " m");
  // Measured: 0.018 m against 0.032 m. The face model does not reach the matcher's resolution:
  // the face lies between two cell centres, where the field is sampled, and the bilinear field
  // is flat over that cell.
  CHECK(face < 0.022);
  CHECK(centre > face + 0.01);
}

TEST_CASE("ScanMatchingLocalizer: tracks a loop on drifting odometry", "[navi][scan_matching]") {
  const OccupancyGrid g = room();
  const sim::SolidMap solid(g);
  ScanMatchingLocalizerOptions o;
  o.initial_pose = true_pose(0);
  CScanMatchingLocalizer loc(o);
  loc.set_map(g);
  DriftingOdometry odo;
  std::vector<ModuleEvent> ev;
  double worst_m = 0.0, worst_rad = 0.0;
  Pose2D dead_reckoning = true_pose(0);
  for (int k = 0; k <= 300; ++k) {
    const Pose2D truth = true_pose(k);
    const Pose2D odom = odo.read(truth);
    loc.step(scan_at(solid, truth), odom, at(k), ev);
    worst_m = std::max(worst_m, distance(loc.estimate(), truth));
    worst_rad = std::max(worst_rad, std::abs(wrap_angle(loc.estimate().theta_rad - truth.theta_rad)));
    dead_reckoning = odom;
  }
  CHECK(worst_m < 0.05);
  CHECK(worst_rad < 0.02);
  CHECK(distance(dead_reckoning, true_pose(300)) > 0.5);  // the odometry alone is far off
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].name == "localizer.ok");
  CHECK(loc.localized());
  NavigationData nd;
  loc.publish(nd);
  CHECK(nd.localized);
  CHECK(nd.pose_stamp == at(300));
}

TEST_CASE("ScanMatchingLocalizer: a kidnapped robot is lost, and the global search finds it again",
          "[navi][scan_matching]") {
  const OccupancyGrid g = room();
  const sim::SolidMap solid(g);
  ScanMatchingLocalizerOptions o;
  o.initial_pose = true_pose(0);
  o.lost_after_scans = 3;
  CScanMatchingLocalizer loc(o);
  loc.set_map(g);
  std::vector<ModuleEvent> ev;
  DriftingOdometry odo;
  for (int k = 0; k < 20; ++k) loc.step(scan_at(solid, true_pose(k)), odo.read(true_pose(k)), at(k), ev);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].name == "localizer.ok");
  ev.clear();
  // carried to the other side of the partition, turned round: the odometry does not see it
  const Pose2D kidnapped{6.0, 3.5, -2.0};
  const Pose2D odom_still = odo.odom;
  int lost_at = -1;
  for (int k = 20; k < 30 && lost_at < 0; ++k) {
    loc.step(scan_at(solid, kidnapped), odom_still, at(k), ev);
    if (!ev.empty()) lost_at = k;
  }
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].name == "localizer.lost");
  CHECK_THAT(ev[0].message, Catch::Contains("stopped matching"));
  CHECK(lost_at == 22);  // after lost_after_scans scans, not at the first bad one
  CHECK_FALSE(loc.localized());
  CHECK(distance(loc.estimate(), kidnapped) > 1.0);
  ev.clear();
  REQUIRE(loc.relocalize());
  CHECK(distance(loc.estimate(), kidnapped) < 0.08);
  CHECK(std::abs(wrap_angle(loc.estimate().theta_rad - kidnapped.theta_rad)) < 0.03);
  loc.step(scan_at(solid, kidnapped), odom_still, at(31), ev);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].name == "localizer.ok");
  CHECK(loc.localized());
}

TEST_CASE("ScanMatchingLocalizer: a blinded laser is a loss that heals by itself", "[navi][scan_matching]") {
  const OccupancyGrid g = room();
  const sim::SolidMap solid(g);
  ScanMatchingLocalizerOptions o;
  o.initial_pose = true_pose(0);
  CScanMatchingLocalizer loc(o);
  loc.set_map(g);
  std::vector<ModuleEvent> ev;
  DriftingOdometry odo;
  for (int k = 0; k < 60; ++k) {
    LaserScan s = scan_at(solid, true_pose(k));
    if (k >= 20 && k < 30) {
      for (float& r : s.ranges_m) r = 0.02f;  // covered: every return below range_min
    }
    loc.step(s, odo.read(true_pose(k)), at(k), ev);
  }
  REQUIRE(ev.size() == 3);
  CHECK(ev[0].name == "localizer.ok");
  CHECK(ev[1].name == "localizer.lost");
  CHECK(ev[1].stamp == at(24));
  CHECK(ev[2].name == "localizer.ok");
  CHECK(ev[2].stamp == at(30));
  CHECK(distance(loc.estimate(), true_pose(59)) < 0.05);
}

TEST_CASE("ScanMatchingLocalizer: an unknown start is found by the global search on the first scan",
          "[navi][scan_matching]") {
  const OccupancyGrid g = room();
  const sim::SolidMap solid(g);
  ScanMatchingLocalizerOptions o;
  o.start_global = true;
  CScanMatchingLocalizer loc(o);
  loc.set_map(g);
  std::vector<ModuleEvent> ev;
  const Pose2D truth{7.5, 1.0, 2.5};
  loc.step(scan_at(solid, truth), Pose2D{}, at(0), ev);
  CHECK(distance(loc.estimate(), truth) < 0.05);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].name == "localizer.ok");
}

TEST_CASE("ScanMatcher: the global search stops at its budget with the best pose found so far", "[navi][scan_matching]") {
  // the room inside a map four times its area of unknown space (a building's map with the
  // outside scanned in): the search skips every block without a free cell, so the unknown part
  // costs nothing, and a budget bounds the rest (issue 41: 5.9 s on the infinite corridor)
  const OccupancyGrid inner = room();
  OccupancyGrid g(400, 320, 0.05, Pose2D{-1.0, -2.0, 0.0}, Occupancy::unknown);
  for (int y = 0; y < inner.height(); ++y) {
    for (int x = 0; x < inner.width(); ++x) g.set_state({x, y}, inner.state({x, y}));
  }
  const sim::SolidMap solid(inner);
  const Pose2D truth{7.5, 1.0, 2.5};
  ScanMatcherOptions unbounded;
  unbounded.global_max_nodes = 0;
  ScanMatcher full(g, unbounded);
  full.set_scan(scan_at(solid, truth));
  const ScanMatch all = full.match_global();
  CHECK(all.exhaustive);
  CHECK(distance(all.pose, truth) < 0.05);
  // the same search on the room alone visits as many blocks: the unknown space added none
  ScanMatcher room_only(inner, unbounded);
  room_only.set_scan(scan_at(solid, truth));
  const ScanMatch on_room = room_only.match_global();
  INFO("nodes with the unknown border " << all.nodes << ", on the room alone " << on_room.nodes);
  CHECK(all.nodes <= on_room.nodes + on_room.nodes / 10);
  // a budget below what the search needs: stopped and marked so (the top tiles of every heading
  // are always bounded, 3,780 here; the budget stops the descent below them)
  ScanMatcherOptions tight;
  tight.global_max_nodes = 100;
  ScanMatcher bounded(g, tight);
  bounded.set_scan(scan_at(solid, truth));
  const ScanMatch part = bounded.match_global();
  CHECK_FALSE(part.exhaustive);
  CHECK(part.nodes < all.nodes);
  CHECK(part.quality <= all.quality + 1e-9);
  // the default budget does not bind on this map
  ScanMatcher deflt(g);
  deflt.set_scan(scan_at(solid, truth));
  CHECK(deflt.match_global().exhaustive);
  ScanMatcherOptions bad;
  bad.global_max_nodes = -1;
  REQUIRE_THROWS_WITH(ScanMatcher(g, bad), Catch::Contains("global_max_nodes must be >= 0"));
}

TEST_CASE("ScanMatcher and ScanMatchingLocalizer refuse bad options and maps with locations",
          "[navi][scan_matching]") {
  const OccupancyGrid g = room();
  const SourceLocation where{"robot.yaml", 12, 5};
  ScanMatcherOptions bad;
  bad.sigma_m = -0.1;
  bad.global_levels = 0;
  REQUIRE_THROWS_WITH(ScanMatcher(g, bad, where), Catch::Contains("robot.yaml:12:5") &&
                                                      Catch::Contains("sigma_m must be a number > 0") &&
                                                      Catch::Contains("global_levels must be 1..10"));
  const OccupancyGrid empty(50, 50, 0.05, {}, Occupancy::free);
  REQUIRE_THROWS_WITH(ScanMatcher(empty, {}, where),
                      Catch::Contains("robot.yaml:12:5") && Catch::Contains("no occupied cell"));
  const OccupancyGrid tiny(1, 1, 0.05, {}, Occupancy::occupied);
  REQUIRE_THROWS_WITH(ScanMatcher(tiny, {}, where), Catch::Contains("expected at least 2 x 2"));

  CScanMatchingLocalizer loc;
  REQUIRE_THROWS_WITH(loc.configure({{"sigma_m", Value{0.0}}}, where),
                      Catch::Contains("robot.yaml:12:5") && Catch::Contains("sigma_m"));
  loc.configure({}, where);
  ModuleContext context;
  REQUIRE_THROWS_WITH(loc.start(context), Catch::Contains("robot.yaml:12:5") && Catch::Contains("GridMaps"));
  loc.set_map(g);
  REQUIRE_THROWS_WITH(loc.start(context), Catch::Contains("no laser resource"));
}

TEST_CASE("MapBuilder: a map from drifting odometry lines up with the world and localizes", "[navi][scan_matching]") {
  const OccupancyGrid world = room();
  const sim::SolidMap solid(world);
  MapBuilder b({-1.5, -2.5}, {9.5, 6.5});
  DriftingOdometry odo;
  double worst_step_m = 0.0;
  Pose2D prev_est, prev_truth;
  for (int k = 0; k <= 320; k += 2) {
    const Pose2D truth = true_pose(k);
    const Pose2D est = b.add(scan_at(solid, truth), odo.read(truth), true_pose(0));
    if (k > 0) {
      // relative motion between consecutive scans, against the truth's (Kuemmerle et al.)
      const Pose2D de = compose(inverse(prev_est), est), dt = compose(inverse(prev_truth), truth);
      worst_step_m = std::max(worst_step_m, std::hypot(de.x_m - dt.x_m, de.y_m - dt.y_m));
    }
    prev_est = est;
    prev_truth = truth;
  }
  CHECK(worst_step_m < 0.05);
  CHECK(distance(prev_est, true_pose(320)) < 0.1);
  const OccupancyGrid map = b.grid();
  // every wall cell the builder marked is on or next to a wall of the world
  const test::WallAgreement walls = test::wall_agreement(map, world);
  REQUIRE(walls.marked > 500);
  CHECK(walls.fraction() > 0.95);
  // and the map it made is one the localizer can work on
  ScanMatcher m(map);
  m.set_scan(scan_at(solid, true_pose(100)));
  CHECK(distance(m.match(compose(true_pose(100), Pose2D{0.1, -0.1, 0.05})).pose, true_pose(100)) < 0.08);

  REQUIRE_THROWS_WITH(MapBuilder({0, 0}, {-1, 5}), Catch::Contains("is empty or larger than a map image may be"));
  MapBuilderOptions bad;
  bad.resolution_m = 0.0;
  REQUIRE_THROWS_WITH(MapBuilder({0, 0}, {5, 5}, bad), Catch::Contains("resolution_m must be a number > 0"));
}

TEST_CASE("MapBuilder: loop closure undoes the drift of a map made on odometry alone", "[navi][scan_matching][pose_graph]") {
  const OccupancyGrid world = room();
  const sim::SolidMap solid(world);
  // three times round the loop (about 26 m) trusting no match: the odometry's heading bias alone
  // would leave the robot far off; the closures against the first round bring it back
  auto run = [&](bool closing) {
    MapBuilderOptions o;
    o.min_quality = 1.0;  // no scan-to-map correction: odometry alone between closures
    o.loop.enabled = closing;
    o.loop.min_travel_m = 6.0;
    // odometry alone drifts 0.04 rad per metre here, far beyond what the default bound allows
    // for (the drift scan-to-map matching leaves): the bound is widened to this odometry's
    o.loop.drift_m_per_m = 0.4;
    o.loop.drift_rad_per_m = 0.06;
    auto b = std::make_unique<MapBuilder>(Point2D{-6.5, -7.5}, Point2D{14.5, 11.5}, o);
    DriftingOdometry odo;
    for (int k = 0; k <= 960; k += 2) b->add(scan_at(solid, true_pose(k)), odo.read(true_pose(k)), true_pose(0));
    return b;
  };
  const auto open = run(false);
  const auto closed = run(true);
  CHECK(open->loop_stats().closures == 0);
  const LoopClosureStats& stats = closed->loop_stats();
  INFO("attempts " << stats.attempts << ", refused: weak " << stats.weak << ", implausible " << stats.implausible
                   << ", disagreeing " << stats.disagreeing << ", ambiguous " << stats.ambiguous);
  CHECK(closed->loop_stats().closures >= 3);
  CHECK(closed->loop_stats().solves >= 1);
  const std::vector<Pose2D> drifted = open->trajectory(), corrected = closed->trajectory();
  REQUIRE(corrected.size() == 481);
  const Pose2D end = true_pose(960);
  CHECK(distance(drifted.back(), end) > 1.0);
  CHECK(distance(corrected.back(), end) < 0.25);
  // the whole path: the closures tie every later round to the first (whose own bend only its
  // closure at the start straightens: a map from odometry alone stays bent, less so)
  double open_sum_m = 0.0, closed_sum_m = 0.0;
  for (std::size_t i = 0; i < corrected.size(); ++i) {
    open_sum_m += distance(drifted[i], true_pose(static_cast<int>(2 * i)));
    closed_sum_m += distance(corrected[i], true_pose(static_cast<int>(2 * i)));
  }
  CHECK(closed_sum_m < open_sum_m / 4.0);
  // and the map drawn again at the solved poses has its walls where the world has them at least
  // twice as often
  const double closed_walls = test::wall_agreement(closed->grid(), world).fraction();
  const double open_walls = test::wall_agreement(open->grid(), world).fraction();
  INFO("wall agreement: closed " << closed_walls << ", open " << open_walls);
  CHECK(closed_walls > 2.0 * open_walls);
}

TEST_CASE("MapBuilder: a closure within its own noise of the graph does not bend it", "[navi][scan_matching][pose_graph]") {
  // once round the loop and on (about 13 m), trusting no match, on odometry with a small heading
  // bias: the closures find the graph off by less than a noise wide enough to cover that drift.
  // Such a closure shows no drift beyond its own error: it is kept, and the graph is not solved
  // (issue 41: on CSAIL one such solve turned the map by 1 degree, 0.075 -> 0.322 m from the start).
  // With the closure noise of the default, the same drift is well beyond it and is solved.
  const OccupancyGrid world = room();
  const sim::SolidMap solid(world);
  auto run = [&](const EdgeNoise& closure_noise, bool closing) {
    MapBuilderOptions o;
    o.min_quality = 1.0;  // odometry alone between closures
    o.recovery_margin = 0.0;
    o.loop.enabled = closing;
    o.loop.min_travel_m = 6.0;
    o.loop.drift_m_per_m = 0.4;
    o.loop.drift_rad_per_m = 0.06;
    o.loop.closure_noise = closure_noise;
    auto b = std::make_unique<MapBuilder>(Point2D{-6.5, -7.5}, Point2D{14.5, 11.5}, o);
    DriftingOdometry odo;
    for (int k = 0; k <= 440; k += 2) b->add(scan_at(solid, true_pose(k)), odo.read(true_pose(k)), true_pose(0));
    return b;
  };
  const EdgeNoise loose{.sigma_xy_m = 5.0, .sigma_theta_rad = 2.0};
  const auto open = run(loose, false);
  const auto settled = run(loose, true);
  INFO("closures " << settled->loop_stats().closures << ", solves " << settled->loop_stats().solves);
  CHECK(settled->loop_stats().closures >= 1);
  CHECK(settled->loop_stats().settled == settled->loop_stats().closures);
  CHECK(settled->loop_stats().solves == 0);
  const std::vector<Pose2D> a = open->trajectory(), b = settled->trajectory();
  REQUIRE(a.size() == b.size());
  double moved_m = 0.0;
  for (std::size_t i = 0; i < a.size(); ++i) moved_m = std::max(moved_m, distance(a[i], b[i]));
  CHECK(moved_m == 0.0);
  // the same drift against the default closure noise: beyond it, solved
  const auto solved = run(LoopClosureOptions{}.closure_noise, true);
  CHECK(solved->loop_stats().solves >= 1);
  CHECK(distance(solved->trajectory().back(), true_pose(440)) < distance(a.back(), true_pose(440)));
}

TEST_CASE("MapBuilder: no loop closure in a corridor where every place looks alike", "[navi][scan_matching][pose_graph]") {
  // a 30 m x 3 m corridor without a feature; the scanner sees 6 m, never an end wall: a scan
  // matches anywhere along it equally well. Driven 6 m up and 5 m back on odometry 4 % long and
  // trusting no match, the builder must not close the loop at a place the scans cannot tell
  // (the look-alike corridors of CSAIL and the Freiburg campus, issue 41)
  OccupancyGrid world(600, 60, 0.05, Pose2D{0.0, 0.0, 0.0}, Occupancy::free);
  for (int x = 0; x < 600; ++x) {
    for (int y : {0, 1, 58, 59}) world.set_state({x, y}, Occupancy::occupied);
  }
  const sim::SolidMap solid(world);
  std::vector<Pose2D> path;
  for (int k = 0; k <= 30; ++k) path.push_back({8.0 + 0.2 * k, 1.5, 0.0});
  for (int k = 0; k <= 25; ++k) path.push_back({14.0 - 0.2 * k, 1.5, std::numbers::pi});
  auto run = [&](const LoopClosureOptions& loop) {
    MapBuilderOptions o;
    o.min_quality = 1.0;  // odometry alone between closures
    o.recovery_margin = 0.0;
    o.window_m = 8.0;
    o.resolution_m = 0.1;  // the global searches over a featureless corridor prune little
    o.loop = loop;
    o.loop.enabled = true;
    o.loop.submap_resolution_m = 0.1;
    o.loop.min_travel_m = 3.0;
    o.loop.every_keyframes = 5;
    auto b = std::make_unique<MapBuilder>(Point2D{-2.0, -4.0}, Point2D{32.0, 7.0}, o);
    Pose2D odom = path.front();
    for (std::size_t i = 0; i < path.size(); ++i) {
      if (i > 0) {
        Pose2D d = compose(inverse(path[i - 1]), path[i]);
        d.x_m *= 1.04;
        odom = compose(odom, d);
      }
      b->add(scan_at(solid, path[i], 6.0), odom, path.front());
    }
    return b;
  };
  // the acceptance test of before (one scan, its best match, no check against the graph) closes
  // the loop there
  LoopClosureOptions lax;
  lax.agree_keyframes = 1;
  lax.exclusion_m = 1000.0;
  lax.drift_base_m = 1000.0;
  lax.drift_base_rad = 10.0;
  const auto before = run(lax);
  CHECK(before->loop_stats().attempts > 0);
  CHECK(before->loop_stats().closures > 0);
  // the default refuses every one of them, and says why: a slide along the corridor larger than
  // the drift since can explain, the scans before not finding the same correction (each slides
  // elsewhere), or another place scoring as well
  const auto now = run(LoopClosureOptions{});
  const LoopClosureStats& stats = now->loop_stats();
  CHECK(stats.attempts > 0);
  CHECK(stats.closures == 0);
  CHECK(stats.solves == 0);
  CHECK(stats.weak == 0);
  CHECK(stats.ambiguous + stats.disagreeing + stats.implausible == stats.attempts);
  // without the drift bound, agreement and distinctness alone refuse them
  LoopClosureOptions no_bound;
  no_bound.drift_base_m = 1000.0;
  no_bound.drift_base_rad = 10.0;
  const auto unbounded = run(no_bound);
  CHECK(unbounded->loop_stats().attempts > 0);
  CHECK(unbounded->loop_stats().closures == 0);
  CHECK(unbounded->loop_stats().implausible == 0);
  CHECK(unbounded->loop_stats().ambiguous + unbounded->loop_stats().disagreeing > 0);

  MapBuilderOptions bad;
  bad.loop.agree_keyframes = 0;
  REQUIRE_THROWS_WITH(MapBuilder({0, 0}, {5, 5}, bad), Catch::Contains("agree_keyframes >= 1"));
}

TEST_CASE("MapBuilder module: maps only between begin and end, crops to what the beams reached, saves a map_server map",
          "[navi][scan_matching][mapping]") {
  const OccupancyGrid world = room();
  const sim::SolidMap solid(world);
  MappingOptions o;
  o.size_m = 30.0;
  CMapBuilder mapper(o);
  DriftingOdometry odo;
  CHECK_FALSE(mapper.map().has_value());
  mapper.add(scan_at(solid, true_pose(0)), odo.read(true_pose(0)));  // not mapping yet: ignored
  CHECK(mapper.scans() == 0);
  CHECK_THROWS_WITH(mapper.save(std::filesystem::temp_directory_path() / "tripodal_no_map.yaml"),
                    Catch::Contains("no map to save yet"));

  mapper.begin(true_pose(0));
  for (int k = 0; k <= 200; k += 2) mapper.add(scan_at(solid, true_pose(k)), odo.read(true_pose(k)));
  CHECK(mapper.scans() == 101);
  CHECK(distance(mapper.pose(), true_pose(200)) < 0.1);
  mapper.end();
  CHECK_FALSE(mapper.mapping());
  mapper.add(scan_at(solid, true_pose(202)), odo.read(true_pose(202)));
  CHECK(mapper.scans() == 101);

  const std::optional<OccupancyGrid> map = mapper.map();
  REQUIRE(map.has_value());
  // cropped to the room (10 m x 8 m and the scanner's reach within it), not the 30 m square
  CHECK(map->width() * map->resolution_m() < 11.0);
  CHECK(map->height() * map->resolution_m() < 9.0);
  const test::WallAgreement walls = test::wall_agreement(*map, world);
  REQUIRE(walls.marked > 500);
  CHECK(walls.fraction() > 0.95);

  const test::TempDir dir("mapping");
  mapper.save(dir.path() / "room.yaml");
  const MapFile saved = load_map(dir.path() / "room.yaml");
  CHECK(saved.grid.width() == map->width());
  CHECK(saved.grid.count(Occupancy::occupied) == map->count(Occupancy::occupied));
}

TEST_CASE("MapBuilder and ScanMatchingLocalizer refuse to start without their sensors, naming what is missing",
          "[navi][scan_matching][mapping]") {
  ModuleContext none;  // a robot without resources
  CMapBuilder mapper;
  mapper.configure({}, SourceLocation{"robot.yaml", 40, 5});
  CHECK_THROWS_WITH(mapper.start(none), Catch::Contains("robot.yaml:40:5: error: MapBuilder needs a laser scanner, and the robot has no laser resource"));
  CMapBuilder named;
  named.configure({{"laser", Value{std::string("front")}}}, SourceLocation{"robot.yaml", 44, 5});
  CHECK_THROWS_WITH(named.start(none), Catch::Contains("robot.yaml:44:5: error: MapBuilder: no laser resource named 'front'"));
  CScanMatchingLocalizer localizer;
  localizer.configure({}, SourceLocation{"robot.yaml", 32, 5});
  localizer.set_map(room());
  CHECK_THROWS_WITH(localizer.start(none), Catch::Contains("robot.yaml:32:5: error: ScanMatchingLocalizer needs a laser scanner"));
}

TEST_CASE("ScanMatchingLocalizer: a match far from the odometry and weaker than usual is not taken",
          "[navi][scan_matching]") {
  // With a permissive lost_quality a wrong match passes the absolute threshold (as on orebro,
  // accepted at 0.72 and metres off): the localizer must judge it against its own recent matches
  // and the odometry instead of reporting it with confidence.
  const OccupancyGrid g = room();
  const sim::SolidMap solid(g);
  ScanMatchingLocalizerOptions o;
  o.initial_pose = true_pose(0);
  o.lost_quality = 0.3;
  CScanMatchingLocalizer loc(o);
  loc.set_map(g);
  std::vector<ModuleEvent> events;
  int k = 0;
  for (; k <= 60; k += 2) loc.step(scan_at(solid, true_pose(k)), true_pose(k), at(k), events);
  REQUIRE(loc.localized());
  CHECK(loc.unreliable_scans() == 0);
  CHECK(loc.typical_quality() > 0.8);
  // carried behind the partition without the odometry seeing it: the tracker's widest window
  // (1 m) cannot reach the truth, and whatever it finds there is weaker than usual
  const Pose2D still = true_pose(k - 2);
  const Pose2D moved{7.5, 1.0, 2.0};
  const Pose2D before = loc.estimate();
  int inconsistent = 0;
  for (int i = 0; i < 6; ++i) {
    loc.step(scan_at(solid, moved), still, at(k + i), events);
    inconsistent += loc.last_verdict() == ScanVerdict::kInconsistent ? 1 : 0;
    INFO("scan " << i << " quality " << loc.last_match().quality);
    CHECK(loc.last_verdict() != ScanVerdict::kConsistent);
    CHECK(distance(loc.estimate(), before) < 1e-9);  // the estimate stays with the odometry
  }
  CHECK(inconsistent >= 1);
  CHECK(loc.unreliable_scans() == 6);
  CHECK_FALSE(loc.localized());
  REQUIRE_FALSE(events.empty());
  CHECK(events.back().name == "localizer.lost");
  // and the global search finds it
  CHECK(loc.relocalize());
  CHECK(distance(loc.estimate(), moved) < 0.1);
}

TEST_CASE("MapBuilder: an odometry jump beyond the tracking window is recovered by a global match",
          "[navi][scan_matching]") {
  // seattle: the odometry turns 80 degrees between two scans that did not. Without recovery the
  // rest of the map is laid at the wrong angle.
  const OccupancyGrid world = room();
  const sim::SolidMap solid(world);
  auto run = [&](double recovery_margin) {
    MapBuilderOptions o;
    o.recovery_margin = recovery_margin;
    auto b = std::make_unique<MapBuilder>(Point2D{-6.5, -7.5}, Point2D{14.5, 11.5}, o);
    Pose2D odom = true_pose(0);
    for (int k = 0; k <= 300; k += 2) {
      if (k > 0) {
        Pose2D d = compose(inverse(true_pose(k - 2)), true_pose(k));
        if (k == 150) d.theta_rad += 1.4;  // the jump
        odom = compose(odom, d);
      }
      b->add(scan_at(solid, true_pose(k)), odom, true_pose(0));
    }
    return b;
  };
  const auto off = run(0.0);
  const auto on = run(MapBuilderOptions{}.recovery_margin);
  const std::vector<Pose2D> lost = off->trajectory(), kept = on->trajectory();
  REQUIRE(kept.size() == 151);
  CHECK(off->health().recovered == 0);
  CHECK(on->health().recovered >= 1);
  CHECK(distance(lost.back(), true_pose(300)) > 0.5);
  CHECK(distance(kept.back(), true_pose(300)) < 0.1);
  double worst_m = 0.0;
  for (std::size_t i = 75; i < kept.size(); ++i) worst_m = std::max(worst_m, distance(kept[i], true_pose(static_cast<int>(2 * i))));
  CHECK(worst_m < 0.15);
}

// The tracking search of issue 42 item 4 (SIMD bilinear reads, rotations and covariance rows, the
// padded pooled fields read without a check each, bounds four at a time) must give the same
// doubles as the scalar search before it: the digest below was recorded with the code of 7da5bd0.
// The map is the room cropped by 0.6 m on the left and 0.4 m at the bottom, so that many points
// fall near or beyond the grid's edges (the checked reads), on poses and windows drawn from a
// fixed seed, with scans whose point counts are odd and even (the scalar tail of the SIMD loops).
TEST_CASE("ScanMatcher: tracking gives the same doubles as the scalar search (grid edges included)", "[navi][scan_matching]") {
  const OccupancyGrid world = room();
  const sim::SolidMap solid(world);
  const int cut_x = 12, cut_y = 8;
  OccupancyGrid map(
      world.width() - cut_x, world.height() - cut_y, world.resolution_m(),
      Pose2D{world.origin().x_m + cut_x * world.resolution_m(), world.origin().y_m + cut_y * world.resolution_m(), 0.0},
      Occupancy::free);
  for (int y = 0; y < map.height(); ++y) {
    for (int x = 0; x < map.width(); ++x) map.set_state({x, y}, world.state(CellIndex{x + cut_x, y + cut_y}));
  }
  ScanMatcher m(map, ScanMatcherOptions{.surface_at_cell_face = true});
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> ux(-0.8, 4.0), uy(-1.6, 5.5), ut(-3.1, 3.1), off(-0.2, 0.2);
  std::uniform_real_distribution<double> window_xy(0.0, 0.6), window_t(0.0, 0.3);
  std::uint64_t digest = 1469598103934665603ULL;  // FNV-1a over the bits of every figure
  auto mix = [&](double v) {
    std::uint64_t bits = 0;
    std::memcpy(&bits, &v, sizeof bits);
    for (int b = 0; b < 8; ++b) {
      digest ^= (bits >> (8 * b)) & 0xffU;
      digest *= 1099511628211ULL;
    }
  };
  std::size_t odd = 0, matched = 0;
  for (int k = 0; k < 40; ++k) {
    const Pose2D truth{ux(rng), uy(rng), ut(rng)};
    const Pose2D predicted{truth.x_m + off(rng), truth.y_m + off(rng), truth.theta_rad + 0.5 * off(rng)};
    const double xy = window_xy(rng), t = window_t(rng);
    if (!solid.disc_overlaps({truth.x_m, truth.y_m}, 0.2)) {
      const std::size_t n = m.set_scan(scan_at(solid, truth, 6.0 + 0.1 * k));
      odd += n % 2;
      const ScanMatch r = m.match(predicted, xy, t);
      for (double v : {r.pose.x_m, r.pose.y_m, r.pose.theta_rad, r.quality, static_cast<double>(r.points)}) mix(v);
      for (double v : r.covariance) mix(v);
      ++matched;
    }
  }
  CHECK(matched > 25);
  CHECK(odd > 3);
  INFO("digest 0x" << std::hex << digest);
  CHECK(digest == 0x29be45cde26b1b83ULL);
}

TEST_CASE("MapBuilder: where most matches are untrusted, the map follows the odometry", "[navi][scan_matching]") {
  // The infinite corridor (issue 41): 1,592 of 1,941 matches far below the usual quality, each
  // taken when within 0.3 m of the odometry, and the map ended farther off than the odometry
  // alone. Here the odometry is exact and, after a lap of clean scans, two beams in three return
  // clutter the map cannot explain (people, glass): each weak match pulls the pose a little.
  const OccupancyGrid world = room();
  const sim::SolidMap solid(world);
  auto run = [&](double fallback_share) {
    MapBuilderOptions o;
    o.fallback_share = fallback_share;
    auto b = std::make_unique<MapBuilder>(Point2D{-6.5, -7.5}, Point2D{14.5, 11.5}, o);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> clutter_m(0.3, 4.0);
    for (int k = 0; k <= 600; k += 2) {
      LaserScan s = scan_at(solid, true_pose(k));
      if (k >= 320) {
        for (std::size_t i = 0; i < s.ranges_m.size(); ++i) {
          if (i % 3 != 0) s.ranges_m[i] = static_cast<float>(clutter_m(rng));
        }
      }
      b->add(s, true_pose(k), true_pose(0));
    }
    return b;
  };
  CHECK(MapBuilderOptions{}.fallback_share == 1.0);  // off by default: it worsened three held-out logs
  const auto trusting = run(1.0);                    // never falls back: the rule before
  const auto falling_back = run(0.75);
  CHECK(trusting->health().in_fallback == 0);
  CHECK(trusting->health().unreliable > 100);
  CHECK(falling_back->health().in_fallback > 100);
  CHECK(falling_back->health().odometry_only > 100);
  double before_m = 0.0, after_m = 0.0;
  const std::vector<Pose2D> a = trusting->trajectory(), b = falling_back->trajectory();
  REQUIRE(a.size() == 301);
  REQUIRE(b.size() == 301);
  for (std::size_t i = 160; i < a.size(); ++i) {
    before_m = std::max(before_m, distance(a[i], true_pose(static_cast<int>(2 * i))));
    after_m = std::max(after_m, distance(b[i], true_pose(static_cast<int>(2 * i))));
  }
  // measured: 0.076 m trusting the weak matches, 0.035 m falling back (the weak matches taken
  // before 15 of the last 20 were untrusted)
  CAPTURE(before_m, after_m);
  CHECK(before_m > 0.06);
  CHECK(after_m < 0.5 * before_m);

  MapBuilderOptions bad;
  bad.fallback_scans = 65;
  REQUIRE_THROWS_WITH(MapBuilder({0, 0}, {5, 5}, bad), Catch::Contains("fallback_scans in [1, 64]"));
}
