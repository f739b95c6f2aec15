// CController: the last stage of a reactive control loop. Every sampling period it takes the
// fused body-frame command from the behavior coordinator, applies the base's limits and
// kinematics, and writes wheel commands to a HardwareInterface (simulator, serial motion board,
// or test double). Controllers are created by name from configuration; swapping one (omni for
// differential) leaves behaviors unchanged, as on the guide robot Jinny.
#pragma once

#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <string_view>

#include "tripodal/controllers/base_capabilities.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal {

/// The boundary to the motion hardware: wheel angular velocities in, wheel states out.
/// Implementations must not allocate or block in write/read (called from the control loop).
class HardwareInterface {
 public:
  virtual ~HardwareInterface() = default;
  [[nodiscard]] virtual std::size_t wheel_count() const noexcept = 0;
  /// Commands wheel angular velocities (rad/s), one per wheel in configuration order.
  /// Returns false when the hardware did not accept them (link down, fault).
  virtual bool write_wheel_velocities(std::span<const double> wheel_rad_s) noexcept = 0;
  /// Measured wheel angular velocities (rad/s) and positions (rad, accumulated, not wrapped).
  /// Returns false when stale.
  virtual bool read_wheel_states(std::span<double> velocity_rad_s, std::span<double> position_rad) noexcept = 0;
};

enum class ControlStatus {
  ok,
  limited,          ///< the command was clipped by a velocity/acceleration/jerk/wheel limit
  timed_out,        ///< no fresh command within cmd_timeout_s: braking to zero through the limits
  hardware_fault,   ///< the hardware interface refused the write or gave stale states
};
[[nodiscard]] std::string_view to_string(ControlStatus status) noexcept;

/// Limits of one body axis (vx, vy or wz). An unset limit means no limit. Deceleration applies
/// when the speed's magnitude decreases (braking); acceleration otherwise.
struct AxisLimits {
  std::optional<double> max_velocity;      ///< m/s or rad/s, > 0
  std::optional<double> max_acceleration;  ///< m/s^2 or rad/s^2, > 0
  std::optional<double> max_deceleration;  ///< m/s^2 or rad/s^2, > 0; unset: max_acceleration
  std::optional<double> max_jerk;          ///< m/s^3 or rad/s^3, > 0
};

/// Body-frame limits of a base.
struct BodyLimits {
  AxisLimits vx;
  AxisLimits vy;  ///< ignored by a differential base (it cannot move sideways)
  AxisLimits wz;
};

/// Per-axis velocity, acceleration, deceleration and jerk limiting of a body-frame command, with
/// the period measured by the caller. State (last command and acceleration) is kept per axis.
/// No allocation; used by every controller.
class TwistLimiter {
 public:
  TwistLimiter() = default;
  explicit TwistLimiter(const BodyLimits& limits) noexcept : limits_(limits) {}
  /// The command reachable from the previous one within `period_s`, moving toward `target`.
  /// Sets `limited` when any limit changed the target.
  Twist2D apply(const Twist2D& target, double period_s, bool& limited) noexcept;
  /// Replaces the state (e.g. after a wheel-saturation rescale).
  void set_state(const Twist2D& velocity, const Twist2D& acceleration) noexcept;
  void reset() noexcept { set_state({}, {}); }
  [[nodiscard]] const Twist2D& velocity() const noexcept { return velocity_; }
  [[nodiscard]] const Twist2D& acceleration() const noexcept { return acceleration_; }
  [[nodiscard]] const BodyLimits& limits() const noexcept { return limits_; }

 private:
  BodyLimits limits_;
  Twist2D velocity_;
  Twist2D acceleration_;
};

/// Base of all base controllers. Public non-virtual methods check and time; leaf classes
/// implement the protected hooks. Not thread-safe: the control loop's thread calls everything.
class CController {
 public:
  virtual ~CController() = default;
  CController(const CController&) = delete;
  CController& operator=(const CController&) = delete;

  /// The registered type name, e.g. "differential" or "omni" (the manifest's name).
  [[nodiscard]] std::string_view type_name() const noexcept { return manifest().name; }
  /// The static manifest of the controller type.
  [[nodiscard]] const ModuleManifest& manifest() const noexcept { return do_manifest(); }
  /// What the base can do, for behaviors (BehaviorContext::base): velocity limits per axis,
  /// max_vy_m_s == 0 for a base that cannot move sideways.
  [[nodiscard]] BaseCapabilities capabilities() const noexcept { return do_capabilities(); }

  /// Records a new command (the coordinator's output) received at `now`; a command older than
  /// the configured timeout makes update() brake to zero.
  void set_command(const Twist2D& command, Time now) noexcept;

  /// One sampling period at time `now`: the period used by the limits is the measured time since
  /// the previous update (the first update uses the nominal period). Never throws, never allocates.
  ControlStatus update(Time now) noexcept;

  /// Odometry integrated from the measured wheel states (odom_from_base and body twist).
  [[nodiscard]] const OdometryReading& odometry() const noexcept { return odometry_; }
  /// Sets the odometry pose (e.g. to the start pose in a simulation).
  void reset_odometry(const Pose2D& pose = {}) noexcept;
  /// The command after limits, as last sent to the wheels.
  [[nodiscard]] const Twist2D& limited_command() const noexcept { return limited_; }
  /// The wheel velocities (rad/s) last written to the hardware.
  [[nodiscard]] std::span<const double> wheel_commands() const noexcept { return do_wheel_commands(); }
  [[nodiscard]] Duration nominal_period() const noexcept { return nominal_period_; }
  [[nodiscard]] ControlStatus last_status() const noexcept { return status_; }

 protected:
  explicit CController(Duration nominal_period) noexcept : nominal_period_(nominal_period) {}

  virtual const ModuleManifest& do_manifest() const noexcept = 0;
  virtual BaseCapabilities do_capabilities() const noexcept = 0;
  virtual std::span<const double> do_wheel_commands() const noexcept = 0;
  /// Applies limits and kinematics to `command` over `period` and writes the wheels; updates
  /// `limited` with what was actually commanded and `odometry` from the read wheel states.
  /// `timed_out` means `command` is zero because the command expired.
  virtual ControlStatus on_update(Time now, Duration period, const Twist2D& command, bool timed_out,
                                  Twist2D& limited, OdometryReading& odometry) noexcept = 0;
  /// cmd_timeout in the controller's configuration; 0 disables the timeout.
  [[nodiscard]] virtual Duration command_timeout() const noexcept = 0;
  /// Hook for reset_odometry(): forget wheel positions so the next update starts from `pose`.
  virtual void on_reset_odometry() noexcept {}

 private:
  Duration nominal_period_;
  Twist2D command_;
  Time command_stamp_{};
  bool has_command_ = false;
  Time last_update_{};
  bool has_updated_ = false;
  Twist2D limited_;
  OdometryReading odometry_;
  ControlStatus status_ = ControlStatus::ok;
};

}  // namespace tripodal
