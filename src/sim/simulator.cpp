#include "tripodal/sim/simulator.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>
#include <utility>

#include "tripodal/controllers/kinematics.hpp"

namespace tripodal::sim {

namespace {

// One independent random stream per noise source, derived from the run's seed (splitmix64), so
// turning a sensor off or on does not change the noise of the others.
std::uint64_t stream_seed(std::uint64_t seed, std::uint64_t stream) noexcept {
  std::uint64_t z = seed + 0x9E3779B97F4A7C15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// Uniform in [lo, hi] from the top 53 bits: the same on every standard library, unlike
// std::uniform_real_distribution, so a seed walks the visitors the same way everywhere.
double uniform(std::mt19937_64& rng, double lo, double hi) noexcept {
  const double u = static_cast<double>(rng() >> 11) * 0x1.0p-53;
  return lo + (hi - lo) * u;
}

double distance(navi::Point2D a, navi::Point2D b) noexcept { return std::hypot(a.x_m - b.x_m, a.y_m - b.y_m); }

// Range along a ray from `o` at unit direction (c, s) to the circle (centre, radius): the nearer
// crossing in front of the origin, or +inf.
double ray_circle(navi::Point2D o, double c, double s, navi::Point2D centre, double radius) noexcept {
  const double dx = centre.x_m - o.x_m, dy = centre.y_m - o.y_m;
  const double along = dx * c + dy * s;
  const double across2 = dx * dx + dy * dy - along * along;
  const double r2 = radius * radius;
  if (across2 > r2) return std::numeric_limits<double>::infinity();
  const double t = along - std::sqrt(r2 - across2);
  return t >= 0.0 ? t : std::numeric_limits<double>::infinity();
}

Duration period_of(double rate_hz) noexcept {
  return rate_hz > 0.0 && std::isfinite(rate_hz) ? from_seconds(1.0 / rate_hz) : Duration{0};
}

// Readings go stale after three missed periods: a dead sensor is detectable, jitter is not.
Duration max_age_of(double rate_hz) noexcept { return 3 * period_of(rate_hz); }

}  // namespace

std::string_view to_string(SimEvent::Kind kind) noexcept {
  switch (kind) {
    case SimEvent::Kind::collision: return "collision";
    case SimEvent::Kind::obstacle_appeared: return "obstacle_appeared";
    case SimEvent::Kind::obstacle_removed: return "obstacle_removed";
    case SimEvent::Kind::sensor_dead: return "sensor_dead";
    case SimEvent::Kind::sensor_restored: return "sensor_restored";
    case SimEvent::Kind::localization_loss_start: return "localization_loss_start";
    case SimEvent::Kind::localization_loss_end: return "localization_loss_end";
    case SimEvent::Kind::kidnapped: return "kidnapped";
    case SimEvent::Kind::fell: return "fell";
    case SimEvent::Kind::battery_empty: return "battery_empty";
    case SimEvent::Kind::button_pressed: return "button_pressed";
    case SimEvent::Kind::docked:
      return "docked";
    case SimEvent::Kind::undocked:
      return "undocked";
  }
  return "?";
}

Simulator::Simulator(World world, const ControllerConfig& base, std::uint64_t seed, Time start)
    : world_(std::move(world)),
      kinematics_(base),
      now_(start),
      laser_model_(world_.robot.laser, stream_seed(seed, 1)),
      odom_rng_(stream_seed(seed, 2)),
      gyro_rng_(stream_seed(seed, 3)),
      unit_normal_(0.0, 1.0),
      gyro_normal_(0.0, world_.robot.gyro.noise_stddev_rad_s > 0.0 ? world_.robot.gyro.noise_stddev_rad_s : 1.0),
      laser_(world_.robot.laser.name, max_age_of(world_.robot.laser.rate_hz)),
      odometry_(world_.robot.odometry.name, max_age_of(world_.robot.odometry.rate_hz)),
      gyro_(world_.robot.gyro.name, max_age_of(world_.robot.gyro.rate_hz)),
      bumpers_(world_.robot.bumpers.name, max_age_of(world_.robot.bumpers.rate_hz)),
      cliff_(world_.robot.cliff.name, max_age_of(world_.robot.cliff.rate_hz)),
      battery_(world_.robot.battery.name, max_age_of(world_.robot.battery.rate_hz)) {
  // The controller's own kinematics: the simulated wheels and the controller never disagree.
  wheels_ = kinematics_.wheel_count();
  wheel_cmd_.assign(wheels_, 0.0);
  wheel_vel_.assign(wheels_, 0.0);
  wheel_pos_.assign(wheels_, 0.0);
  wheel_scale_.assign(wheels_, 1.0);
  if (world_.robot.odometry.scale_error_stddev > 0.0) {
    for (double& s : wheel_scale_) s = 1.0 + world_.robot.odometry.scale_error_stddev * unit_normal_(odom_rng_);
  }

  solid_ = SolidMap(world_.grid);
  if (!world_.sonar_only.empty()) {
    // The sonar-only obstacles are part of the static solid map (the body, the bumpers and the
    // ultrasonic cones meet them); the laser casts on a copy without them.
    sonar_only_.assign(world_.grid.size(), 0);
    for (const SonarOnlyObstacle& o : world_.sonar_only) {
      navi::Region r{o.name, o.polygon, o.where};
      for (std::size_t i : navi::cells_in_region(world_.grid, r)) {
        sonar_only_[i] = 1;
        const navi::CellIndex c = world_.grid.cell(i);
        solid_.set_solid(c.x, c.y, true);
      }
    }
    solid_.refresh();
    laser_solid_ = SolidMap(world_.grid);
    copy_laser_map();
  }
  static_solid_ = solid_.cells();
  drop_depth_.assign(world_.grid.size(), 0.0F);
  for (const DropArea& a : world_.drops) {
    navi::Region r{a.name, a.polygon, a.where};
    for (std::size_t i : navi::cells_in_region(world_.grid, r)) drop_depth_[i] = static_cast<float>(a.depth_m);
  }
  // The wheels touch the floor at these points: one over a drop and the robot falls.
  if (base.type == "differential") {
    const double half = base.differential.wheel_separation_m / 2.0;
    wheel_points_ = {{0.0, half}, {0.0, -half}};
  } else {
    for (const OmniWheelConfig& wc : base.holonomic.wheels) wheel_points_.push_back({wc.x_m, wc.y_m});
  }
  for (const DynamicObstacle& o : world_.obstacles) {
    navi::Region r{o.name, o.polygon, o.where};
    obstacle_cells_.push_back(navi::cells_in_region(world_.grid, r));
  }
  obstacle_present_.assign(world_.obstacles.size(), 0);
  outage_active_.assign(world_.faults.dead_sensors.size(), 0);
  loss_active_.assign(world_.faults.localization_loss.size(), 0);
  events_.reserve(64);

  pose_ = world_.start_pose;
  odom_pose_ = world_.start_pose;
  gyro_yaw_ = world_.start_pose.theta_rad;
  soc_ = std::clamp(world_.robot.battery.initial, 0.0, 1.0);

  const SimRobotConfig& rc = world_.robot;
  laser_due_ = {rc.laser.enabled ? period_of(rc.laser.rate_hz) : Duration{0}, start};
  odom_due_ = {period_of(rc.odometry.rate_hz), start};
  gyro_due_ = {rc.gyro.enabled ? period_of(rc.gyro.rate_hz) : Duration{0}, start};
  bumper_due_ = {rc.bumpers.enabled ? period_of(rc.bumpers.rate_hz) : Duration{0}, start};
  cliff_due_ = {rc.cliff.enabled ? period_of(rc.cliff.rate_hz) : Duration{0}, start};
  battery_due_ = {rc.battery.enabled ? period_of(rc.battery.rate_hz) : Duration{0}, start};
  bumpers_.edit().count = rc.bumpers.sectors;
  cliff_.edit().cliff.assign(rc.cliff.positions.size(), 0);

  // Visitors: each its own stream, after the sensors' streams, so adding a visitor changes no
  // sensor noise. The seed places it on its first leg and draws its first speed.
  for (std::size_t i = 0; i < world_.visitors.size(); ++i) {
    const Visitor& v = world_.visitors[i];
    VisitorWalk walk{std::mt19937_64(stream_seed(seed, 100 + i)), 0, 1, v.start};
    VisitorState st;
    st.position = v.path.front();
    if (v.path.size() > 1) {
      const double f = uniform(walk.rng, 0.0, 1.0);
      st.position = {v.path[0].x_m + f * (v.path[1].x_m - v.path[0].x_m), v.path[0].y_m + f * (v.path[1].y_m - v.path[0].y_m)};
      walk.next = 1;
      st.speed_m_s = uniform(walk.rng, v.speed_min_m_s, v.speed_max_m_s);
    }
    visitors_.push_back(st);
    walks_.push_back(walk);
  }
  trail_.assign(4096, {});
  follower_next_.assign(world_.visitors.size(), 0);
  for (const JointConfig& j : world_.robot.joints) {
    joints_.push_back({j.initial_rad, j.initial_rad, 0.0, false});
  }
  leds_.assign(world_.robot.buttons.size(), 0);

  update_faults();
  sample_sensors();
}

Simulator::~Simulator() = default;

// --- visitors, joints, buttons ---------------------------------------------------------------

std::optional<std::size_t> Simulator::visitor_hit(const Pose2D& p) const noexcept {
  for (std::size_t i = 0; i < visitors_.size(); ++i) {
    if (distance({p.x_m, p.y_m}, visitors_[i].position) < world_.visitors[i].radius_m + world_.robot.radius_m) return i;
  }
  return std::nullopt;
}

std::optional<std::size_t> Simulator::other_hit(const Pose2D& p) const noexcept {
  for (std::size_t i = 0; i < others_.size(); ++i) {
    if (distance({p.x_m, p.y_m}, others_[i].position) < others_[i].radius_m + world_.robot.radius_m) return i;
  }
  return std::nullopt;
}

void Simulator::set_other_bodies(std::span<const OtherBody> bodies) {
  others_.assign(bodies.begin(), bodies.end());
  for (const OtherBody& b : others_) {
    min_robot_clearance_m_ =
        std::min(min_robot_clearance_m_, distance({pose_.x_m, pose_.y_m}, b.position) - b.radius_m - world_.robot.radius_m);
  }
}

bool Simulator::footprint_blocked(const Pose2D& p) const noexcept {
  return solid_.disc_overlaps({p.x_m, p.y_m}, world_.robot.radius_m) || visitor_hit(p).has_value() || other_hit(p).has_value();
}

void Simulator::next_leg(std::size_t index) noexcept {
  const Visitor& v = world_.visitors[index];
  VisitorWalk& w = walks_[index];
  const std::size_t n = v.path.size();
  if (v.loop) {
    w.next = (w.next + 1) % n;
  } else {
    if ((w.direction > 0 && w.next + 1 >= n) || (w.direction < 0 && w.next == 0)) w.direction = -w.direction;
    w.next = w.direction > 0 ? w.next + 1 : w.next - 1;
  }
  visitors_[index].speed_m_s = uniform(w.rng, v.speed_min_m_s, v.speed_max_m_s);
  w.pause_until = now_ + from_seconds(uniform(w.rng, v.pause_min_s, v.pause_max_s));
}

void Simulator::move_visitors(double h) noexcept {
  const navi::Point2D robot{pose_.x_m, pose_.y_m};
  constexpr double kTrailStepM = 0.2;
  if (trail_size_ == 0 || distance(trail_[(trail_head_ + trail_size_ - 1) % trail_.size()], robot) >= kTrailStepM) {
    trail_[(trail_head_ + trail_size_) % trail_.size()] = robot;
    if (trail_size_ < trail_.size()) {
      ++trail_size_;
    } else {
      trail_head_ = (trail_head_ + 1) % trail_.size();
    }
    ++trail_count_;
  }
  for (std::size_t i = 0; i < visitors_.size(); ++i) {
    const Visitor& v = world_.visitors[i];
    VisitorState& st = visitors_[i];
    VisitorWalk& w = walks_[i];
    st.giving_way = false;
    if (v.follow_robot && now_ >= w.pause_until) {
      // Along the robot's trail, the next point not yet reached, until follow_gap_m from it.
      st.speed_m_s = 0.0;
      const std::uint64_t oldest = trail_count_ - trail_size_;
      follower_next_[i] = std::max(follower_next_[i], oldest);
      double budget = v.speed_max_m_s * h;
      while (budget > 0.0 && follower_next_[i] < trail_count_ &&
             distance(st.position, robot) - v.radius_m - world_.robot.radius_m > v.follow_gap_m) {
        const navi::Point2D target = trail_[(trail_head_ + (follower_next_[i] - oldest)) % trail_.size()];
        const double left = distance(st.position, target);
        if (left <= budget) {
          st.position = target;
          budget -= left;
          ++follower_next_[i];
        } else {
          st.position = {st.position.x_m + (target.x_m - st.position.x_m) * budget / left,
                         st.position.y_m + (target.y_m - st.position.y_m) * budget / left};
          budget = 0.0;
        }
        st.speed_m_s = v.speed_max_m_s;
      }
    } else if (v.path.size() > 1 && now_ >= w.pause_until) {
      const navi::Point2D target = v.path[w.next];
      const double left = distance(st.position, target);
      const double step = st.speed_m_s * h;
      const navi::Point2D candidate =
          step >= left ? target
                       : navi::Point2D{st.position.x_m + (target.x_m - st.position.x_m) * step / left,
                                       st.position.y_m + (target.y_m - st.position.y_m) * step / left};
      // People give way to a robot: no step that brings them closer than give_way_m to its body.
      const double keep = v.radius_m + world_.robot.radius_m + v.give_way_m;
      const double now_d = distance(st.position, robot), next_d = distance(candidate, robot);
      if (next_d < keep && next_d < now_d) {
        st.giving_way = true;
      } else {
        st.position = candidate;
        if (step >= left) next_leg(i);
      }
    }
    const double clearance = distance(st.position, robot) - v.radius_m - world_.robot.radius_m;
    min_visitor_clearance_m_ = std::min(min_visitor_clearance_m_, clearance);
  }
}

void Simulator::move_joints(double h) noexcept {
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    JointState& j = joints_[i];
    const double gap = j.target_rad - j.position_rad;
    const double max_step = world_.robot.joints[i].speed_rad_s * h;
    const double step = std::clamp(gap, -max_step, max_step);
    // Landing exactly on the target: the joint then reads as stopped (velocity 0).
    j.position_rad = std::abs(gap) <= max_step ? j.target_rad : j.position_rad + step;
    j.velocity_rad_s = h > 0.0 ? step / h : 0.0;
  }
}

std::optional<std::size_t> Simulator::joint_index(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < world_.robot.joints.size(); ++i) {
    if (world_.robot.joints[i].name == name) return i;
  }
  return std::nullopt;
}

bool Simulator::command_joint(std::size_t index, double target_rad) noexcept {
  if (index >= joints_.size() || !std::isfinite(target_rad)) return false;
  const JointConfig& c = world_.robot.joints[index];
  const double clamped = std::clamp(target_rad, c.min_rad, c.max_rad);
  joints_[index].target_rad = clamped;
  joints_[index].at_limit = clamped != target_rad;
  return clamped == target_rad;
}

bool Simulator::press_button(std::string_view name) {
  for (const ButtonConfig& b : world_.robot.buttons) {
    if (b.name != name) continue;
    presses_.emplace_back(name);
    log(SimEvent::Kind::button_pressed, name);
    return true;
  }
  return false;
}

std::vector<std::string> Simulator::take_button_presses() { return std::exchange(presses_, {}); }

bool Simulator::set_led(std::string_view name, bool on) noexcept {
  for (std::size_t i = 0; i < world_.robot.buttons.size(); ++i) {
    if (world_.robot.buttons[i].name != name) continue;
    leds_[i] = on ? 1 : 0;
    return true;
  }
  return false;
}

bool Simulator::led(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < world_.robot.buttons.size(); ++i) {
    if (world_.robot.buttons[i].name == name) return leds_[i] != 0;
  }
  return false;
}

void Simulator::add_visitors_to_scan(LaserScan& scan) const noexcept {
  if (visitors_.empty() && others_.empty()) return;
  const LaserConfig& lc = world_.robot.laser;
  const double c = std::cos(pose_.theta_rad), s = std::sin(pose_.theta_rad);
  const navi::Point2D origin{pose_.x_m + c * lc.mount.x_m - s * lc.mount.y_m, pose_.y_m + s * lc.mount.x_m + c * lc.mount.y_m};
  const double heading = pose_.theta_rad + lc.mount.theta_rad;
  for (std::size_t k = 0; k < visitors_.size(); ++k)
    add_disc_to_scan(scan, origin, heading, visitors_[k].position, world_.visitors[k].radius_m);
  for (const OtherBody& b : others_) add_disc_to_scan(scan, origin, heading, b.position, b.radius_m);
}

void Simulator::add_disc_to_scan(LaserScan& scan, navi::Point2D origin, double heading, navi::Point2D p,
                                 double r) const noexcept {
  const double reach = scan.range_max_m;
  const double d = distance(origin, p);
  if (d - r > reach) return;
  // Only the beams within the disc's angular extent can hit it.
  const double centre = std::atan2(p.y_m - origin.y_m, p.x_m - origin.x_m) - heading;
  const double half = d > r ? std::asin(r / d) : std::numbers::pi;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    if (std::abs(wrap_angle(a - centre)) > half + 1e-9) continue;
    const double range = ray_circle(origin, std::cos(heading + a), std::sin(heading + a), p, r);
    if (range < scan.range_min_m || range > reach) continue;
    const auto f = static_cast<float>(range);
    if (!(scan.ranges_m[i] <= f)) scan.ranges_m[i] = f;  // an inf or a farther wall: the disc
  }
}

// --- kinematics ------------------------------------------------------------------------------

void Simulator::inverse_kinematics(const Twist2D& twist, std::span<double> wheel_rad_s) const noexcept {
  kinematics_.inverse(twist, wheel_rad_s);
}

Twist2D Simulator::forward_kinematics(std::span<const double> wheel_rad_s) const noexcept {
  return kinematics_.forward(wheel_rad_s);
}

void Simulator::command_twist(const Twist2D& twist) noexcept {
  inverse_kinematics(twist, wheel_cmd_);
}

// --- hardware interface ----------------------------------------------------------------------

bool Simulator::write_wheel_velocities(std::span<const double> wheel_rad_s) noexcept {
  if (wheel_rad_s.size() != wheels_) return false;
  for (double w : wheel_rad_s) {
    if (!std::isfinite(w)) return false;
  }
  std::copy(wheel_rad_s.begin(), wheel_rad_s.end(), wheel_cmd_.begin());
  return true;
}

bool Simulator::read_wheel_states(std::span<double> velocity_rad_s, std::span<double> position_rad) noexcept {
  if (velocity_rad_s.size() != wheels_ || position_rad.size() != wheels_) return false;
  if (sensor_dead(SensorKind::odometry, now_)) return false;
  std::copy(wheel_vel_.begin(), wheel_vel_.end(), velocity_rad_s.begin());
  std::copy(wheel_pos_.begin(), wheel_pos_.end(), position_rad.begin());
  return true;
}

std::optional<Pose2D> Simulator::true_pose(Time /*now*/) const { return pose_; }

bool Simulator::set_pose(const Pose2D& map_from_base) noexcept {
  if (footprint_blocked(map_from_base)) return false;
  pose_ = map_from_base;
  pose_.theta_rad = wrap_angle(pose_.theta_rad);
  blocked_ = false;
  return true;
}

// --- stepping --------------------------------------------------------------------------------

void Simulator::step(Duration dt) noexcept {
  if (dt.count() <= 0) return;
  const Duration max_sub = world_.robot.max_substep.count() > 0 ? world_.robot.max_substep : dt;
  // Equal integer substeps (the remainder spread one nanosecond at a time) keep the substep grid
  // independent of floating point, hence the run bit-identical.
  const auto n = (dt.count() + max_sub.count() - 1) / max_sub.count();
  const auto base = dt.count() / n;
  const auto rem = dt.count() % n;
  for (Duration::rep i = 0; i < n; ++i) {
    const Duration d{base + (i < rem ? 1 : 0)};
    substep(d);
    now_ += d;
    update_faults();
    sample_sensors();
  }
}

void Simulator::substep(Duration dt) noexcept {
  const double h = to_seconds(dt);
  const SimRobotConfig& rc = world_.robot;
  Twist2D actual{};
  const bool immobile = fallen_ || battery_empty_;
  if (!immobile) {
    const Twist2D cmd = forward_kinematics(wheel_cmd_);
    const double dx = cmd.vx_m_s * h, dy = cmd.vy_m_s * h, dth = cmd.wz_rad_s * h;
    const Pose2D candidate = integrate_body_displacement(pose_, dx, dy, dth);
    double frac = 1.0;
    if (footprint_blocked(candidate)) {
      // Contact inside this substep: bisect the fraction of the motion that stays clear, so the
      // robot stops against the obstacle rather than a whole substep short of it.
      double lo = 0.0, hi = 1.0;
      for (int k = 0; k < 16; ++k) {
        const double mid = 0.5 * (lo + hi);
        const Pose2D p = integrate_body_displacement(pose_, dx * mid, dy * mid, dth * mid);
        (footprint_blocked(p) ? hi : lo) = mid;
      }
      frac = lo;
      pose_ = integrate_body_displacement(pose_, dx * lo, dy * lo, dth * lo);
      if (!blocked_) {
        ++collisions_;
        char where[96];
        const Pose2D touching = integrate_body_displacement(pose_, dx * hi, dy * hi, dth * hi);
        if (const auto o = other_hit(touching); o && !solid_.disc_overlaps({touching.x_m, touching.y_m}, rc.radius_m)) {
          ++robot_collisions_;
          std::snprintf(where, sizeof where, "with robot %u at (%.2f, %.2f)", static_cast<unsigned>(others_[*o].id), pose_.x_m,
                        pose_.y_m);
        } else if (const auto v = visitor_hit(touching); v && !solid_.disc_overlaps({touching.x_m, touching.y_m}, rc.radius_m)) {
          ++visitor_collisions_;
          std::snprintf(where, sizeof where, "with %s at (%.2f, %.2f)", world_.visitors[*v].name.c_str(), pose_.x_m, pose_.y_m);
        } else if (touches_sonar_only(touching)) {
          ++sonar_only_collisions_;
          std::snprintf(where, sizeof where, "with a sonar-only obstacle at (%.2f, %.2f)", pose_.x_m, pose_.y_m);
        } else {
          std::snprintf(where, sizeof where, "at (%.2f, %.2f)", pose_.x_m, pose_.y_m);
        }
        log(SimEvent::Kind::collision, where);
      }
      blocked_ = true;
    } else {
      pose_ = candidate;
      blocked_ = false;
    }
    actual = {cmd.vx_m_s * frac, cmd.vy_m_s * frac, cmd.wz_rad_s * frac};
    distance_m_ += std::hypot(actual.vx_m_s, actual.vy_m_s) * h;
    rotation_rad_ += std::abs(actual.wz_rad_s) * h;
  }
  velocity_ = blocked_ ? Twist2D{} : actual;
  for (const OtherBody& o : others_) {
    min_robot_clearance_m_ =
        std::min(min_robot_clearance_m_, distance({pose_.x_m, pose_.y_m}, o.position) - o.radius_m - rc.radius_m);
  }
  move_visitors(h);
  move_joints(h);

  // Encoders: the wheels' actual rotation, each read with a relative error (odometry drift
  // proportional to the distance) and its constant scale error.
  inverse_kinematics(actual, wheel_vel_);
  const double ratio = rc.odometry.noise_ratio;
  for (std::size_t i = 0; i < wheels_; ++i) {
    const double e = unit_normal_(odom_rng_);
    wheel_vel_[i] *= wheel_scale_[i] * (1.0 + ratio * e);
    wheel_pos_[i] += wheel_vel_[i] * h;
  }
  odom_twist_ = forward_kinematics(wheel_vel_);
  odom_pose_ = integrate_body_displacement(odom_pose_, odom_twist_.vx_m_s * h, odom_twist_.vy_m_s * h,
                                           odom_twist_.wz_rad_s * h);
  gyro_yaw_ = wrap_angle(gyro_yaw_ + (actual.wz_rad_s + rc.gyro.bias_rad_s) * h);

  // Docks: the contacts touch within the dock's radius and heading tolerance.
  int dock = -1;
  for (std::size_t i = 0; i < world_.docks.size() && dock < 0; ++i) {
    const Dock& k = world_.docks[i];
    const bool near = std::hypot(pose_.x_m - k.pose.x_m, pose_.y_m - k.pose.y_m) <= k.contact_radius_m;
    const bool aligned = k.heading_tolerance_rad >= std::numbers::pi ||
                         std::abs(wrap_angle(pose_.theta_rad - k.pose.theta_rad)) <= k.heading_tolerance_rad;
    if (near && aligned) dock = static_cast<int>(i);
  }
  if (dock != dock_) {
    if (dock_ >= 0) log(SimEvent::Kind::undocked, world_.docks[static_cast<std::size_t>(dock_)].name);
    if (dock >= 0) log(SimEvent::Kind::docked, world_.docks[static_cast<std::size_t>(dock)].name);
    dock_ = dock;
    dock_powered_ = dock >= 0 && world_.docks[static_cast<std::size_t>(dock)].powered;
  }

  // Battery: the electronics and any extra load drain it with time, the wheels with distance.
  const BatteryConfig& bc = rc.battery;
  if (bc.enabled) {
    double d = -(bc.drain_per_s + extra_drain_per_s_) * h - bc.drain_per_m * std::hypot(actual.vx_m_s, actual.vy_m_s) * h;
    if (charging()) d += bc.charge_per_s * h;
    const double before = soc_;
    soc_ = std::clamp(soc_ + d, 0.0, 1.0);
    soc_rate_ = h > 0.0 ? (soc_ - before) / h : 0.0;
    if (soc_ <= 0.0 && !battery_empty_) {
      battery_empty_ = true;
      log(SimEvent::Kind::battery_empty, {});
    } else if (soc_ > 0.0 && battery_empty_) {
      battery_empty_ = false;
    }
  }

  // The centre or a wheel's contact point over a drop cell: the robot has fallen.
  if (!fallen_ && !world_.drops.empty()) {
    const char* what = drop_depth_at(pose_.x_m, pose_.y_m) > 0.0 ? "centre" : nullptr;
    const double c = std::cos(pose_.theta_rad), s = std::sin(pose_.theta_rad);
    for (std::size_t i = 0; what == nullptr && i < wheel_points_.size(); ++i) {
      const navi::Point2D& w = wheel_points_[i];
      if (drop_depth_at(pose_.x_m + c * w.x_m - s * w.y_m, pose_.y_m + s * w.x_m + c * w.y_m) > 0.0) what = "wheel";
    }
    if (what != nullptr) {
      fallen_ = true;
      velocity_ = {};
      char detail[64];
      std::snprintf(detail, sizeof detail, "%s over the edge at (%.2f, %.2f)", what, pose_.x_m, pose_.y_m);
      log(SimEvent::Kind::fell, detail);
    }
  }
}

double Simulator::drop_depth_at(double x_m, double y_m) const noexcept {
  const navi::CellIndex c = world_.grid.cell_at({x_m, y_m});
  return world_.grid.contains(c) ? drop_depth_[world_.grid.index(c)] : 0.0;
}

double Simulator::cliff_depth_m(std::size_t index) const noexcept {
  const std::vector<navi::Point2D>& positions = world_.robot.cliff.positions;
  if (index >= positions.size()) return 0.0;
  for (const StuckCliffSensor& st : world_.faults.stuck_cliff) {
    if (st.index == index) return st.reads_drop ? std::numeric_limits<double>::infinity() : 0.0;
  }
  const navi::Point2D& b = positions[index];
  const double c = std::cos(pose_.theta_rad), s = std::sin(pose_.theta_rad);
  return drop_depth_at(pose_.x_m + c * b.x_m - s * b.y_m, pose_.y_m + s * b.x_m + c * b.y_m);
}

bool Simulator::touches_sonar_only(const Pose2D& p) const noexcept {
  if (sonar_only_.empty()) return false;
  const navi::OccupancyGrid& g = world_.grid;
  const double r = world_.robot.radius_m + g.resolution_m();
  // The cells around the footprint, one cell wider (the contact is at the next substep's pose).
  const navi::CellIndex lo = g.cell_at({p.x_m - r, p.y_m - r}), hi = g.cell_at({p.x_m + r, p.y_m + r});
  for (int y = std::min(lo.y, hi.y); y <= std::max(lo.y, hi.y); ++y) {
    for (int x = std::min(lo.x, hi.x); x <= std::max(lo.x, hi.x); ++x) {
      const navi::CellIndex c{x, y};
      if (!g.contains(c) || sonar_only_[g.index(c)] == 0) continue;
      const navi::Point2D q = g.cell_center(c);
      if (std::hypot(q.x_m - p.x_m, q.y_m - p.y_m) <= r) return true;
    }
  }
  return false;
}

void Simulator::copy_laser_map() noexcept {
  const std::vector<std::uint8_t>& cells = solid_.cells();
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const navi::CellIndex c = world_.grid.cell(i);
    laser_solid_.set_solid(c.x, c.y, cells[i] != 0 && sonar_only_[i] == 0);
  }
  try {
    laser_solid_.refresh();
  } catch (...) {
    // Out of memory: the plain traversal stays exact, only slower.
  }
}

void Simulator::log(SimEvent::Kind kind, std::string_view detail) noexcept {
  // Events are rare (faults, first contacts); the vector's reserve covers a normal run.
  try {
    events_.push_back({kind, now_, std::string(detail)});
  } catch (...) {
  }
}

void Simulator::update_faults() noexcept {
  bool obstacles_changed = false;
  for (std::size_t i = 0; i < world_.obstacles.size(); ++i) {
    const DynamicObstacle& o = world_.obstacles[i];
    const bool present = now_ >= o.appear && (!o.disappear || now_ < *o.disappear);
    if (present != (obstacle_present_[i] != 0)) {
      set_obstacle(i, present);
      obstacles_changed = true;
      log(present ? SimEvent::Kind::obstacle_appeared : SimEvent::Kind::obstacle_removed, o.name);
    }
  }
  // Every obstacle that came or went in this step at once: laid once, the ray jumps computed once
  // (10^5 obstacles appearing together cost one pass, not one pass each).
  if (obstacles_changed) lay_obstacles();
  for (std::size_t i = 0; i < world_.faults.dead_sensors.size(); ++i) {
    const SensorOutage& s = world_.faults.dead_sensors[i];
    const bool active = now_ >= s.start && now_ < s.end;
    if (active != (outage_active_[i] != 0)) {
      outage_active_[i] = active ? 1 : 0;
      log(active ? SimEvent::Kind::sensor_dead : SimEvent::Kind::sensor_restored, to_string(s.sensor));
    }
  }
  for (std::size_t i = 0; i < world_.faults.localization_loss.size(); ++i) {
    const navi::LocalizationFault& f = world_.faults.localization_loss[i];
    const bool active = now_ >= f.start && now_ < f.end;
    if (active != (loss_active_[i] != 0)) {
      loss_active_[i] = active ? 1 : 0;
      log(active ? SimEvent::Kind::localization_loss_start : SimEvent::Kind::localization_loss_end, {});
    }
  }
  // The world carries the robot off (someone lifts it): its wheels do not turn, so the odometry
  // goes on from where it was. set_pose refuses a place its footprint does not fit (the world file
  // checks the static map; a box may stand there now): the robot then stays.
  while (next_kidnapping_ < world_.faults.kidnappings.size() && now_ >= world_.faults.kidnappings[next_kidnapping_].at) {
    const Kidnapping& k = world_.faults.kidnappings[next_kidnapping_++];
    const bool moved = set_pose(k.to);
    char text[96];
    std::snprintf(text, sizeof text, "%s (%.2f, %.2f, %.2f)", moved ? "to" : "refused, stays; to", k.to.x_m, k.to.y_m,
                  k.to.theta_rad);
    log(SimEvent::Kind::kidnapped, text);
  }
}

void Simulator::set_obstacle(std::size_t index, bool present) noexcept {
  obstacle_present_[index] = present ? 1 : 0;
  const navi::OccupancyGrid& g = world_.grid;
  // Rebuild the cells of this obstacle from the static map; lay_obstacles() then lays every
  // present obstacle back on them.
  for (std::size_t i : obstacle_cells_[index]) {
    const navi::CellIndex c = g.cell(i);
    solid_.set_solid(c.x, c.y, static_solid_[i] != 0);
  }
}

void Simulator::lay_obstacles() noexcept {
  const navi::OccupancyGrid& g = world_.grid;
  // A box never appears under the robot (it would trap it inside).
  const double keep_out = world_.robot.radius_m + g.resolution_m();
  for (std::size_t k = 0; k < obstacle_cells_.size(); ++k) {
    if (obstacle_present_[k] == 0) continue;
    for (std::size_t i : obstacle_cells_[k]) {
      const navi::CellIndex c = g.cell(i);
      const navi::Point2D p = g.cell_center(c);
      if (std::hypot(p.x_m - pose_.x_m, p.y_m - pose_.y_m) < keep_out) continue;
      solid_.set_solid(c.x, c.y, true);
    }
  }
  // Obstacles come and go rarely: recomputing the ray jumps (about a millisecond on the demo
  // map) is cheaper than tracing every later scan cell by cell. The allocation is reused.
  try {
    solid_.refresh();
  } catch (...) {
    // Out of memory: the plain traversal stays exact, only slower.
  }
  if (!sonar_only_.empty()) copy_laser_map();
}

bool Simulator::due(Schedule& s) const noexcept {
  if (s.period.count() <= 0 || now_ < s.next) return false;
  while (s.next <= now_) s.next += s.period;
  return true;
}

bool Simulator::sensor_dead(SensorKind sensor, Time t) const noexcept {
  for (const SensorOutage& s : world_.faults.dead_sensors) {
    if (s.sensor == sensor && t >= s.start && t < s.end) return true;
  }
  return false;
}

bool Simulator::localization_lost(Time t) const noexcept {
  for (const navi::LocalizationFault& f : world_.faults.localization_loss) {
    if (t >= f.start && t < f.end) return true;
  }
  return false;
}

void Simulator::update_bumpers() noexcept {
  const BumperConfig& bc = world_.robot.bumpers;
  const navi::Point2D g = solid_.to_cells({pose_.x_m, pose_.y_m});
  const double res = solid_.resolution_m();
  const double r = (world_.robot.radius_m + bc.contact_margin_m) / res;
  const int x0 = static_cast<int>(std::floor(g.x_m - r)), x1 = static_cast<int>(std::floor(g.x_m + r));
  const int y0 = static_cast<int>(std::floor(g.y_m - r)), y1 = static_cast<int>(std::floor(g.y_m + r));
  const double sector = 2.0 * std::numbers::pi / bc.sectors;
  // Contact directions are found in the grid frame; the body heading in that frame turns them
  // into the bumper's own frame.
  const double heading = solid_.to_grid_angle(pose_.theta_rad);
  std::uint32_t mask = 0;
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      // Beyond the map's edge counts as a wall, as it does for collisions.
      if (solid_.contains(x, y) && !solid_.solid(x, y)) continue;
      const double nx = std::clamp(g.x_m, static_cast<double>(x), x + 1.0) - g.x_m;
      const double ny = std::clamp(g.y_m, static_cast<double>(y), y + 1.0) - g.y_m;
      if (nx * nx + ny * ny >= r * r) continue;
      const double a = std::atan2(ny, nx) - heading + 0.5 * sector;
      double wrapped = std::fmod(a, 2.0 * std::numbers::pi);
      if (wrapped < 0.0) wrapped += 2.0 * std::numbers::pi;
      auto s = static_cast<std::uint32_t>(wrapped / sector);
      if (s >= bc.sectors) s = bc.sectors - 1;
      mask |= 1U << s;
    }
  }
  // Visitors press the sector facing them when within the margin of the footprint.
  for (std::size_t i = 0; i < visitors_.size(); ++i) {
    const navi::Point2D p = visitors_[i].position;
    const double gap = distance(p, {pose_.x_m, pose_.y_m}) - world_.visitors[i].radius_m - world_.robot.radius_m;
    if (gap >= bc.contact_margin_m) continue;
    const double a = std::atan2(p.y_m - pose_.y_m, p.x_m - pose_.x_m) - pose_.theta_rad + 0.5 * sector;
    double wrapped = std::fmod(a, 2.0 * std::numbers::pi);
    if (wrapped < 0.0) wrapped += 2.0 * std::numbers::pi;
    auto k = static_cast<std::uint32_t>(wrapped / sector);
    if (k >= bc.sectors) k = bc.sectors - 1;
    mask |= 1U << k;
  }
  // Other robots likewise.
  for (const OtherBody& o : others_) {
    const double gap = distance(o.position, {pose_.x_m, pose_.y_m}) - o.radius_m - world_.robot.radius_m;
    if (gap >= bc.contact_margin_m) continue;
    const double a = std::atan2(o.position.y_m - pose_.y_m, o.position.x_m - pose_.x_m) - pose_.theta_rad + 0.5 * sector;
    double wrapped = std::fmod(a, 2.0 * std::numbers::pi);
    if (wrapped < 0.0) wrapped += 2.0 * std::numbers::pi;
    auto k = static_cast<std::uint32_t>(wrapped / sector);
    if (k >= bc.sectors) k = bc.sectors - 1;
    mask |= 1U << k;
  }
  BumperReading& b = bumpers_.edit();
  b.stamp = now_;
  b.count = bc.sectors;
  b.pressed_mask = mask;
}

void Simulator::sample_sensors() noexcept {
  const SimRobotConfig& rc = world_.robot;
  if (due(laser_due_) && !sensor_dead(SensorKind::laser, now_)) {
    LaserScan& scan = laser_.edit();
    laser_model_.scan(laser_map(), pose_, now_, scan);
    add_visitors_to_scan(scan);
    // A localization loss is the scanner dazzled: it still publishes, without a return (after
    // drawing the beams' noise, so the noise stream is the same as without the fault).
    if (localization_lost(now_)) std::fill(scan.ranges_m.begin(), scan.ranges_m.end(), std::numeric_limits<float>::infinity());
    laser_.commit();
  }
  if (due(odom_due_) && !sensor_dead(SensorKind::odometry, now_)) {
    OdometryReading& o = odometry_.edit();
    o.stamp = now_;
    o.pose = odom_pose_;
    o.twist = odom_twist_;
    odometry_.commit();
  }
  if (due(gyro_due_) && !sensor_dead(SensorKind::gyro, now_)) {
    GyroReading& gr = gyro_.edit();
    gr.stamp = now_;
    const double noise = rc.gyro.noise_stddev_rad_s > 0.0 ? gyro_normal_(gyro_rng_) : 0.0;
    gr.yaw_rate_rad_s = velocity_.wz_rad_s + rc.gyro.bias_rad_s + noise;
    gr.yaw_rad = gyro_yaw_;
    gyro_.commit();
  }
  if (due(bumper_due_) && !sensor_dead(SensorKind::bumpers, now_)) {
    update_bumpers();
    bumpers_.commit();
  }
  if (due(cliff_due_) && !sensor_dead(SensorKind::cliff, now_)) {
    InfraredReading& ir = cliff_.edit();
    ir.stamp = now_;
    for (std::size_t i = 0; i < rc.cliff.positions.size() && i < ir.cliff.size(); ++i)
      ir.cliff[i] = cliff_depth_m(i) > 0.0 ? 1 : 0;
    cliff_.commit();
  }
  if (due(battery_due_) && !sensor_dead(SensorKind::battery, now_)) {
    const BatteryConfig& bc = rc.battery;
    BatteryReading& br = battery_.edit();
    br.stamp = now_;
    br.percentage = soc_;
    br.voltage_v = bc.voltage_empty_v + soc_ * (bc.voltage_full_v - bc.voltage_empty_v);
    br.current_a = soc_rate_ * bc.capacity_ah * 3600.0;
    br.charging = charging();
    battery_.commit();
  }
}

void Simulator::add_resources(ResourceTable& table, bool with_odometry) {
  const SimRobotConfig& rc = world_.robot;
  if (rc.laser.enabled) table.add(laser_);
  if (with_odometry) table.add(odometry_);
  if (rc.gyro.enabled) table.add(gyro_);
  if (rc.bumpers.enabled) table.add(bumpers_);
  if (rc.cliff.enabled) table.add(cliff_);
  if (rc.battery.enabled) table.add(battery_);
}

// --- pacing and co-stepping ------------------------------------------------------------------

void RealtimePacer::pace(Time sim_now) noexcept {
  if (!started_) {
    started_ = true;
    sim_start_ = sim_now;
    wall_start_ = wall_.now();
    return;
  }
  const double elapsed = static_cast<double>((sim_now - sim_start_).count()) / speed_;
  wall_.sleep_until(wall_start_ + Duration{static_cast<Duration::rep>(elapsed)});
}

std::vector<Pose2D> fleet_start_poses(const World& world, std::size_t n, double gap_m) {
  std::vector<Pose2D> poses;
  if (n == 0) return poses;
  poses.push_back(world.start_pose);
  const SolidMap solid(world.grid);
  const double r = world.robot.radius_m;
  const double spacing = 2.0 * r + gap_m;
  struct Candidate {
    double d;
    Pose2D pose;
  };
  std::vector<Candidate> candidates;
  constexpr int kRings = 12;
  for (int i = -kRings; i <= kRings; ++i) {
    for (int j = -kRings; j <= kRings; ++j) {
      if (i == 0 && j == 0) continue;
      const Pose2D p{world.start_pose.x_m + i * spacing, world.start_pose.y_m + j * spacing, world.start_pose.theta_rad};
      candidates.push_back({std::hypot(i, j) + 1e-3 * (i + kRings) + 1e-6 * (j + kRings), p});  // ties broken in a fixed order
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) { return a.d < b.d; });
  for (const Candidate& c : candidates) {
    if (poses.size() == n) break;
    if (solid.disc_overlaps({c.pose.x_m, c.pose.y_m}, r + 0.5 * gap_m)) continue;
    poses.push_back(c.pose);
  }
  if (poses.size() < n) {
    throw ConfigError(
        SourceLocation{world.file.string(), 1, 1},
        "no room for " + std::to_string(n) + " robots around the start pose (found " + std::to_string(poses.size()) + ")");
  }
  return poses;
}

}  // namespace tripodal::sim
