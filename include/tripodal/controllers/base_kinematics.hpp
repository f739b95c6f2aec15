// BaseKinematics: the wheel kinematics of a configured base (differential, omni, mecanum) as a
// value, without a controller's limits or odometry — what the simulator moves its wheels by and
// what hardware behind a twist interface (a base on DDS's cmd_vel) converts wheel commands with.
#pragma once

#include <cstddef>
#include <memory>
#include <span>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal {

class HolonomicController;
class IdealWheelHardware;

class BaseKinematics {
 public:
  /// From the base controller's configuration: "differential" (wheels [left, right]), "omni" or
  /// "mecanum" (wheels in configuration order). A holonomic base uses the controller's own
  /// Jacobian and pseudo-inverse, so the two never disagree about the geometry. Throws
  /// ConfigError (at base.where) for an invalid configuration or another type.
  explicit BaseKinematics(const ControllerConfig& base);
  ~BaseKinematics();
  BaseKinematics(const BaseKinematics&) = delete;
  BaseKinematics& operator=(const BaseKinematics&) = delete;

  [[nodiscard]] std::size_t wheel_count() const noexcept { return wheels_; }
  [[nodiscard]] bool holonomic() const noexcept { return holonomic_ != nullptr; }
  /// Wheel velocities (rad/s) of a body twist; the twist of wheel velocities (least squares for
  /// more than three holonomic wheels). Spans of another size than wheel_count(): nothing, zero.
  void inverse(const Twist2D& twist, std::span<double> wheel_rad_s) const noexcept;
  [[nodiscard]] Twist2D forward(std::span<const double> wheel_rad_s) const noexcept;

 private:
  ControllerConfig base_;
  std::size_t wheels_ = 0;
  std::unique_ptr<IdealWheelHardware> model_hw_;
  std::unique_ptr<HolonomicController> holonomic_;
};

}  // namespace tripodal
