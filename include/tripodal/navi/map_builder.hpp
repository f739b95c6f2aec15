// MapBuilder, the occupancy-grid mapper of the navigation modules (sequencing layer): it builds the
// map a robot is later localized on from its laser and odometry while it is driven by hand (the
// thesis's mapping run), matching each scan against the map made so far with navi::ScanMatcher.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <vector>

#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/navi/pose_graph.hpp"
#include "tripodal/navi/scan_matcher.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::navi {

/// Loop closure: the builder keeps a pose graph of key scans (one every keyframe_m or
/// keyframe_rad of motion) joined by their scan-to-map matches; now and then it matches the
/// current scan against a local map of the key scans it passed long ago near where it believes it
/// is, and when that match passes the acceptance test the graph gains a closure, is solved, and
/// the map is drawn again from the key scans at their solved poses (docs/localization.md, "Loop
/// closure"). A good match alone is not enough (issue 41: look-alike corridors bent CSAIL and the
/// Freiburg campus): the correction must be one the drift since the candidate can explain, the
/// agree_keyframes - 1 key scans before must each find the same correction by their own search
/// (the widest tracking window around where it puts them), and the best place outside
/// exclusion_m of the winner must score distinct_margin lower.
struct LoopClosureOptions {
  bool enabled = true;
  double keyframe_m = 0.2;
  double keyframe_rad = 0.2;
  int every_keyframes = 10;       ///< a closure is looked for at every this many key scans
  double min_travel_m = 10.0;     ///< with key scans at least this far back along the path
  double search_radius_m = 5.0;   ///< near the current estimate (the drift a closure can undo)
  int submap_keyframes = 10;      ///< key scans on each side of the candidate make its local map
  double min_quality = 0.55;      ///< the closure's match quality
  /// Agreement: this many consecutive key scans (the current one and those before it) are each
  /// matched on the local map, and their corrections of the graph must agree within
  /// agree_m / agree_rad (one scan in a corridor fits several places; three seen from 0.4 m
  /// apart rarely pick the same wrong one).
  int agree_keyframes = 3;
  double agree_m = 0.15;
  double agree_rad = 0.05;
  /// Distinctness: the best pose more than exclusion_m from the winner (the local map's free cells
  /// there are hidden from a second global search) must score at least distinct_margin lower.
  double exclusion_m = 1.0;
  double distinct_margin = 0.05;
  /// Graph consistency: the closure may move the current key scan by at most
  /// drift_base_m + drift_m_per_m x (the travel since the candidate), and turn it by at most
  /// drift_base_rad + drift_rad_per_m x that travel: what scan-to-map drift can explain.
  double drift_base_m = 0.5;
  double drift_m_per_m = 0.05;
  double drift_base_rad = 0.1;
  double drift_rad_per_m = 0.005;
  /// The local map is drawn this coarse: the global search over it costs a quarter of the
  /// builder's 5 cm, and its sub-cell refinement keeps the closure within the closure noise.
  double submap_resolution_m = 0.05;
  /// A closure whose disagreement with the graph its own error explains (its chi-square under
  /// closure_noise at most this: 7.81, chi-square with 3 degrees of freedom at 95 %) is kept
  /// without a solve: it shows no drift beyond the closure's own error, and a solve would bend a
  /// consistent map by that error. Issue 41: CSAIL's one solve (5 cm and 0.013 rad off,
  /// chi-square 1.5) turned the path after the loose edges beside the candidate by 1 degree
  /// (0.075 -> 0.322 m from the start); on the six logs it was looked at on, every solve was at
  /// 1.1-4.8, and as many made the map worse as better (docs/localization.md).
  double settled_chi2 = 7.81;
  EdgeNoise match_noise{.sigma_xy_m = 0.02, .sigma_theta_rad = 0.01};     ///< scan to map
  EdgeNoise odometry_noise{.sigma_xy_m = 0.1, .sigma_theta_rad = 0.05};   ///< a poor match: odometry
  EdgeNoise closure_noise{.sigma_xy_m = 0.05, .sigma_theta_rad = 0.02};
};

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
  /// The localizer's window, grown with the motion and retried wide on a poor match: CSAIL's
  /// odometry errs by more than 0.2 rad between scans, and a fixed window left its map in pieces
  /// (10 s relative error 7.9 m against 0.22 m; Intel and ACES within 5 mm either way:
  /// docs/localization.md).
  TrackingWindow window{};
  /// A match below this quality (new ground, clutter) is no better than the odometry: the scan
  /// is inserted at the predicted pose.
  double min_quality = 0.2;
  /// Recovery from an odometry jump (seattle's odometry misses an 80 degree turn between two
  /// scans, beyond any tracking window): a match more than recovery_margin below the median of
  /// the recent matches is searched again over every heading within the widest window around the
  /// odometry's position, and that match is taken when it is a usual one (within recovery_margin
  /// of the median), better than the tracked one by recovery_gain, and turns the pose by no more
  /// than the odometry turned over the last ten scans (+ recovery_tolerance_rad): a jump
  /// of the odometry is undone, a turn it never reported is not made. Otherwise the weak match is
  /// taken only if it stays within recovery_tolerance (+ 0.3 per metre / radian moved) of the
  /// odometry's prediction. 0 margin: off.
  double recovery_margin = 0.15;
  double recovery_gain = 0.05;
  /// The recovery searches headings up to this far from the odometry's: a missed turn (seattle's
  /// 1.41 rad), not the half turn a symmetric corridor matches at.
  double recovery_max_turn_rad = 2.4;
  double recovery_tolerance_m = 0.3;
  double recovery_tolerance_rad = 0.25;
  /// Odometry fallback: when more than fallback_share of the last fallback_scans (at most 64)
  /// matches were untrusted (weak and not recovered), the matcher is not believed there at all:
  /// a weak match is never taken, a usual one only within recovery_tolerance of the odometry,
  /// and the scan is inserted where the odometry puts it. Issue 41: on the infinite corridor
  /// 1,592 of 1,941 matches were weak, and taking those within the tolerance (0.3 m per scan,
  /// sliding along the corridor) made the map 13.4 m off aligned against the odometry's 3.5 m.
  /// Off by default (1.0): at 0.75 (15 of 20; CSAIL, tuned on, has 12 of 20 once) it halved the
  /// corridor's error but worsened fhw, acapulco and the campus (docs/localization.md).
  int fallback_scans = 20;
  double fallback_share = 1.0;
  LoopClosureOptions loop;
};

/// What the builder thought of its own matches.
struct MappingHealth {
  std::size_t scans = 0;
  std::size_t weak = 0;          ///< matches far below the recent median (a search of all headings followed)
  std::size_t recovered = 0;     ///< of those, replaced by a match at another heading
  std::size_t unreliable = 0;    ///< the others: the weak match, or the odometry where they disagree
  /// Scans inserted at the odometry's prediction because most recent matches were untrusted
  /// (the odometry fallback of MapBuilderOptions), their match not taken.
  std::size_t odometry_only = 0;
  /// Scans seen while the fallback was on (whether their match was taken or not).
  std::size_t in_fallback = 0;
};

/// What the loop closure did so far.
struct LoopClosureStats {
  std::size_t keyframes = 0;
  std::size_t attempts = 0;   ///< local matches tried
  std::size_t weak = 0;       ///< refused: no match of min_quality within search_radius_m
  std::size_t implausible = 0;  ///< refused: a correction larger than the drift since can explain
  std::size_t disagreeing = 0;  ///< refused: the consecutive key scans found different corrections
  std::size_t ambiguous = 0;    ///< refused: another place scored nearly as well
  std::size_t closures = 0;   ///< kept in the graph
  std::size_t settled = 0;    ///< of those, within their own noise of the graph when found: no solve
  std::size_t rejected = 0;   ///< dropped by the solver as disagreeing with the rest
  std::size_t solves = 0;     ///< graph solves, each followed by a redraw of the map
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
  /// The pose of every scan given to add(), as the graph now places it (after the last solve;
  /// add() returned the estimate at the time).
  [[nodiscard]] std::vector<Pose2D> trajectory() const;
  [[nodiscard]] const LoopClosureStats& loop_stats() const noexcept { return stats_; }
  [[nodiscard]] const MappingHealth& health() const noexcept { return health_; }
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
  void add_keyframe(const LaserScan& scan, const Pose2D& base_from_laser, bool matched);
  void try_closure();
  // The refusals of try_closure(), in the order they are checked; true: accepted.
  [[nodiscard]] bool closure_accepted(ScanMatcher& matcher, const OccupancyGrid& submap, const ScanMatch& best,
                                      std::size_t candidate);
  void redraw();
  [[nodiscard]] ScanMatch rematch_all_headings() noexcept;
  // Whether a match moves the pose beyond recovery_tolerance (+ 0.3 per metre / radian moved) of
  // the odometry's prediction.
  [[nodiscard]] bool far_from_odometry(const Pose2D& match, const Pose2D& motion) const noexcept;
  // Whether more than fallback_share of the last fallback_scans matches were untrusted.
  [[nodiscard]] bool fallback_on() const noexcept;
  [[nodiscard]] double recent_turn_rad() const noexcept;
  struct Keyframe {
    LaserScan scan;
    Pose2D base_from_laser;
    double travel_m;
  };
  struct ScanRef {
    std::size_t keyframe;
    Pose2D keyframe_from_base;
  };
  MapBuilderOptions options_;
  ScanMatcherOptions closure_matcher_;  // the caller's matcher options, global levels kept
  int width_ = 0, height_ = 0;
  Pose2D origin_;
  std::vector<float> log_odds_;
  std::unique_ptr<ScanMatcher> matcher_;
  int since_refresh_ = 0;
  bool started_ = false;
  Pose2D pose_, last_odom_;
  double last_quality_ = 0.0;
  PoseGraph graph_;
  std::vector<Keyframe> keyframes_;
  std::vector<ScanRef> scans_;
  double travel_m_ = 0.0;
  LoopClosureStats stats_;
  RecentQualities qualities_;
  MappingHealth health_;
  std::uint64_t untrusted_bits_ = 0;  // the last fallback_scans matches, bit 0 the newest: 1 untrusted
  int recorded_ = 0;                  // matches recorded in untrusted_bits_ (up to fallback_scans)
  // the odometry's turn (absolute) over the last ten scans, this one included: what a recovery
  // may undo (seattle's jump is found weak a few scans after it)
  std::array<double, 10> turns_rad_{};
  std::size_t turn_next_ = 0;
};

}  // namespace tripodal::navi
