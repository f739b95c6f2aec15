#include "tripodal/navi/pose_graph.hpp"

#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tripodal::navi {

namespace {

bool finite(const Pose2D& p) noexcept {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
}

// The error of a measurement z of xj in the frame of xi: z^-1 * (xi^-1 * xj) as (x, y, theta),
// with its Jacobians with respect to xi (a) and xj (b).
struct Linearized {
  Eigen::Vector3d e;
  Eigen::Matrix3d a, b;
};

Linearized linearize(const Pose2D& xi, const Pose2D& xj, const Pose2D& z) noexcept {
  const double ci = std::cos(xi.theta_rad), si = std::sin(xi.theta_rad);
  const double cz = std::cos(z.theta_rad), sz = std::sin(z.theta_rad);
  const double dx = xj.x_m - xi.x_m, dy = xj.y_m - xi.y_m;
  // xj in the frame of xi
  const double lx = ci * dx + si * dy, ly = -si * dx + ci * dy;
  Linearized l;
  l.e << cz * (lx - z.x_m) + sz * (ly - z.y_m), -sz * (lx - z.x_m) + cz * (ly - z.y_m),
      wrap_angle(xj.theta_rad - xi.theta_rad - z.theta_rad);
  Eigen::Matrix2d rz_t, ri_t, dri_t;
  rz_t << cz, sz, -sz, cz;
  ri_t << ci, si, -si, ci;
  dri_t << -si, ci, -ci, -si;  // d(Ri^T)/d(theta_i)
  const Eigen::Vector2d d(dx, dy);
  l.a.setZero();
  l.a.topLeftCorner<2, 2>() = -rz_t * ri_t;
  l.a.topRightCorner<2, 1>() = rz_t * dri_t * d;
  l.a(2, 2) = -1.0;
  l.b.setZero();
  l.b.topLeftCorner<2, 2>() = rz_t * ri_t;
  l.b(2, 2) = 1.0;
  return l;
}

}  // namespace

PoseGraph::PoseGraph(PoseGraphOptions options) : options_(options) {}

std::size_t PoseGraph::add_node(const Pose2D& estimate) {
  if (!finite(estimate)) throw std::invalid_argument("pose graph: a node's pose must be finite");
  poses_.push_back(estimate);
  return poses_.size() - 1;
}

void PoseGraph::add_edge(std::size_t from, std::size_t to, const Pose2D& from_to, const EdgeNoise& noise, bool robust) {
  if (from >= poses_.size() || to >= poses_.size() || from == to) {
    throw std::invalid_argument("pose graph: an edge joins two different nodes of the graph, got " + std::to_string(from) +
                                " -> " + std::to_string(to) + " with " + std::to_string(poses_.size()) + " nodes");
  }
  if (!finite(from_to)) throw std::invalid_argument("pose graph: an edge's measurement must be finite");
  if (!(noise.sigma_xy_m > 0.0 && noise.sigma_theta_rad > 0.0 && std::isfinite(noise.sigma_xy_m) &&
        std::isfinite(noise.sigma_theta_rad))) {
    throw std::invalid_argument("pose graph: an edge's noise must be > 0");
  }
  edges_.push_back({from, to, from_to, 1.0 / (noise.sigma_xy_m * noise.sigma_xy_m),
                    1.0 / (noise.sigma_theta_rad * noise.sigma_theta_rad), robust});
}

double PoseGraph::chi2(std::size_t k) const {
  const Edge& edge = edges_.at(k);
  const Eigen::Vector3d e = linearize(poses_[edge.from], poses_[edge.to], edge.z).e;
  return edge.w_xy * (e(0) * e(0) + e(1) * e(1)) + edge.w_theta * e(2) * e(2);
}

double PoseGraph::solve_chi2() const {
  double sum = 0.0;
  for (std::size_t k = 0; k < edges_.size(); ++k) {
    if (!edges_[k].rejected) sum += chi2(k);
  }
  return sum;
}

int PoseGraph::gauss_newton() {
  const std::size_t n = poses_.size();
  if (n < 2) return 0;
  const auto dim = static_cast<Eigen::Index>(3 * (n - 1));  // node 0 is fixed: not a variable
  std::vector<Eigen::Triplet<double>> triplets;
  triplets.reserve(edges_.size() * 36 + static_cast<std::size_t>(dim));
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver;
  Eigen::SparseMatrix<double> h(dim, dim);
  Eigen::VectorXd g(dim);
  int it = 0;
  while (it < options_.max_iterations) {
    ++it;
    triplets.clear();
    g.setZero();
    for (const Edge& edge : edges_) {
      if (edge.rejected) continue;
      const Linearized l = linearize(poses_[edge.from], poses_[edge.to], edge.z);
      Eigen::Vector3d w(edge.w_xy, edge.w_xy, edge.w_theta);
      if (edge.robust) {
        const double s = std::sqrt(w.dot(l.e.cwiseProduct(l.e)));
        if (s > options_.huber_delta) w *= options_.huber_delta / s;
      }
      const Eigen::Matrix3d omega = w.asDiagonal();
      const std::size_t nodes[2] = {edge.from, edge.to};
      const Eigen::Matrix3d* jac[2] = {&l.a, &l.b};
      for (int r = 0; r < 2; ++r) {
        if (nodes[r] == 0) continue;
        const auto ri = static_cast<Eigen::Index>(3 * (nodes[r] - 1));
        g.segment<3>(ri) += jac[r]->transpose() * omega * l.e;
        for (int c = 0; c < 2; ++c) {
          if (nodes[c] == 0) continue;
          const auto ci = static_cast<Eigen::Index>(3 * (nodes[c] - 1));
          const Eigen::Matrix3d block = jac[r]->transpose() * omega * *jac[c];
          for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) triplets.emplace_back(ri + i, ci + j, block(i, j));
          }
        }
      }
    }
    // A node no edge reaches stays where it is instead of making the system singular.
    for (Eigen::Index i = 0; i < dim; ++i) triplets.emplace_back(i, i, 1e-9);
    h.setFromTriplets(triplets.begin(), triplets.end());
    if (it == 1) solver.analyzePattern(h);
    solver.factorize(h);
    if (solver.info() != Eigen::Success) break;
    const Eigen::VectorXd dx = solver.solve(-g);
    double largest = 0.0;
    for (std::size_t i = 1; i < n; ++i) {
      const auto k = static_cast<Eigen::Index>(3 * (i - 1));
      Pose2D& p = poses_[i];
      p.x_m += dx(k);
      p.y_m += dx(k + 1);
      p.theta_rad = wrap_angle(p.theta_rad + dx(k + 2));
      largest = std::max({largest, std::abs(dx(k)), std::abs(dx(k + 1)), std::abs(dx(k + 2))});
    }
    if (largest < options_.tolerance) break;
  }
  return it;
}

PoseGraphReport PoseGraph::optimize() {
  PoseGraphReport report;
  report.initial_chi2 = solve_chi2();
  const std::vector<Pose2D> start = poses_;
  report.iterations = gauss_newton();
  // Drop the worst closure beyond the threshold and solve again from the start, until every kept
  // closure agrees with the rest: one wrong closure also inflates the errors of right ones, so
  // they are dropped one at a time, worst first.
  for (;;) {
    std::size_t worst = edges_.size();
    double worst_chi2 = options_.outlier_chi2;
    for (std::size_t k = 0; k < edges_.size(); ++k) {
      if (!edges_[k].robust || edges_[k].rejected) continue;
      const double c = chi2(k);
      if (c > worst_chi2) {
        worst_chi2 = c;
        worst = k;
      }
    }
    if (worst == edges_.size()) break;
    edges_[worst].rejected = true;
    ++report.rejected;
    poses_ = start;
    report.iterations += gauss_newton();
  }
  report.final_chi2 = solve_chi2();
  return report;
}

}  // namespace tripodal::navi
