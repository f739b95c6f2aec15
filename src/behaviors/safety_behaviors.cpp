#include "tripodal/behaviors/safety_behaviors.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tripodal/behaviors/behavior_registry.hpp"

namespace tripodal {

namespace {

using parameter::number;
using parameter::text;

constexpr std::array<double, 3> kBeyond_m{0.0, 0.35, 0.7};  // hazard points ahead of a cliff sensor

// "a, b, c" or "x,y; x,y": numbers in groups of `per` (1 or 2); ConfigError naming the parameter.
std::vector<double> parse_numbers(const std::string& value, std::size_t per, std::size_t max_groups, std::string_view behavior,
                                  std::string_view parameter) {
  std::vector<double> out;
  std::string cleaned = value;
  std::replace(cleaned.begin(), cleaned.end(), ';', ' ');
  std::replace(cleaned.begin(), cleaned.end(), ',', ' ');
  std::istringstream in(cleaned);
  std::string word;
  while (in >> word) {
    std::size_t used = 0;
    double v = 0.0;
    try {
      v = std::stod(word, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != word.size() || !std::isfinite(v)) {
      throw ConfigError(SourceLocation{}, std::string(behavior) + ": parameter '" + std::string(parameter) + "': '" + word +
                                              "' is not a number (in '" + value + "')");
    }
    out.push_back(v);
  }
  if (out.empty() || out.size() % per != 0 || out.size() / per > max_groups) {
    throw ConfigError(SourceLocation{},
                      std::string(behavior) + ": parameter '" + std::string(parameter) + "' is '" + value + "'; expected 1 to " +
                          std::to_string(max_groups) +
                          (per == 2 ? " positions \"x,y; x,y; ...\" (body frame, m)" : " numbers \"a, b, ...\""));
  }
  return out;
}

BackOffReflex::Options reflex_options(const ParameterSet& params) {
  BackOffReflex::Options o;
  o.back_off_m = params.number("back_off_m");
  o.back_speed_m_s = params.number("back_speed_m_s");
  o.hold_s = params.number("hold_s");
  o.release_turn_rad = params.number("release_turn_rad");
  o.max_back_off_m = params.number("max_back_off_m");
  if (o.max_back_off_m < o.back_off_m) {
    throw ConfigError(SourceLocation{}, "max_back_off_m (" + std::to_string(o.max_back_off_m) +
                                            ") must be at least back_off_m (" + std::to_string(o.back_off_m) + ")");
  }
  return o;
}

std::vector<ParameterSpec> reflex_parameters(double back_off_m) {
  return {number("back_off_m", back_off_m, "m", "how far to back straight away once triggered", 0.0, 1.0),
          parameter::positive("back_speed_m_s", 0.1, "m/s", "backing speed"),
          number("max_back_off_m", 0.4, "m", "backing while the sensor still fires stops here (a sensor stuck)", 0.0, 2.0),
          number("hold_s", 12.0, "s",
                 "after backing, no forward translation this long (rotation free): the path follower counts itself "
                 "blocked and the sequencing layer plans around the hazard; longer than its blocked timeout, so "
                 "with no way around it gives up",
                 0.0, 600.0),
          number("release_turn_rad", 1.0, "rad", "the hold ends once the robot has turned this far away (toward a detour)", 0.0,
                 3.2)};
}

Pose2D to_map(const Pose2D& map_from_base, double bx, double by) noexcept {
  const double c = std::cos(map_from_base.theta_rad), s = std::sin(map_from_base.theta_rad);
  return {map_from_base.x_m + c * bx - s * by, map_from_base.y_m + s * bx + c * by, 0.0};
}

template <std::size_t N>
void report_hazards(const BehaviorContext& context, const std::array<Pose2D, N>& hazards, std::size_t count) noexcept {
  if (context.feedback == nullptr) return;
  for (std::size_t i = 0; i < count; ++i) context.feedback->add_hazard(hazards[i].x_m, hazards[i].y_m);
}

}  // namespace

// --- BackOffReflex ----------------------------------------------------------------------------

double BackOffReflex::turn_toward_side_rad() const noexcept {
  const double turn = std::remainder(heading_rad_ - heading0_rad_, 2.0 * std::numbers::pi);
  return side_ == Side::right ? -turn : turn;
}

bool BackOffReflex::update(bool triggered, Time now, double heading_rad, Side side) noexcept {
  bool fresh = false;
  heading_rad_ = heading_rad;
  if (triggered && phase_ != Phase::backing) {
    phase_ = Phase::backing;
    started_ = now;
    heading0_rad_ = heading_rad;
    side_ = side;
    fresh = true;
  }
  if (triggered) back_until_ = now + from_seconds(options_.back_off_m / options_.back_speed_m_s);
  if (phase_ == Phase::backing && !triggered && now >= back_until_) {
    phase_ = Phase::holding;
    hold_until_ = now + from_seconds(options_.hold_s);
  }
  if (phase_ == Phase::holding) {
    // Ahead: released once turned well away (a detour). From a side: once heading about along the
    // obstacle again (the way on), the arc having moved the body off it.
    const bool turned_away = side_ == Side::ahead ? std::abs(turn_toward_side_rad()) > options_.release_turn_rad
                                                  : turn_toward_side_rad() <= options_.side_release_rad;
    if (now >= hold_until_ || turned_away) phase_ = Phase::idle;
  }
  return fresh;
}

std::optional<VelocityEnvelope> BackOffReflex::envelope(Time now) const noexcept {
  VelocityEnvelope e;
  switch (phase_) {
    case Phase::idle:
      return std::nullopt;
    case Phase::backing: {
      // Straight back, the way the robot came (the sensors look ahead of the wheels), no farther
      // than max_back_off_m: a trigger still on then (a stuck sensor) leaves the robot standing.
      const bool too_far = to_seconds(now - started_) * options_.back_speed_m_s >= options_.max_back_off_m;
      const bool backs = !too_far && now < back_until_;
      e.vx_lo_m_s = e.vx_hi_m_s = backs ? -options_.back_speed_m_s : 0.0;
      e.vy_lo_m_s = e.vy_hi_m_s = 0.0;
      // From a side, an arc of side_turn_rad over back_off_m, rear away from the contact: turning
      // toward the contact's side while backing (counter-clockwise for the left).
      double wz = 0.0;
      if (backs && side_ != Side::ahead && options_.back_off_m > 0.0 && turn_toward_side_rad() < options_.side_turn_rad) {
        wz = options_.side_turn_rad * options_.back_speed_m_s / options_.back_off_m;
        if (side_ == Side::right) wz = -wz;
      }
      e.wz_lo_rad_s = e.wz_hi_rad_s = wz;
      return e;
    }
    case Phase::holding:
      e.vx_hi_m_s = 0.0;
      e.vy_lo_m_s = e.vy_hi_m_s = 0.0;
      return e;
  }
  return std::nullopt;
}

// --- BhCliffGuard -----------------------------------------------------------------------------

const ModuleManifest& BhCliffGuard::static_manifest() {
  static const ModuleManifest m = [] {
    std::vector<ParameterSpec> p{text("cliff", "", "infrared resource whose cliff bits are watched (empty: the first one)"),
                                 text("sensors", "0.2,0; 0.1,0.17; 0.1,-0.17",
                                      "the cliff sensors' places on the chassis, \"x,y; ...\" (body frame, m), in the resource's "
                                      "order: where a "
                                      "drop was seen"),
                                 text("event", "cliff", "the net event raised once per detection")};
    for (ParameterSpec& s : reflex_parameters(0.12)) p.push_back(std::move(s));
    return behavior_manifest("BhCliffGuard",
                             "cliff safety reflex: on a cliff bit stops, backs straight off, holds forward motion and "
                             "raises `cliff`",
                             {"cliff"}, std::move(p));
  }();
  return m;
}

void BhCliffGuard::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  const std::string& name = params.string("cliff");
  cliff_ = context.resources == nullptr ? nullptr
           : name.empty()               ? context.resources->first<InfraredReading>()
                                        : context.resources->find<InfraredReading>(name);
  const std::vector<double> xy = parse_numbers(params.string("sensors"), 2, kMaxSensors, "BhCliffGuard", "sensors");
  sensor_count_ = xy.size() / 2;
  for (std::size_t i = 0; i < sensor_count_; ++i) sensors_[i] = {xy[2 * i], xy[2 * i + 1], 0.0};
  event_ = params.string("event");
  reflex_.configure(reflex_options(params));
  reflex_.reset();
  hazard_count_ = 0;
  if (cliff_ == nullptr) fail("no cliff resource");
}

std::optional<Twist2D> BhCliffGuard::on_step(const BehaviorContext& context) noexcept {
  bool any = false;
  if (cliff_->is_fresh(context.now)) {
    const std::vector<std::uint8_t>& bits = cliff_->latest().cliff;
    any = std::any_of(bits.begin(), bits.end(), [](std::uint8_t b) { return b != 0; });
    if (any && context.navi != nullptr) {
      // Where the drop is: under each sensor that sees it (kept for the whole reflex, so the
      // sequencing layer still has it when the path follower reports itself blocked).
      // A ledge does not end at the edge: the floor is gone beyond it too, so the points go on
      // ahead of each sensor (kBeyond), and a detour keeps off the drop, not only off its edge.
      hazard_count_ = 0;
      for (std::size_t i = 0; i < bits.size() && i < sensor_count_; ++i) {
        if (bits[i] == 0) continue;
        for (const double ahead : kBeyond_m) {
          if (hazard_count_ < hazards_.size()) {
            hazards_[hazard_count_++] = to_map(context.navi->map_from_base, sensors_[i].x_m + ahead, sensors_[i].y_m);
          }
        }
      }
    }
  }
  const double heading = context.navi != nullptr ? context.navi->map_from_base.theta_rad : 0.0;
  if (reflex_.update(any, context.now, heading) && !event_.empty()) signal(event_);
  const std::optional<VelocityEnvelope> e = reflex_.envelope(context.now);
  if (!e) hazard_count_ = 0;
  report_hazards(context, hazards_, hazard_count_);
  set_envelope(e);
  return std::nullopt;
}

// --- BhBumperGuard ----------------------------------------------------------------------------

const ModuleManifest& BhBumperGuard::static_manifest() {
  static const ModuleManifest m = [] {
    std::vector<ParameterSpec> p{
        text("bumpers", "", "bumper resource watched (empty: the first one)"),
        number("back_mask", 4.0, "", "bits of the bump switches at the back (pressed alone: no backing)", 0.0, 255.0),
        number("sectors", 4.0, "", "the switches' equal sectors round the body, sector 0 ahead (for the contact's place)", 1.0,
               32.0),
        number("robot_radius_m", 0.25, "m", "radius of the circular footprint", 0.0, 5.0),
        number("side_angle_rad", 1.0, "rad",
               "pressed sectors whose mean direction is this far or more off ahead are a contact on that side: backed "
               "away from along an arc, not straight along the obstacle",
               0.0, 3.2),
        number("side_turn_rad", 0.6, "rad",
               "the arc backed from a side contact turns this far over back_off_m (the rear away from the contact)", 0.0, 1.6),
        number("side_release_rad", 0.3, "rad",
               "after a side contact the hold ends once the robot heads no more than this toward that side (relative to "
               "its heading at the contact): the way on along the obstacle",
               0.0, 1.6)};
    for (ParameterSpec& s : reflex_parameters(0.1)) p.push_back(std::move(s));
    return behavior_manifest("BhBumperGuard",
                             "bump safety reflex: a front bump switch stops the robot and backs it off (along an arc "
                             "away from a contact on a side)",
                             {"bumpers"}, std::move(p));
  }();
  return m;
}

void BhBumperGuard::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  const std::string& name = params.string("bumpers");
  bumpers_ = context.resources == nullptr ? nullptr
             : name.empty()               ? context.resources->first<BumperReading>()
                                          : context.resources->find<BumperReading>(name);
  back_mask_ = static_cast<std::uint32_t>(params.number("back_mask"));
  sectors_ = static_cast<std::uint32_t>(params.number("sectors"));
  radius_m_ = params.number("robot_radius_m");
  side_angle_rad_ = params.number("side_angle_rad");
  BackOffReflex::Options options = reflex_options(params);
  options.side_turn_rad = params.number("side_turn_rad");
  options.side_release_rad = params.number("side_release_rad");
  if (options.side_turn_rad > 0.0 && options.side_release_rad >= options.side_turn_rad) {
    throw ConfigError(SourceLocation{}, "BhBumperGuard: side_release_rad (" + std::to_string(options.side_release_rad) +
                                            ") must be less than side_turn_rad (" + std::to_string(options.side_turn_rad) +
                                            "), else the hold after a side contact ends as the backing does");
  }
  reflex_.configure(options);
  reflex_.reset();
  hazard_count_ = 0;
  if (bumpers_ == nullptr) fail("no bumper resource");
}

std::optional<Twist2D> BhBumperGuard::on_step(const BehaviorContext& context) noexcept {
  std::uint32_t pressed = 0;
  if (bumpers_->is_fresh(context.now)) pressed = bumpers_->latest().pressed_mask;
  const std::uint32_t front = pressed & ~back_mask_;
  // The contact's mean direction (body frame): ahead, or on a side (left and right at once, a
  // narrow gap, cancel out: ahead, straight back).
  double sum_x = 0.0, sum_y = 0.0;
  if (front != 0 && context.navi != nullptr) hazard_count_ = 0;
  for (std::uint32_t i = 0; i < sectors_ && i < 32; ++i) {
    if ((front & (1U << i)) == 0) continue;
    const double a = 2.0 * std::numbers::pi * i / sectors_;
    sum_x += std::cos(a);
    sum_y += std::sin(a);
    if (context.navi != nullptr && hazard_count_ < hazards_.size()) {
      const double r = radius_m_ + 0.05;
      hazards_[hazard_count_++] = to_map(context.navi->map_from_base, r * std::cos(a), r * std::sin(a));
    }
  }
  BackOffReflex::Side side = BackOffReflex::Side::ahead;
  if (std::hypot(sum_x, sum_y) > 1e-6 && std::abs(std::atan2(sum_y, sum_x)) >= side_angle_rad_) {
    side = sum_y > 0.0 ? BackOffReflex::Side::left : BackOffReflex::Side::right;
  }
  (void)reflex_.update(front != 0, context.now, context.navi != nullptr ? context.navi->map_from_base.theta_rad : 0.0, side);
  std::optional<VelocityEnvelope> e = reflex_.envelope(context.now);
  if (!e) hazard_count_ = 0;
  if ((pressed & back_mask_) != 0) {
    // Something touches the back: no backing into it (a front reflex then just stands).
    if (!e) e = VelocityEnvelope{};
    e->vx_lo_m_s = std::max(e->vx_lo_m_s, 0.0);
    e->vx_hi_m_s = std::max(e->vx_hi_m_s, 0.0);
  }
  report_hazards(context, hazards_, hazard_count_);
  set_envelope(e);
  return std::nullopt;
}

// --- BhSonarGuard -----------------------------------------------------------------------------

const ModuleManifest& BhSonarGuard::static_manifest() {
  static const ModuleManifest m = behavior_manifest(
      "BhSonarGuard",
      "ultrasonic safety override: slows and stops forward translation before what the sonar sees ahead "
      "(glass, a low "
      "table)",
      {"sonar"},
      {text("ultrasonic", "", "sonar resource watched (empty: the first one)"),
       text("angles_rad", "-0.5236, 0, 0.5236",
            "the transducers' directions on the rim (body frame, rad), in the resource's order"),
       number("cone_rad", 0.26, "rad", "full beam angle of a transducer", 0.0, 3.0),
       number("robot_radius_m", 0.25, "m", "radius of the circular footprint (the transducers sit on it)", 0.0, 5.0),
       number("stop_distance_m", 0.1, "m", "no forward motion with this little clearance ahead", 0.0, 2.0),
       number("slow_distance_m", 0.6, "m", "full speed allowed beyond this clearance", 0.0, 5.0),
       number("max_speed_m_s", 0.5, "m/s", "speed allowed at slow_distance_m and beyond", 0.0, 5.0),
       number("corridor_margin_m", 0.03, "m", "the corridor ahead is the footprint's width plus this each side", 0.0, 1.0)});
  return m;
}

void BhSonarGuard::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  const std::string& name = params.string("ultrasonic");
  sonar_ = context.resources == nullptr ? nullptr
           : name.empty()               ? context.resources->first<SonarReading>()
                                        : context.resources->find<SonarReading>(name);
  const std::vector<double> a = parse_numbers(params.string("angles_rad"), 1, kMaxTransducers, "BhSonarGuard", "angles_rad");
  angle_count_ = a.size();
  std::copy(a.begin(), a.end(), angles_.begin());
  radius_m_ = params.number("robot_radius_m");
  stop_m_ = params.number("stop_distance_m");
  slow_m_ = params.number("slow_distance_m");
  if (slow_m_ <= stop_m_)
    throw ConfigError(SourceLocation{}, "BhSonarGuard: slow_distance_m must be greater than stop_distance_m");
  max_speed_ = params.number("max_speed_m_s");
  margin_m_ = params.number("corridor_margin_m");
  cone_half_ = params.number("cone_rad") / 2.0;
  if (sonar_ == nullptr) fail("no ultrasonic resource");
}

std::optional<Twist2D> BhSonarGuard::on_step(const BehaviorContext& context) noexcept {
  VelocityEnvelope e;
  if (!sonar_->is_fresh(context.now)) {
    e.vx_hi_m_s = 0.0;  // blind ahead: no forward motion, backing and turning stay free
    set_envelope(e);
    return std::nullopt;
  }
  const std::vector<float>& ranges = sonar_->latest().ranges_m;
  double clearance = VelocityEnvelope::kInf;
  const double r = radius_m_;
  for (std::size_t i = 0; i < ranges.size() && i < angle_count_; ++i) {
    const double d = ranges[i];
    if (!std::isfinite(d)) continue;
    // The echo may come from anywhere in the cone: take its direction nearest straight ahead.
    const double lo = angles_[i] - cone_half_, hi = angles_[i] + cone_half_;
    const double a = lo > 0.0 ? lo : (hi < 0.0 ? hi : 0.0);
    const double x = (r + d) * std::cos(a), y = (r + d) * std::sin(a);
    if (x <= 0.0 || std::abs(y) > r + margin_m_) continue;  // beside the corridor the body sweeps
    const double m = r + d;
    if (context.navi != nullptr && context.navi->map != nullptr) {
      const Pose2D on_axis = to_map(context.navi->map_from_base, m * std::cos(angles_[i]), m * std::sin(angles_[i]));
      const Pose2D nearest = to_map(context.navi->map_from_base, x, y);
      if (context.navi->map->near_obstacle(on_axis.x_m, on_axis.y_m) ||
          context.navi->map->near_obstacle(nearest.x_m, nearest.y_m))
        continue;
    }
    const double c = x - std::sqrt(std::max(0.0, r * r - std::min(r * r, y * y)));
    clearance = std::min(clearance, c);
    if (c <= stop_m_ + 0.05 && context.feedback != nullptr && context.navi != nullptr) {
      const Pose2D p = to_map(context.navi->map_from_base, m * std::cos(angles_[i]), m * std::sin(angles_[i]));
      context.feedback->add_hazard(p.x_m, p.y_m);
    }
  }
  if (clearance <= stop_m_) {
    e.vx_hi_m_s = 0.0;
  } else if (clearance < slow_m_) {
    e.vx_hi_m_s = max_speed_ * (clearance - stop_m_) / (slow_m_ - stop_m_);
  } else {
    e.vx_hi_m_s = max_speed_;
  }
  set_envelope(e);
  return std::nullopt;
}

// --- registration -----------------------------------------------------------------------------

void register_safety_behaviors(BehaviorRegistry& registry) {
  registry.add<BhCliffGuard>();
  registry.add<BhBumperGuard>();
  registry.add<BhSonarGuard>();
}

}  // namespace tripodal
