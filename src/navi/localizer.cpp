#include "tripodal/navi/localizer.hpp"

#include "tripodal/hardware/hardware.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

namespace tripodal::navi {

std::vector<LocalizationFault> parse_fault_schedule(const std::string& text, const SourceLocation& where) {
  std::vector<LocalizationFault> out;
  Diagnostics d;
  std::size_t pos = 0;
  while (pos <= text.size()) {
    std::size_t end = text.find(';', pos);
    if (end == std::string::npos) end = text.size();
    std::string item = text.substr(pos, end - pos);
    const auto first = item.find_first_not_of(" \t");
    const auto last = item.find_last_not_of(" \t");
    item = first == std::string::npos ? std::string() : item.substr(first, last - first + 1);
    if (!item.empty()) {
      double a = 0.0, b = 0.0;
      char dash = 0;
      std::istringstream in(item);
      in >> a >> dash >> b;
      const bool read = !in.fail();
      std::string rest;
      in >> rest;
      if (read && dash == '-' && rest.empty() && std::isfinite(a) && std::isfinite(b) && a >= 0.0 && b > a) {
        out.push_back({time_from_seconds(a), time_from_seconds(b)});
      } else {
        d.error(where, "bad localization fault '" + item + "': expected START-END in seconds with 0 <= START < END, "
                       "windows separated by ';' (e.g. \"10-20; 35.5-40\")");
      }
    }
    pos = end + 1;
  }
  if (d.has_errors()) throw ConfigError(d);
  return out;
}

CGroundTruthLocalizer::CGroundTruthLocalizer(const GroundTruthSource* truth, LocalizerOptions options)
    : truth_(truth), options_(std::move(options)), rng_(options_.seed) {}

const ModuleManifest& CGroundTruthLocalizer::static_manifest() {
  static const ModuleManifest m = navi_manifest(
      "GroundTruthLocalizer",
      "pose estimate from the simulator's ground truth with seeded noise and injected faults; posts "
      "localizer.ok / localizer.lost",
      {"ground_truth_pose"}, {"map_from_base", "position_fix", "localizer.ok", "localizer.lost"},
      {ParameterSpec{"noise_xy_m", ValueType::number, Value{0.02}, "m", "position noise (standard deviation per axis)", 0.0,
                     std::nullopt},
       ParameterSpec{"noise_theta_rad", ValueType::number, Value{0.01}, "rad", "heading noise (standard deviation)", 0.0,
                     std::nullopt},
       ParameterSpec{"lost_threshold_m", ValueType::number, Value{0.3}, "m", "position error beyond which the estimate disagrees",
                     1e-6, std::nullopt},
       ParameterSpec{"lost_threshold_rad", ValueType::number, Value{0.35}, "rad",
                     "heading error beyond which the estimate disagrees", 1e-6, std::nullopt},
       ParameterSpec{"fault_offset_m", ValueType::number, Value{2.0}, "m", "estimate jump when a fault starts", 0.0,
                     std::nullopt},
       ParameterSpec{"recover_at_fault_end", ValueType::boolean, Value{false}, "",
                     "estimate returns by itself when a fault window ends (else global localization is needed)", std::nullopt,
                     std::nullopt},
       ParameterSpec{"seed", ValueType::number, Value{1.0}, "", "noise seed: the same seed gives the same run", 0.0,
                     std::nullopt},
       ParameterSpec{"faults", ValueType::string, Value{std::string()}, "s",
                     "loss windows \"START-END; START-END\" in seconds of simulated time", std::nullopt, std::nullopt},
       ParameterSpec{"serves", ValueType::string, Value{std::string("BhGlobalLocalization")}, "",
                     "the behavior during whose activation it attempts global position fixes (its parameter "
                     "attempt_period_s)",
                     std::nullopt, std::nullopt}});
  return m;
}

void CGroundTruthLocalizer::on_configure(const ParameterSet& params) {
  fix_attempts_.serves = params.string("serves");
  LocalizerOptions o;
  o.noise_xy_m = params.number("noise_xy_m");
  o.noise_theta_rad = params.number("noise_theta_rad");
  o.lost_threshold_m = params.number("lost_threshold_m");
  o.lost_threshold_rad = params.number("lost_threshold_rad");
  o.fault_offset_m = params.number("fault_offset_m");
  o.recover_at_fault_end = params.boolean("recover_at_fault_end");
  o.seed = static_cast<std::uint64_t>(params.number("seed"));
  o.faults = parse_fault_schedule(params.string("faults"));
  options_ = std::move(o);
  rng_.seed(options_.seed);
  state_ = State::unknown;
  corrupted_ = false;
  estimate_.reset();
}

bool CGroundTruthLocalizer::in_fault(Time now) const noexcept {
  if (truth_ != nullptr && truth_->localization_lost(now)) return true;
  for (const LocalizationFault& f : options_.faults) {
    if (now >= f.start && now < f.end) return true;
  }
  return false;
}

bool CGroundTruthLocalizer::relocalize(Time now) noexcept {
  if (truth_ == nullptr || in_fault(now) || !truth_->true_pose(now)) return false;
  corrupted_ = false;
  return true;
}

void CGroundTruthLocalizer::publish(NavigationData& data) const noexcept {
  if (estimate_) data.map_from_base = *estimate_;
  data.pose_stamp = stamp_;
  data.localized = localized();
}

void CGroundTruthLocalizer::on_start(ModuleContext& context) {
  if (truth_ == nullptr) truth_ = dynamic_cast<const GroundTruthSource*>(context.hardware);
  if (truth_ == nullptr) {
    throw ConfigError(
        where(), "GroundTruthLocalizer estimates the pose from a simulation's ground truth, and the robot's hardware gives none");
  }
}

void CGroundTruthLocalizer::on_update(ModuleContext& context) {
  step(context.now, context.events);
  if (fix_attempts_.due(context.now) && relocalize(context.now)) ++fixes_;
  context.heartbeat = true;
  publish(*context.navigation);
  context.navigation->fixes = fixes_;
}

void CGroundTruthLocalizer::on_behavior_activated(const BehaviorActivation& activation, ModuleContext& context) {
  fix_attempts_.activated(activation, context.now);
}

void CGroundTruthLocalizer::on_behavior_deactivated(std::string_view behavior, ModuleContext& /*context*/) {
  fix_attempts_.deactivated(behavior);
}

void CGroundTruthLocalizer::step(Time now, std::vector<ModuleEvent>& out) noexcept {
  if (!configured()) return;
  if (truth_ == nullptr) return;
  const std::optional<Pose2D> truth = truth_->true_pose(now);
  if (!truth) return;
  const bool faulted = in_fault(now);
  if (faulted && !corrupted_) {
    // the estimate jumps away in a seeded direction, as after a wrong scan match
    std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
    const double a = angle(rng_);
    offset_ = {options_.fault_offset_m * std::cos(a), options_.fault_offset_m * std::sin(a), 0.0};
    corrupted_ = true;
  } else if (!faulted && corrupted_ && options_.recover_at_fault_end) {
    corrupted_ = false;
  }
  std::normal_distribution<double> nxy(0.0, 1.0);
  const double ex = options_.noise_xy_m * nxy(rng_);
  const double ey = options_.noise_xy_m * nxy(rng_);
  const double et = options_.noise_theta_rad * nxy(rng_);
  Pose2D est{truth->x_m + ex, truth->y_m + ey, wrap_angle(truth->theta_rad + et)};
  if (corrupted_) {
    est.x_m += offset_.x_m;
    est.y_m += offset_.y_m;
  }
  estimate_ = est;
  stamp_ = now;
  error_m_ = std::hypot(est.x_m - truth->x_m, est.y_m - truth->y_m);
  const double heading_error = std::abs(wrap_angle(est.theta_rad - truth->theta_rad));
  const bool agrees = error_m_ <= options_.lost_threshold_m && heading_error <= options_.lost_threshold_rad;
  const State next = agrees ? State::ok : State::lost;
  if (next == state_) return;
  state_ = next;
  try {
    std::ostringstream msg;
    msg.precision(3);
    msg << (agrees ? "estimate agrees with the actual position" : "estimate disagrees with the actual position")
        << " (error " << error_m_ << " m, " << heading_error << " rad)";
    out.push_back({now, agrees ? "localizer.ok" : "localizer.lost", msg.str()});
  } catch (...) {
    // out of memory while posting: the state change is kept, the event is lost
  }
}

}  // namespace tripodal::navi
