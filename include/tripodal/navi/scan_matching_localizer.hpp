// CScanMatchingLocalizer, the localizer navigation module for a real robot (sequencing layer): it
// predicts the pose from the wheel odometry and corrects it by matching each laser scan against the
// known map (navi::ScanMatcher), and drives the process PrCleaning's places P3/P4 ("normal" /
// "abnormal localization") from its own evidence: localizer.lost when the match quality stays low,
// localizer.ok when it recovers. relocalize() is the global search of PrGlobalLocalization.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/navi/scan_matcher.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::navi {

struct ScanMatchingLocalizerOptions {
  ScanMatcherOptions matcher;
  Pose2D base_from_laser;         ///< the scanner's mounting on the base
  Pose2D initial_pose;            ///< map_from_base at start, unless start_global
  bool start_global = false;      ///< find the start pose by a global search on the first scan
  double lost_quality = 0.7;      ///< a match below this quality is no evidence of the pose...
  int lost_after_scans = 5;       ///< ...and this many in a row make the robot lost
  /// A global search is accepted at or above this quality (higher than lost_quality: a wrong
  /// place that happens to explain part of the scan must not pass).
  double relocalize_quality = 0.75;
  TrackingWindow window;          ///< how the search window follows the odometry
  /// An odometry increment longer than this between two scans is a reset of the odometry's
  /// origin (the simulator's, when `tripodal run` puts the robot on its start pose), not motion;
  /// 0: every increment is motion (logs whose scans are far apart, `localization eval`).
  double odometry_reset_m = 1.0;
  /// Self-judgement (docs/localization.md, "No silent failure"). A match that moves the pose away
  /// from the odometry's prediction by more than odometry_tolerance (plus a share of the motion)
  /// is taken only when its quality is typical of this robot's recent matches: at most
  /// consistency_margin below their median. Otherwise it is "unreliable": the pose follows the
  /// odometry, and lost_after_scans such scans in a row make the robot lost. Absolute quality
  /// thresholds do not transfer between logs (right matches score 0.35 on one, wrong ones 0.95 on
  /// another); the disagreement with the odometry and the drop from the recent median do.
  double odometry_tolerance_m = 0.3;
  double odometry_tolerance_rad = 0.25;
  double tolerance_per_motion = 0.3;   ///< added tolerance, per metre (m) and per radian (rad) moved
  double consistency_margin = 0.1;
};

/// How the last scan was judged.
enum class ScanVerdict {
  kNone,          ///< no scan yet, or no map
  kConsistent,    ///< matched, and taken
  kNoEvidence,    ///< quality below lost_quality: the pose follows the odometry
  kInconsistent,  ///< a match far from the odometry's prediction and weaker than usual: not taken
};

/// Type "ScanMatchingLocalizer". As a module of the robot it takes the map of the GridMaps module
/// at start, the laser and the odometry from the robot's resources (the first of each kind unless
/// named), matches every new scan, publishes the estimate and keeps the supervisor's watchdog fed;
/// while BhGlobalLocalization is active it runs the global search every attempt_period_s.
class CScanMatchingLocalizer final : public CNaviModules {
 public:
  explicit CScanMatchingLocalizer(ScanMatchingLocalizerOptions options = {});
  ~CScanMatchingLocalizer() override;

  static const ModuleManifest& static_manifest();

  /// Gives the map directly (tests, tools) instead of the GridMaps module; builds the matcher.
  void set_map(const OccupancyGrid& map);

  /// One scan with the odometry pose (odom_from_base) read with it: predict, match, post
  /// localizer.ok / localizer.lost into `out` on a change. Does not allocate once started (an
  /// event's text is built only on a change). Precondition: a map (set_map or start).
  void step(const LaserScan& scan, const Pose2D& odom_from_base, Time now, std::vector<ModuleEvent>& out);
  /// Global localization on the last scan: accepted when its quality reaches relocalize_quality;
  /// the next step then posts localizer.ok. Returns whether it was accepted.
  bool relocalize();

  [[nodiscard]] const Pose2D& estimate() const noexcept { return pose_; }
  [[nodiscard]] const ScanMatch& last_match() const noexcept { return last_; }
  [[nodiscard]] bool localized() const noexcept { return state_ == State::ok; }
  [[nodiscard]] ScanVerdict last_verdict() const noexcept { return verdict_; }
  /// Scans judged unreliable so far (no evidence or inconsistent): the pose then is the odometry's.
  [[nodiscard]] std::uint64_t unreliable_scans() const noexcept { return unreliable_; }
  /// The median quality of the recent consistent matches (0 before there are enough).
  [[nodiscard]] double typical_quality() const noexcept { return qualities_.typical(); }
  void publish(NavigationData& data) const noexcept;
  [[nodiscard]] const ScanMatchingLocalizerOptions& options() const noexcept { return options_; }

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  void on_start(ModuleContext& context) override;
  void on_update(ModuleContext& context) override;
  void on_behavior_activated(const BehaviorActivation& activation, ModuleContext& context) override;
  void on_behavior_deactivated(std::string_view behavior, ModuleContext& context) override;

 private:
  enum class State { unknown, ok, lost };
  void post(State next, Time now, std::vector<ModuleEvent>& out);
  // Whether an odometry increment between two scans is motion the tracker can follow (not a reset).
  [[nodiscard]] bool plausible(const Pose2D& motion) const noexcept;
  [[nodiscard]] ScanVerdict judge(const ScanMatch& m, const Pose2D& motion) const noexcept;

  ScanMatchingLocalizerOptions options_;
  std::unique_ptr<ScanMatcher> matcher_;
  std::string laser_name_, odometry_name_;
  const LaserResource* laser_ = nullptr;
  const OdometryResource* odometry_ = nullptr;
  Time last_scan_stamp_{};
  bool has_scan_ = false;

  Pose2D pose_;
  std::optional<Pose2D> last_odom_;
  ScanMatch last_;
  Time stamp_{};
  int low_scans_ = 0;
  bool need_global_ = false;  // start_global before the first scan
  State state_ = State::unknown;

  RecentQualities qualities_;  // of the consistent matches
  ScanVerdict verdict_ = ScanVerdict::kNone;
  std::uint64_t unreliable_ = 0;

  GlobalFixAttempts fix_attempts_;  // global localization while BhGlobalLocalization is active
  std::uint32_t fixes_ = 0;
};

}  // namespace tripodal::navi
