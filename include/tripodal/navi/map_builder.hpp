// MapBuilder, the occupancy-grid mapper of the navigation modules (sequencing layer): it builds the
// map a robot is later localized on from its laser and odometry while it is driven by hand (the
// thesis's mapping run), matching each scan against the map made so far with navi::ScanMatcher.
#pragma once

#include <memory>
#include <vector>

#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/navi/scan_matcher.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::navi {

struct MapBuilderOptions {
  double resolution_m = 0.05;
  double max_range_m = 30.0;     ///< beams beyond this (or at the scanner's maximum) are not inserted
  /// Evidence of an end point: strong enough that a wall seen once survives the miss of a beam
  /// grazing it later (with 0.85, a miss turned it back to unknown, and the Intel relative errors
  /// were twice as large: docs/localization.md).
  double hit_log_odds = 2.5;
  double miss_log_odds = -0.4;   ///< evidence of a cell a beam crossed
  double clamp_log_odds = 5.0;   ///< bound on the evidence, so that a cell can change its state
  /// The matcher's map is refreshed from the grid every this many scans (a refresh recomputes
  /// the distance field of the window, O(cells)); every scan: the last scan is matched too.
  int refresh_every_scans = 1;
  /// The matcher sees the map within this distance of the robot (a square): the cost of a
  /// refresh stays bounded however large the map grows.
  double window_m = 15.0;
  ScanMatcherOptions matcher;
  /// A fixed window, no wide retry: on a map still being made, a poor match is mostly new
  /// ground, and a wider search there snaps to the wrong wall (on the Intel log, the localizer's
  /// growing window doubles the relative errors: docs/localization.md).
  TrackingWindow window{.m_per_m = 0.0, .rad_per_rad = 0.0, .rad_per_m = 0.0, .retry_quality = 0.0};
  /// A match below this quality (new ground, clutter) is no better than the odometry: the scan
  /// is inserted at the predicted pose.
  double min_quality = 0.2;
};

/// Log-odds occupancy grid over a fixed extent, with scan-to-map matching. Scans are inserted by
/// casting each beam cell by cell (free cells up to the end point, the end point occupied).
class MapBuilder {
 public:
  /// A grid covering [lower, upper] (map frame, metres). Throws ConfigError for an empty or
  /// too large extent (more than kMaxPgmPixels cells) or bad options.
  MapBuilder(Point2D lower, Point2D upper, MapBuilderOptions options = {});
  ~MapBuilder();

  /// Inserts a scan taken at map_from_base (no matching): a map from known poses.
  void insert(const LaserScan& scan, const Pose2D& map_from_base, const Pose2D& base_from_laser = {});
  /// Scan-to-map: predicts from the odometry (odom_from_base) since the previous call, corrects by
  /// matching against the map made so far, inserts, and returns the pose. The first scan is
  /// inserted at `start`.
  Pose2D add(const LaserScan& scan, const Pose2D& odom_from_base, const Pose2D& start = {},
             const Pose2D& base_from_laser = {});
  /// The quality of the last match (0 before the matcher has a map).
  [[nodiscard]] double last_quality() const noexcept { return last_quality_; }

  /// The map as map_server would publish it: occupied above p = 0.65, free below 0.196.
  [[nodiscard]] OccupancyGrid grid() const;
  /// The same over the cells within window_m of `center` (clipped to the grid).
  [[nodiscard]] OccupancyGrid grid_around(Point2D center) const;
  /// The same over the cells of the box [lower, upper] (map frame, clipped to the grid).
  [[nodiscard]] OccupancyGrid grid_within(Point2D lower, Point2D upper) const;

 private:
  [[nodiscard]] OccupancyGrid grid_of(int x0, int y0, int x1, int y1) const;
  MapBuilderOptions options_;
  int width_ = 0, height_ = 0;
  Pose2D origin_;
  std::vector<float> log_odds_;
  std::unique_ptr<ScanMatcher> matcher_;
  int since_refresh_ = 0;
  bool started_ = false;
  Pose2D pose_, last_odom_;
  double last_quality_ = 0.0;
};

}  // namespace tripodal::navi
