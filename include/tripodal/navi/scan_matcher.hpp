// The laser scan matcher of the navigation modules (sequencing layer): it places a 2D laser scan on
// a known occupancy grid, near a predicted pose (tracking) or anywhere on the map (global
// localization). The scan-matching localizer and the map builder are built on it.
#pragma once

#include <array>
#include <cstddef>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::navi {

struct ScanMatcherOptions {
  double sigma_m = 0.1;              ///< spread of the likelihood field around the walls
  double max_range_m = 30.0;         ///< returns farther than this are not matched
  int max_points = 360;              ///< beams beyond this are decimated evenly (bounds the cost)
  double search_xy_m = 0.25;         ///< half width of the tracking window around the prediction
  double search_theta_rad = 0.2;     ///< half width of the tracking window in heading
  double angular_step_rad = 0.01;    ///< heading step of the discrete searches
  /// The largest tracking window a caller may ask for (the score buffer is sized for it).
  double max_search_xy_m = 1.0;
  double max_search_theta_rad = 0.8;
  /// Global search: headings step and the farthest point used (farther points would need finer
  /// heading steps to stay within a cell, so the global search drops them).
  double global_angular_step_rad = 0.02;
  double global_max_range_m = 12.0;
  int global_levels = 6;             ///< branch-and-bound tiles of 2^levels cells at the top
  /// Budget of the global search, in bounds evaluated below the top tiles (each one pass over the
  /// scan's points; the top tiles of every heading are always bounded, to order the search): the
  /// search stops there and returns the best pose found so far, marked not exhaustive, so that
  /// its descent no longer grows with the map (issue 41: 5.9 s on the infinite corridor). Blocks
  /// without a free cell are never bounded (no pose can be there). 0: no budget.
  int global_max_nodes = 400000;
  /// Where a wall's surface lies in the map's cells. A map built from scans (SLAM, MapBuilder, the
  /// CARMEN logs) marks the cell a return fell in: the surface lies inside the wall's boundary
  /// cells, at their centre on average (false). A map drawn as solid cells (a floor plan, the
  /// simulator's world, whose beams stop at an occupied cell's face) has it on the face between
  /// an occupied cell and an open one (true). Matching with the wrong one biases every match by
  /// half a cell towards the nearer walls (docs/localization.md).
  bool surface_at_cell_face = false;
};

/// How a tracker sizes its search: the odometry errs more the more the robot moves, so the window
/// grows by these much per metre travelled and per radian turned since the last scan (up to the
/// matcher's max_search_*); a match below retry_quality is searched again in the widest window
/// (the odometry sometimes errs by more than the window: a wheel slipping in a turn).
struct TrackingWindow {
  double m_per_m = 0.2;
  double rad_per_rad = 0.3;
  double rad_per_m = 0.1;
  double retry_quality = 0.8;
};

/// The median quality of a tracker's recent good matches: what "a usual match" scores on this map
/// with this scanner. Absolute thresholds do not transfer between logs (right matches score 0.35
/// on one, wrong ones 0.95 on another); a drop from the recent median does. No allocation.
class RecentQualities {
 public:
  static constexpr std::size_t kSize = 64;
  static constexpr std::size_t kMin = 5;  ///< fewer samples: no judgement (typical() is 0)
  void add(double quality) noexcept;
  [[nodiscard]] double typical() const noexcept;
  void clear() noexcept { count_ = 0; }

 private:
  std::array<float, kSize> q_{};
  std::size_t count_ = 0;
};

/// Throws ConfigError located at where naming every option out of its range.
void validate(const ScanMatcherOptions& options, const SourceLocation& where = {});

/// A match: the pose (map_from_base), its covariance (x, y, theta; row-major) and the quality, the
/// mean likelihood of the matched points in [0, 1] (1: every point on a wall of the map).
struct ScanMatch {
  Pose2D pose;
  std::array<double, 9> covariance{};
  double quality = 0.0;
  std::size_t points = 0;  ///< points matched
  /// Global search only: bounds evaluated, and false when the budget stopped it before every
  /// branch was pruned (the pose is then the best found, not provably the best).
  std::size_t nodes = 0;
  bool exhaustive = true;
};

/// A likelihood-field matcher: each cell holds exp(-d^2 / 2 sigma^2), d the distance to the
/// nearest wall surface (navi::DistanceField); a pose scores the sum over the scan's points.
/// Tracking is a correlative search (every heading step x every cell of the window, the
/// translations as index offsets of the rotated points, pruned by a branch and bound over the
/// max-pooled fields) followed by a sub-cell hill climb on the bilinear field; the covariance
/// comes from the score distribution around the best pose. Its inner loops use SSE2 where the
/// target has it, with the scalar code's operations in its order: the same doubles either way.
/// The global search is a branch and bound over max-pooled fields (as Cartographer's), so its
/// answer is the best pose of the discretisation, not a sampled guess. Every buffer is sized at
/// construction: set_scan() and match() do not allocate.
class ScanMatcher {
 public:
  /// Precomputes the fields of `map` (O(cells x levels)). Throws ConfigError located at where
  /// for options out of range or a map without occupied cells.
  ScanMatcher(const OccupancyGrid& map, ScanMatcherOptions options = {}, const SourceLocation& where = {});

  /// Takes the points of `scan` as seen from the base (base_from_laser: the scanner's mounting).
  /// Returns the number of points kept (valid returns within max_range_m, decimated).
  std::size_t set_scan(const LaserScan& scan, const Pose2D& base_from_laser = {}) noexcept;
  [[nodiscard]] std::size_t points() const noexcept { return px_.size(); }

  /// Best pose within the tracking window around `predicted`.
  [[nodiscard]] ScanMatch match(const Pose2D& predicted) noexcept {
    return match(predicted, options_.search_xy_m, options_.search_theta_rad);
  }
  /// The same in a window of the given half widths (clipped to max_search_*).
  [[nodiscard]] ScanMatch match(const Pose2D& predicted, double search_xy_m, double search_theta_rad) noexcept;
  /// Tracking: the best pose around `predicted` in a window sized by the motion (odometry) since
  /// the last scan, searched again in the widest window when the match is poor.
  [[nodiscard]] ScanMatch track(const Pose2D& predicted, const Pose2D& motion, const TrackingWindow& window) noexcept;
  /// Best pose anywhere on the free cells of the map.
  [[nodiscard]] ScanMatch match_global();
  /// Quality (mean likelihood of the points) of the scan at `pose`, without searching.
  [[nodiscard]] double quality_at(const Pose2D& pose) const noexcept;
  /// The quality of the evidence at `pose`: the mean likelihood of the points the map can
  /// explain. A point within 2 m, far from every wall, whose beam crosses no wall of the map
  /// stopped on something the map does not hold (a cart, a person): it says nothing about the
  /// pose and is left out. At most a third of the points are left out (more would leave too
  /// little of the map to vouch for the pose): beyond, this is quality_at(). Never below
  /// quality_at().
  [[nodiscard]] double explained_quality(const Pose2D& pose) const noexcept;

  [[nodiscard]] const ScanMatcherOptions& options() const noexcept { return options_; }
  [[nodiscard]] const OccupancyGrid& map() const noexcept { return map_; }

 private:
  struct GridPose {
    double x = 0.0, y = 0.0, theta = 0.0;  // grid frame, in cells and radians
  };
  [[nodiscard]] GridPose to_grid(const Pose2D& p) const noexcept;
  [[nodiscard]] Pose2D from_grid(const GridPose& g) const noexcept;
  [[nodiscard]] double score_bilinear(const GridPose& g) const noexcept;
  // The climb from g; its score (score_bilinear of the pose returned) in *score.
  [[nodiscard]] GridPose hill_climb(GridPose g, double step_cells, double step_rad, double* score) const noexcept;
  // A heading's points rotated into the grid: the cell of each point as an offset from the cell of
  // the window's centre, and its index in the padded fields (pooled_) when every cell the tracking
  // search may read for it (up to `reach` cells away) lies in the padded grid, else -1 (those
  // points are read with a check each).
  struct Rotated {
    int* cx;
    int* cy;
    int* at;
  };
  [[nodiscard]] Rotated rotated(std::size_t heading, std::size_t count) noexcept;
  void rotate_points(double theta, double x, double y, std::size_t count, int reach, const Rotated& out) const noexcept;
  // The sums over the points of the padded field of `level` at kSums offsets (dx[j], dy[j]) in one
  // pass (independent accumulators). Each sum adds the points in their order, a point outside the
  // padded grid adding nothing: level 0 gives the exact score of a cell, a level above a bound.
  template <int kSums>
  void padded_sums(int level, const Rotated& r, std::size_t count, const int* dx, const int* dy, float* out) const noexcept;
  void padded_sums(int level, const Rotated& r, std::size_t count, const int* dx, const int* dy, int m,
                   float* out) const noexcept;
  // The exact scores of kCells adjacent cells (dx ... dx + kCells - 1, dy) in one pass.
  template <int kCells>
  void row_sums(const Rotated& r, std::size_t count, int dx, int dy, float* out) const noexcept;
  [[nodiscard]] float pooled_sum(int level, const int* cx, const int* cy, std::size_t count, int x, int y) const noexcept;
  ScanMatch finish(const GridPose& best, double sum_w, const std::array<double, 6>& moments) const noexcept;

  OccupancyGrid map_;
  ScanMatcherOptions options_;
  double cell_m_ = 0.05;
  int width_ = 0, height_ = 0;
  std::vector<float> field_;                 // the likelihood field, width x height
  // pooled_[h]: max of the field over the 2^h x 2^h cells from (x, y), on the domain extended
  // by pad_ cells of zeros on every side (a tile partly outside the grid still bounds its inside);
  // pooled_[0] is the field itself, padded
  std::vector<std::vector<float>> pooled_;
  int pad_ = 1;
  std::vector<float> px_, py_, range_;       // points in the base frame, metres
  double origin_x_ = 0.0, origin_y_ = 0.0;   // the scanner in the base frame, metres
  std::vector<int> cx_, cy_, at_;            // rotated points of every heading of the window (Rotated)
  struct Block {
    float bound;
    int k, dx, dy;
  };
  std::vector<Block> blocks_;                // the window's 2 x 2-cell blocks, by heading
  std::vector<int> gcx_, gcy_;               // rotated points for every global heading
  // free_sum_[(y + 1) * (width_ + 1) + x + 1]: free cells in [0, x] x [0, y] (an integral image):
  // the global search skips every block without a free cell, where no pose can be
  std::vector<int> free_sum_;
  [[nodiscard]] bool any_free(int x, int y, int side) const noexcept;
};

}  // namespace tripodal::navi
