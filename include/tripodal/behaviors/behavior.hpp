// CBehavior: the base of behaviors, the primitive actions of the reactive layer. The process
// supervisor activates a behavior with typed parameters while a Petri-net place binding it is
// marked; every sampling period the control loop steps it and hands its command to the behavior
// coordinator. Its outcome becomes an event of the net: "<BehaviorName>.done" or
// "<BehaviorName>.failed".
#pragma once

#include <array>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "tripodal/controllers/base_capabilities.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/resources/readings.hpp"
#include "tripodal/resources/resource.hpp"

namespace tripodal {

/// What the map says about a point, for behaviors that must tell the walls they follow from
/// obstacles the map does not hold. Implemented by the sequencing layer's map module over an
/// immutable grid, so the reactive loop may read it from its own thread.
class ObstacleMap {
 public:
  virtual ~ObstacleMap() = default;
  /// True when (x_m, y_m), map frame, lies on or next to an obstacle of the map.
  [[nodiscard]] virtual bool near_obstacle(double x_m, double y_m) const noexcept = 0;
};

/// Navigation data the sequencing layer (localizer, path and coverage planners) publishes for the
/// reactive layer's behaviors. The control loop holds a copy; `path` views storage owned by
/// whoever set it (the loop copies it into a fixed-capacity buffer when path_id changes).
struct NavigationData {
  Pose2D map_from_base;      ///< pose estimate in the map frame
  Time pose_stamp{};
  /// Covariance of map_from_base over (x, y, theta), row-major (m², m·rad, rad²), as the
  /// localizer estimates it; all zero when it does not (the ground-truth test double).
  std::array<double, 9> pose_covariance{};
  bool localized = false;    ///< the localizer trusts map_from_base
  std::uint32_t fixes = 0;   ///< global position fixes accepted so far (BhGlobalLocalization)
  bool has_goal = false;
  Pose2D goal;               ///< current goal in the map frame
  /// The path to follow, map frame (theta unused). A new path_id is a new path: a following
  /// behavior takes it up at path_start_m. 0: no path.
  std::span<const Pose2D> path;
  std::uint32_t path_id = 0;
  double path_start_m = 0.0;
  /// Speed limits (m/s) along the path: entry i bounds the leg from path[i] to path[i + 1] (a
  /// disinfection's lanes, navi/dose_planner.hpp). Empty: the behavior's own speed only.
  std::span<const double> path_speed_m_s;
  /// True when the end of the path is the behavior's goal (it succeeds there); false for a
  /// detour, after which the sequencing layer publishes the way on.
  bool path_final = true;
  /// Why the sequencing layer could not give a path for the active behavior ("unknown goal",
  /// "no path to the goal"); static storage. Empty: none.
  std::string_view path_failure;
  /// Radius of the body disc the paths were planned with (clearance checks use it).
  double robot_radius_m = 0.25;
  const ObstacleMap* map = nullptr;  ///< nullptr: every laser return counts as an obstacle
};

/// What a path-following behavior reports back to the sequencing layer every period (written in
/// step(), published by the loop): where it is along the path and whether something the map does
/// not hold stops it, so the sequencing layer can replan around it.
struct NavigationFeedback {
  std::uint32_t path_id = 0;  ///< the path being followed; 0: none
  double progress_m = 0.0;    ///< arc length reached along it
  bool reached_end = false;   ///< at the end of the path
  bool blocked = false;       ///< stopped by an obstacle the map does not hold, or a bumper
  Time blocked_since{};
  /// What the safety behaviors found that neither the map nor the laser holds (map frame, theta
  /// unused): where a cliff sensor saw a drop, where an ultrasonic echo or a bumper met glass or a
  /// low table. The sequencing layer plans detours around them as around the laser's unmapped
  /// returns. Written every period while they hold the robot back.
  static constexpr std::size_t kMaxHazards = 16;
  std::array<Pose2D, kMaxHazards> hazards{};
  std::uint8_t hazard_count = 0;
  /// Adds a hazard point (ignored when full).
  void add_hazard(double x_m, double y_m) noexcept {
    if (hazard_count < kMaxHazards) hazards[hazard_count++] = Pose2D{x_m, y_m, 0.0};
  }
  friend bool operator==(const NavigationFeedback&, const NavigationFeedback&) = default;
};

/// A per-axis velocity envelope [lo, hi] a safety behavior imposes (see CBehaviorCoordinator's
/// safety override). Unbounded by default.
struct VelocityEnvelope {
  static constexpr double kInf = std::numeric_limits<double>::infinity();
  double vx_lo_m_s = -kInf, vx_hi_m_s = kInf;
  double vy_lo_m_s = -kInf, vy_hi_m_s = kInf;
  double wz_lo_rad_s = -kInf, wz_hi_rad_s = kInf;
  friend bool operator==(const VelocityEnvelope&, const VelocityEnvelope&) = default;
};

/// What the behavior coordinator's safety override did to the command of the previous period, as
/// the control loop hands it to the behavior whose input won that fusion (docs/guide.md, "Visitors
/// who do not give way"). A safety input restricts whatever wins without the winner knowing; a
/// path-following behavior reads this to learn that it is held still (its translation clamped to
/// zero) and counts itself blocked, as before an obstacle on its path.
struct SafetyFeedback {
  bool limited = false;         ///< a safety input changed the fused command
  Twist2D requested;            ///< the fused command before the safety override
  Twist2D allowed;              ///< the command after it (what the controller was given)
  std::string_view limited_by;  ///< the first live safety input, when limited
  /// Translation (m/s) asked for and allowed, along the body axes together.
  [[nodiscard]] double requested_speed_m_s() const noexcept;
  [[nodiscard]] double allowed_speed_m_s() const noexcept;
};

/// What a behavior can see during activation and each step. Built by the control loop; holds
/// references only, so building and passing it allocates nothing.
struct BehaviorContext {
  Time now{};
  Duration period{0};                 ///< nominal sampling period of the loop
  const ResourceTable* resources = nullptr;
  const NavigationData* navi = nullptr;
  BaseCapabilities base;
  /// Where path-following behaviors report (nullptr outside a loop); the loop resets it to
  /// "no path" before every cycle.
  NavigationFeedback* feedback = nullptr;
  /// The safety override's effect on this behavior's command of the previous period; nullptr when
  /// that command did not win the fusion (or outside a loop).
  const SafetyFeedback* safety = nullptr;
};

enum class BehaviorStatus : std::uint8_t {
  idle,       ///< not active
  running,
  succeeded,  ///< reported to the supervisor as "<BehaviorName>.done"
  failed,     ///< reported as "<BehaviorName>.failed" with failure_reason()
};
[[nodiscard]] std::string_view to_string(BehaviorStatus status) noexcept;

/// Names of the events a behavior's outcome posts to the process supervisor's net.
[[nodiscard]] std::string done_event_name(std::string_view behavior_name);    // "<name>.done"
[[nodiscard]] std::string failed_event_name(std::string_view behavior_name);  // "<name>.failed"

/// Base of every behavior. Lifecycle: activate() (outside the loop: may allocate and throw) ->
/// step() every period (noexcept, no allocation) until the status leaves running or the
/// supervisor calls deactivate(). After success or failure step() returns nothing; the status
/// stays until the next activate() or deactivate().
class CBehavior {
 public:
  virtual ~CBehavior() = default;
  CBehavior(const CBehavior&) = delete;
  CBehavior& operator=(const CBehavior&) = delete;

  /// The static manifest of the behavior type (name, inputs, outputs, parameters).
  [[nodiscard]] const ModuleManifest& manifest() const noexcept { return do_manifest(); }
  /// The registered type name, e.g. "BhGoToPose".
  [[nodiscard]] std::string_view name() const noexcept { return manifest().name; }

  /// Resolves `params` against the manifest (ConfigError listing every problem, located at
  /// `where`; also when the manifest declares more than kMaxBehaviorChannels writes), resolves
  /// the names of the channels it writes, then calls on_activate(). Status becomes running unless on_activate() already
  /// reported an outcome. May be called again to re-activate with new parameters.
  void activate(const ParameterValues& params, const BehaviorContext& context,
                const SourceLocation& where = {});
  /// Activation with parameters already resolved.
  void activate(const ParameterSet& params, const BehaviorContext& context);
  /// Stops the behavior (status idle). Never throws.
  void deactivate() noexcept;

  /// One sampling period: the command of this period (body frame) or nothing (this behavior
  /// does not want to drive now). Returns nothing unless running.
  [[nodiscard]] std::optional<Twist2D> step(const BehaviorContext& context) noexcept;

  [[nodiscard]] BehaviorStatus status() const noexcept { return status_; }
  [[nodiscard]] bool running() const noexcept { return status_ == BehaviorStatus::running; }
  /// Why the behavior failed ("" otherwise); text with static storage duration.
  [[nodiscard]] std::string_view failure_reason() const noexcept { return failure_reason_; }
  /// The envelope a safety behavior imposes this period, if any (set during step()).
  [[nodiscard]] const std::optional<VelocityEnvelope>& envelope() const noexcept { return envelope_; }
  /// This period's write to the behavior's i-th declared channel (manifest().writes), if any.
  /// Cleared before every step, and after a step in which the behavior finished.
  [[nodiscard]] const std::optional<ChannelValue>& channel_write(std::size_t i) const noexcept { return writes_[i]; }
  /// The channel the i-th declared write goes to, resolved at activation (a parameter-named
  /// write takes the parameter's value); "" before.
  [[nodiscard]] std::string_view channel_name(std::size_t i) const noexcept { return channel_names_[i]; }
  /// Number of step() calls since the last activation.
  [[nodiscard]] std::uint64_t steps() const noexcept { return steps_; }
  /// The event this behavior raised in its last step for the nets (e.g. "cliff"; static storage),
  /// and forgets it; empty when none. The control loop posts it as a net event.
  [[nodiscard]] std::string_view take_signal() noexcept {
    const std::string_view s = signal_;
    signal_ = {};
    return s;
  }

 protected:
  CBehavior() = default;
  virtual const ModuleManifest& do_manifest() const noexcept = 0;
  /// Copies parameters into typed members and looks up resources (keep the pointers).
  virtual void on_activate(const ParameterSet& params, const BehaviorContext& context) = 0;
  /// The per-period computation. Must not throw or allocate.
  virtual std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept = 0;
  virtual void on_deactivate() noexcept {}

  /// Reports success (event "<name>.done"); later steps return nothing.
  void succeed() noexcept { status_ = BehaviorStatus::succeeded; }
  /// Reports failure with a reason that must have static storage duration (a string literal).
  void fail(std::string_view static_reason) noexcept {
    status_ = BehaviorStatus::failed;
    failure_reason_ = static_reason;
  }
  /// Raises net event `static_name` (a string literal) this period, without ending the behavior:
  /// a safety behavior's finding the nets may react to ("cliff").
  void signal(std::string_view static_name) noexcept { signal_ = static_name; }
  /// Sets (or clears with nullopt) this period's safety envelope; cleared before every step.
  void set_envelope(const std::optional<VelocityEnvelope>& envelope) noexcept { envelope_ = envelope; }
  /// Writes `value` to the i-th channel the manifest declares (i < manifest().writes.size()).
  void write_channel(std::size_t i, const ChannelValue& value) noexcept {
    if (i < writes_.size()) writes_[i] = value;
  }

 private:
  void clear_writes() noexcept {
    for (auto& w : writes_) w.reset();
  }

  BehaviorStatus status_ = BehaviorStatus::idle;
  std::string_view failure_reason_;
  std::optional<VelocityEnvelope> envelope_;
  std::array<std::optional<ChannelValue>, kMaxBehaviorChannels> writes_{};
  std::array<std::string, kMaxBehaviorChannels> channel_names_;
  std::string_view signal_;
  std::uint64_t steps_ = 0;
};

}  // namespace tripodal
