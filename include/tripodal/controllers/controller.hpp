// CController: the last stage of a reactive control loop. Every sampling period it takes the
// fused body-frame command from the behavior coordinator, applies the base's limits and
// kinematics, and writes wheel commands to a HardwareInterface (simulator, serial motion board,
// or test double). Controllers are created by name from configuration; swapping one (omni for
// differential) leaves behaviors unchanged, as on the guide robot Jinny.
#pragma once

#include <cstddef>
#include <span>
#include <string_view>

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
  /// Measured wheel angular velocities (rad/s) and positions (rad). Returns false when stale.
  virtual bool read_wheel_states(std::span<double> velocity_rad_s, std::span<double> position_rad) noexcept = 0;
};

enum class ControlStatus {
  ok,
  limited,          ///< the command was clipped by a velocity/acceleration/jerk limit
  timed_out,        ///< no fresh command within cmd_timeout_s: braking to zero through the limits
  hardware_fault,   ///< the hardware interface refused the write or gave stale states
};

/// Base of all base controllers. Public non-virtual methods check and time; leaf classes
/// implement the protected hooks.
class CController {
 public:
  virtual ~CController() = default;
  CController(const CController&) = delete;
  CController& operator=(const CController&) = delete;

  /// The registered type name, e.g. "differential" or "omni".
  [[nodiscard]] virtual std::string_view type_name() const noexcept = 0;

  /// Records a new command (the coordinator's output) received at `now`; a command older than
  /// the configured timeout makes update() brake to zero.
  void set_command(const Twist2D& command, Time now) noexcept;

  /// One sampling period at time `now`: the period used by the limits is the measured time since
  /// the previous update (the first update uses the nominal period). Never throws, never allocates.
  ControlStatus update(Time now) noexcept;

  /// Odometry integrated from the measured wheel states (odom_from_base and body twist).
  [[nodiscard]] const OdometryReading& odometry() const noexcept { return odometry_; }
  /// The command after limits, as last sent to the wheels.
  [[nodiscard]] const Twist2D& limited_command() const noexcept { return limited_; }

 protected:
  explicit CController(Duration nominal_period) noexcept : nominal_period_(nominal_period) {}

  /// Applies limits and kinematics to `command` over `period` and writes the wheels; updates
  /// `limited` with what was actually commanded and `odometry` from the read wheel states.
  virtual ControlStatus on_update(Time now, Duration period, const Twist2D& command, bool timed_out,
                                  Twist2D& limited, OdometryReading& odometry) noexcept = 0;
  /// cmd_timeout in the controller's configuration; 0 disables the timeout.
  [[nodiscard]] virtual Duration command_timeout() const noexcept = 0;

 private:
  Duration nominal_period_;
  Twist2D command_;
  Time command_stamp_{0};
  bool has_command_ = false;
  Time last_update_{0};
  bool has_updated_ = false;
  Twist2D limited_;
  OdometryReading odometry_;
};

}  // namespace tripodal
