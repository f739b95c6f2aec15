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
    acc = std::clamp(acc, a - j * dt, a + j * dt);
    // The acceleration must be able to fall back to zero, one jerk step j*dt per period, before
    // the target is reached, or the velocity overshoots. Ramping down from acc covers
    // acc^2 / (2j) + acc * dt / 2 of velocity; solving for acc gives the bound.
    const double reachable = j * (std::sqrt(0.25 * dt * dt + 2.0 * std::abs(dv) / j) - 0.5 * dt);
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
