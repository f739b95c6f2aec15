#include "tripodal/controllers/base_kinematics.hpp"

#include "tripodal/controllers/holonomic_controller.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/controllers/kinematics.hpp"
#include "tripodal/core/diagnostic.hpp"

namespace tripodal {

namespace {

const ControllerConfig& checked_base(const ControllerConfig& base) {
  Diagnostics d = validate(base);
  if (base.type != "differential" && base.type != "omni" && base.type != "mecanum") {
    d.error(base.where,
            "the base must be of type \"differential\", \"omni\" or \"mecanum\", got \"" + base.type + "\"");
  }
  if (d.has_errors()) throw ConfigError(std::move(d));
  return base;
}

}  // namespace

BaseKinematics::BaseKinematics(const ControllerConfig& base) : base_(checked_base(base)) {
  if (base_.type == "differential") {
    wheels_ = 2;
  } else {
    wheels_ = base_.holonomic.wheels.size();
    // The controller's own Jacobian and pseudo-inverse are the base's kinematics.
    model_hw_ = std::make_unique<IdealWheelHardware>(wheels_, base_.period);
    holonomic_ = std::make_unique<HolonomicController>(base_, *model_hw_);
  }
}

BaseKinematics::~BaseKinematics() = default;

void BaseKinematics::inverse(const Twist2D& twist, std::span<double> wheel_rad_s) const noexcept {
  if (wheel_rad_s.size() != wheels_) return;
  if (holonomic_) {
    holonomic_->inverse(twist, wheel_rad_s);
  } else {
    differential_inverse(base_.differential.wheel_separation_m, base_.differential.wheel_radius_m, twist,
                         wheel_rad_s[0], wheel_rad_s[1]);
  }
}

Twist2D BaseKinematics::forward(std::span<const double> wheel_rad_s) const noexcept {
  if (wheel_rad_s.size() != wheels_) return {};
  if (holonomic_) return holonomic_->forward(wheel_rad_s);
  return differential_forward(base_.differential.wheel_separation_m, base_.differential.wheel_radius_m,
                              wheel_rad_s[0], wheel_rad_s[1]);
}

}  // namespace tripodal
