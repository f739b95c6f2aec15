#include "tripodal/navi/pose_graph.hpp"

#include <catch2/catch.hpp>

#include <cmath>
#include <numbers>
#include <stdexcept>

using namespace tripodal;
using namespace tripodal::navi;

namespace {

// A square loop of 4 x 10 steps of 0.5 m, a quarter turn at each corner.
Pose2D truth(int k) {
  Pose2D p{};
  for (int i = 0; i < k; ++i) p = compose(p, Pose2D{0.5, 0.0, (i % 10 == 9) ? std::numbers::pi / 2 : 0.0});
  return p;
}

double gap_m(const Pose2D& a, const Pose2D& b) { return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m); }

// The graph of the loop on odometry biased by 0.02 rad per step, optionally closed.
PoseGraph drifting_loop() {
  PoseGraph g;
  Pose2D dead{};
  g.add_node(dead);
  for (int k = 1; k <= 40; ++k) {
    Pose2D step = compose(inverse(truth(k - 1)), truth(k));
    step.theta_rad += 0.02;
    dead = compose(dead, step);
    g.add_node(dead);
    g.add_edge(static_cast<std::size_t>(k - 1), static_cast<std::size_t>(k), step, {.sigma_xy_m = 0.05, .sigma_theta_rad = 0.02});
  }
  return g;
}

}  // namespace

TEST_CASE("PoseGraph: a loop closure pulls a drifting loop back onto itself", "[navi][pose_graph]") {
  PoseGraph g = drifting_loop();
  // node 40 ends where node 0 began: dead reckoning puts it metres away
  REQUIRE(truth(40).x_m == Approx(0.0).margin(1e-9));
  const double before = gap_m(g.pose(40), g.pose(0));
  REQUIRE(before > 2.0);
  g.add_edge(0, 40, Pose2D{}, {.sigma_xy_m = 0.02, .sigma_theta_rad = 0.01}, true);
  const PoseGraphReport r = g.optimize();
  CHECK(r.rejected == 0);
  CHECK(r.final_chi2 < r.initial_chi2 / 100.0);
  CHECK(gap_m(g.pose(40), g.pose(0)) < 0.05);
  // every pose of the loop is nearer the truth than dead reckoning left it, the far side included
  double worst_m = 0.0;
  for (int k = 0; k <= 40; ++k) worst_m = std::max(worst_m, gap_m(g.pose(static_cast<std::size_t>(k)), truth(k)));
  CHECK(worst_m < 0.35);
  CHECK(g.pose(0) == Pose2D{});  // node 0 anchors the map frame
}

TEST_CASE("PoseGraph: a wrong closure is dropped and the right one kept", "[navi][pose_graph]") {
  PoseGraph g = drifting_loop();
  g.add_edge(0, 40, Pose2D{}, {.sigma_xy_m = 0.02, .sigma_theta_rad = 0.01}, true);
  // a closure in a corridor that looks the same 3 m further on
  g.add_edge(10, 30, Pose2D{3.0, 0.0, 0.0}, {.sigma_xy_m = 0.02, .sigma_theta_rad = 0.01}, true);
  const PoseGraphReport r = g.optimize();
  CHECK(r.rejected == 1);
  CHECK_FALSE(g.rejected(40));
  CHECK(g.rejected(41));
  CHECK(gap_m(g.pose(40), g.pose(0)) < 0.05);
  CHECK(g.chi2(40) < 1.0);
}

TEST_CASE("PoseGraph: a graph without closures stays where its edges put it", "[navi][pose_graph]") {
  PoseGraph g = drifting_loop();
  const std::vector<Pose2D> before = g.poses();
  const PoseGraphReport r = g.optimize();
  CHECK(r.final_chi2 < 1e-12);
  for (std::size_t k = 0; k < before.size(); ++k) CHECK(gap_m(g.pose(k), before[k]) < 1e-9);
}

TEST_CASE("PoseGraph refuses edges between unknown nodes, non-finite values and noise that is not > 0", "[navi][pose_graph]") {
  PoseGraph g;
  g.add_node({});
  g.add_node({1.0, 0.0, 0.0});
  CHECK_THROWS_AS(g.add_node({std::nan(""), 0.0, 0.0}), std::invalid_argument);
  CHECK_THROWS_WITH(g.add_edge(0, 2, {}, {}), Catch::Contains("0 -> 2 with 2 nodes"));
  CHECK_THROWS_AS(g.add_edge(1, 1, {}, {}), std::invalid_argument);
  CHECK_THROWS_AS(g.add_edge(0, 1, {INFINITY, 0.0, 0.0}, {}), std::invalid_argument);
  CHECK_THROWS_WITH(g.add_edge(0, 1, {}, {.sigma_xy_m = 0.0, .sigma_theta_rad = 0.1}), Catch::Contains("noise must be > 0"));
  CHECK(g.edge_count() == 0);
}
