// A 2D pose graph, the back end of the map builder's loop closure (navigation modules, sequencing
// layer): scan poses as nodes, relative-pose measurements (scan to map, loop closures) as edges,
// solved by sparse Gauss-Newton so that a loop found late spreads its error over the whole loop.
#pragma once

#include <cstddef>
#include <vector>

#include "tripodal/core/geometry.hpp"

namespace tripodal::navi {

/// How much an edge is trusted: the standard deviations of its measured relative pose.
struct EdgeNoise {
  double sigma_xy_m = 0.05;
  double sigma_theta_rad = 0.02;
};

struct PoseGraphOptions {
  int max_iterations = 30;
  /// Converged when no pose moves by more than this (metres, and radians alike).
  double tolerance = 1e-6;
  /// Robust edges (loop closures) are weighted down beyond this normalised error (Huber), so that
  /// one wrong closure bends the graph less than it would with squares.
  double huber_delta = 1.5;
  /// After solving, a robust edge whose chi-square (its error squared over its noise, 3 degrees of
  /// freedom) still exceeds this is dropped and the graph solved again: at this value a right
  /// closure is dropped with a probability below 1e-4.
  double outlier_chi2 = 21.1;
};

/// What a solve did.
struct PoseGraphReport {
  int iterations = 0;
  double initial_chi2 = 0.0;  ///< sum over the kept edges, before
  double final_chi2 = 0.0;    ///< and after
  std::size_t rejected = 0;   ///< robust edges dropped as outliers by this solve
};

/// Nodes are poses in the map frame; node 0 is held fixed (it anchors the map frame).
class PoseGraph {
 public:
  explicit PoseGraph(PoseGraphOptions options = {});

  /// Adds a node at its initial estimate; returns its index (0, 1, ...). Throws
  /// std::invalid_argument for a non-finite pose.
  std::size_t add_node(const Pose2D& estimate);
  /// A measurement of node `to` in the frame of node `from` (from_to = inverse(from) * to).
  /// `robust`: a loop closure, which may be wrong (Huber weight, rejected as an outlier).
  /// Throws std::invalid_argument for an unknown node, from == to, a non-finite measurement or a
  /// noise that is not > 0.
  void add_edge(std::size_t from, std::size_t to, const Pose2D& from_to, const EdgeNoise& noise, bool robust = false);

  /// Gauss-Newton on every node but node 0, outlier closures dropped (PoseGraphOptions).
  PoseGraphReport optimize();

  [[nodiscard]] std::size_t size() const noexcept { return poses_.size(); }
  [[nodiscard]] const Pose2D& pose(std::size_t i) const { return poses_.at(i); }
  [[nodiscard]] const std::vector<Pose2D>& poses() const noexcept { return poses_; }
  /// Edges added, rejected ones included (edge k is the k-th add_edge).
  [[nodiscard]] std::size_t edge_count() const noexcept { return edges_.size(); }
  /// The chi-square of edge k (the order of add_edge) at the current poses.
  [[nodiscard]] double chi2(std::size_t k) const;
  /// Whether edge k was dropped as an outlier.
  [[nodiscard]] bool rejected(std::size_t k) const { return edges_.at(k).rejected; }

 private:
  struct Edge {
    std::size_t from, to;
    Pose2D z;
    double w_xy, w_theta;  // information: 1 / sigma^2
    bool robust, rejected = false;
  };
  [[nodiscard]] double solve_chi2() const;
  int gauss_newton();

  PoseGraphOptions options_;
  std::vector<Pose2D> poses_;
  std::vector<Edge> edges_;
};

}  // namespace tripodal::navi
