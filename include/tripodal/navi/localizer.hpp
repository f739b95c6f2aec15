// CGroundTruthLocalizer, the localizer navigation module for simulation (sequencing layer): it estimates the
// robot's pose from a ground-truth source (the simulator) with seeded noise and an injectable
// fault schedule, and posts localizer.ok / localizer.lost when its estimate starts or stops
// agreeing with the actual position, the events the process PrCleaning's low-level net waits for
// (paper, Fig. 3 / Table 2: t2 and t3; PrAutoMove.xml's t1 and t2 alike). A scan-matching
// localizer would post the same events from its own consistency test.
#pragma once

#include <cstdint>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::navi {

/// Where the actual pose of the robot comes from; the simulator implements it.
class GroundTruthSource {
 public:
  virtual ~GroundTruthSource() = default;
  /// map_from_base of the robot at time now, or nothing if unknown.
  [[nodiscard]] virtual std::optional<Pose2D> true_pose(Time now) const = 0;
  /// Whether the world denies localization at `now` (a scheduled fault window of a simulation).
  [[nodiscard]] virtual bool localization_lost(Time /*now*/) const noexcept { return false; }
};

/// A window of localization loss: from start (inclusive) to end (exclusive).
struct LocalizationFault {
  Time start{};
  Time end{};
  friend bool operator==(const LocalizationFault&, const LocalizationFault&) = default;
};

/// Parses "10-20; 35.5-40" (seconds) into faults; throws ConfigError located at where.
[[nodiscard]] std::vector<LocalizationFault> parse_fault_schedule(const std::string& text,
                                                                 const SourceLocation& where = {});

struct LocalizerOptions {
  double noise_xy_m = 0.02;         ///< standard deviation of the position noise, per axis
  double noise_theta_rad = 0.01;    ///< standard deviation of the heading noise
  double lost_threshold_m = 0.3;    ///< the estimate disagrees beyond this position error...
  double lost_threshold_rad = 0.35; ///< ...or this heading error
  double fault_offset_m = 2.0;      ///< how far off the estimate jumps when a fault starts
  /// Whether the estimate comes back by itself when a fault window ends; if not, it stays off
  /// until relocalize() (global localization) succeeds.
  bool recover_at_fault_end = false;
  std::uint64_t seed = 1;
  std::vector<LocalizationFault> faults;
};

/// Type "GroundTruthLocalizer". As a module of the robot it takes the ground truth from the robot's hardware
/// (the simulator) at start, updates and publishes its estimate every sequencing period, keeps the
/// supervisor's watchdog fed, and attempts a global position fix every attempt_period_s while
/// BhGlobalLocalization is active (NavigationData::fixes counts the fixes accepted).
class CGroundTruthLocalizer final : public CNaviModules {
 public:
  explicit CGroundTruthLocalizer(const GroundTruthSource* truth = nullptr, LocalizerOptions options = {});

  static const ModuleManifest& static_manifest();

  /// The ground truth to compare with (not owned; must outlive the updates).
  void set_ground_truth(const GroundTruthSource* truth) noexcept { truth_ = truth; }
  /// Adds a localization loss window (e.g. from the simulator's fault schedule).
  void add_fault(LocalizationFault fault) { options_.faults.push_back(fault); }

  /// Global localization: puts the estimate back on the actual pose, unless a fault window is
  /// active at now or there is no ground truth. Returns whether it succeeded; the next update
  /// posts localizer.ok.
  bool relocalize(Time now) noexcept;

  /// The current estimate (after the first update with a ground truth).
  [[nodiscard]] const std::optional<Pose2D>& estimate() const noexcept { return estimate_; }
  /// Whether the estimate agrees with the actual pose (as of the last update).
  [[nodiscard]] bool localized() const noexcept { return state_ == State::ok; }
  /// Error of the estimate at the last update, metres.
  [[nodiscard]] double position_error_m() const noexcept { return error_m_; }
  /// Copies the estimate into the navigation data behaviors read.
  void publish(NavigationData& data) const noexcept;
  /// One update at `now` on its own: the estimate, and the events it posts appended to `out`.
  void step(Time now, std::vector<ModuleEvent>& out) noexcept;
  [[nodiscard]] const LocalizerOptions& options() const noexcept { return options_; }

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  void on_start(ModuleContext& context) override;
  void on_update(ModuleContext& context) override;
  void on_behavior_activated(const BehaviorActivation& activation, ModuleContext& context) override;
  void on_behavior_deactivated(std::string_view behavior, ModuleContext& context) override;

 private:
  enum class State { unknown, ok, lost };
  [[nodiscard]] bool in_fault(Time now) const noexcept;

  const GroundTruthSource* truth_;
  LocalizerOptions options_;
  std::mt19937_64 rng_;
  State state_ = State::unknown;
  bool corrupted_ = false;      // the estimate is off by offset_ until relocalized
  Pose2D offset_;
  std::optional<Pose2D> estimate_;
  Time stamp_{};
  double error_m_ = 0.0;
  // Global localization while the behavior it serves (BhGlobalLocalization) is active.
  GlobalFixAttempts fix_attempts_;  // global localization while BhGlobalLocalization is active
  std::uint32_t fixes_ = 0;
};

}  // namespace tripodal::navi
