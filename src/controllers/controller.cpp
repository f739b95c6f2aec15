#include "tripodal/controllers/controller.hpp"

#include <algorithm>
#include <cmath>

namespace tripodal {

std::string_view to_string(ControlStatus status) noexcept {
  switch (status) {
    case ControlStatus::ok: return "ok";
    case ControlStatus::limited: return "limited";
    case ControlStatus::timed_out: return "timed_out";
    case ControlStatus::hardware_fault: return "hardware_fault";
  }
  return "?";
}

namespace {

// One axis: velocity `v` with acceleration `a` moves toward `target` over `dt`.
void limit_axis(const AxisLimits& lim, double target, double dt, double& v, double& a) noexcept {
  if (lim.max_velocity) target = std::clamp(target, -*lim.max_velocity, *lim.max_velocity);
  const double dv = target - v;
  double acc = dv / dt;
  // Braking (the speed's magnitude decreases) uses the deceleration limit.
  const bool braking = v * dv < 0.0;
  const std::optional<double>& bound =
      braking && lim.max_deceleration ? lim.max_deceleration : lim.max_acceleration;
  if (bound) acc = std::clamp(acc, -*bound, *bound);
  if (lim.max_jerk) {
    const double j = *lim.max_jerk;
    // The acceleration must be able to fall back to zero (at the jerk limit) before the target is
    // reached, or the velocity overshoots: |acc| <= sqrt(2 j |dv|).
    acc = std::clamp(acc, a - j * dt, a + j * dt);
    const double reachable = std::sqrt(2.0 * j * std::abs(dv));
    acc = std::clamp(acc, -reachable, reachable);
  }
  double next = v + acc * dt;
  // Never step past the target (jerk discretisation could).
  if ((dv >= 0.0 && next > target) || (dv <= 0.0 && next < target)) next = target;
  a = (next - v) / dt;
  v = next;
}

}  // namespace

Twist2D TwistLimiter::apply(const Twist2D& target, double period_s, bool& limited) noexcept {
  if (!(period_s > 0.0)) {
    limited = !(target == velocity_);
    return velocity_;
  }
  limit_axis(limits_.vx, target.vx_m_s, period_s, velocity_.vx_m_s, acceleration_.vx_m_s);
  limit_axis(limits_.vy, target.vy_m_s, period_s, velocity_.vy_m_s, acceleration_.vy_m_s);
  limit_axis(limits_.wz, target.wz_rad_s, period_s, velocity_.wz_rad_s, acceleration_.wz_rad_s);
  constexpr double kEps = 1e-12;
  limited = std::abs(velocity_.vx_m_s - target.vx_m_s) > kEps || std::abs(velocity_.vy_m_s - target.vy_m_s) > kEps ||
            std::abs(velocity_.wz_rad_s - target.wz_rad_s) > kEps;
  return velocity_;
}

void TwistLimiter::set_state(const Twist2D& velocity, const Twist2D& acceleration) noexcept {
  velocity_ = velocity;
  acceleration_ = acceleration;
}

void CController::set_command(const Twist2D& command, Time now) noexcept {
  command_ = command;
  command_stamp_ = now;
  has_command_ = true;
}

ControlStatus CController::update(Time now) noexcept {
  Duration period = has_updated_ ? now - last_update_ : nominal_period_;
  // A stalled loop must not license a velocity jump: the wheels kept their command meanwhile.
  period = std::min(period, 2 * nominal_period_);
  if (period.count() < 0) period = Duration{0};
  last_update_ = now;
  has_updated_ = true;
  const Duration timeout = command_timeout();
  const bool timed_out = timeout.count() > 0 && (!has_command_ || now - command_stamp_ > timeout);
  const Twist2D command = timed_out ? Twist2D{} : command_;
  ControlStatus status = on_update(now, period, command, timed_out, limited_, odometry_);
  if (timed_out && status != ControlStatus::hardware_fault) status = ControlStatus::timed_out;
  status_ = status;
  return status;
}

void CController::reset_odometry(const Pose2D& pose) noexcept {
  odometry_.pose = pose;
  odometry_.twist = {};
  on_reset_odometry();
}

}  // namespace tripodal

#include "controller_manifest.hpp"

namespace tripodal::detail {

ModuleManifest controller_manifest(std::string name, std::string description, std::vector<ParameterSpec> specific) {
  ModuleManifest m;
  m.name = std::move(name);
  m.layer = Layer::reactive;
  m.kind = ModuleKind::controller;
  m.description = std::move(description);
  m.inputs = {"cmd_vel"};
  m.outputs = {"odometry", "wheel_commands"};
  auto num = [](std::string n, std::optional<Value> def, std::string unit, std::string desc) {
    return ParameterSpec{std::move(n), ValueType::number, std::move(def), std::move(unit), std::move(desc), 0.0, {}};
  };
  m.parameters = std::move(specific);
  m.parameters.push_back(num("period_s", Value{0.01}, "s", "nominal sampling period"));
  m.parameters.push_back(num("cmd_timeout_s", Value{0.0}, "s", "brake to zero when no command came for this long; 0 disables"));
  m.parameters.push_back(num("max_wheel_speed_rad_s", std::nullopt, "rad/s", "wheel saturation (unset: none); scaled keeping curvature"));
  for (const char* axis : {"vx", "vy", "wz"}) {
    const std::string a = axis;
    const bool lin = a != "wz";
    m.parameters.push_back(num("limits." + a + ".max_velocity", std::nullopt, lin ? "m/s" : "rad/s", "unset: no limit"));
    m.parameters.push_back(num("limits." + a + ".max_acceleration", std::nullopt, lin ? "m/s^2" : "rad/s^2", "unset: no limit"));
    m.parameters.push_back(num("limits." + a + ".max_deceleration", std::nullopt, lin ? "m/s^2" : "rad/s^2", "unset: max_acceleration"));
    m.parameters.push_back(num("limits." + a + ".max_jerk", std::nullopt, lin ? "m/s^3" : "rad/s^3", "unset: no limit"));
  }
  return m;
}

}  // namespace tripodal::detail
