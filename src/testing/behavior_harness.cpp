#include "tripodal/testing/behavior_harness.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_resources.hpp"

namespace tripodal::testing {

namespace {

std::string seconds(Time t) { return format_seconds(t) + " s"; }

std::string num(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", v);
  return buf;
}

std::string twist_text(const Twist2D& c) {
  return "(vx " + num(c.vx_m_s) + " m/s, vy " + num(c.vy_m_s) + " m/s, wz " + num(c.wz_rad_s) + " rad/s)";
}

}  // namespace

// --- RunLog ------------------------------------------------------------------------------------

std::optional<std::size_t> RunLog::behavior_index(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < names_.size(); ++i) {
    if (names_[i] == name) return i;
  }
  return std::nullopt;
}

std::optional<std::size_t> RunLog::require_index(std::string_view behavior, CheckResult& out) const {
  auto i = behavior_index(behavior);
  if (!i) {
    out.passed = false;
    out.explanation = "no behavior named '" + std::string(behavior) + "' is attached (attached:";
    for (const auto& n : names_) out.explanation += " " + n;
    out.explanation += ")";
  }
  return i;
}

CheckResult RunLog::command_never_exceeds(const CommandLimits& limits) const {
  constexpr double kTol = 1e-9;
  std::size_t violations = 0;
  std::string first;
  double peak_vx = 0.0, peak_vy = 0.0, peak_wz = 0.0;
  for (const StepRecord& s : steps_) {
    const Twist2D& c = s.command;
    peak_vx = std::max(peak_vx, std::abs(c.vx_m_s));
    peak_vy = std::max(peak_vy, std::abs(c.vy_m_s));
    peak_wz = std::max(peak_wz, std::abs(c.wz_rad_s));
    // Written so that a NaN command counts as a violation.
    const bool ok = std::abs(c.vx_m_s) <= limits.max_vx_m_s + kTol && std::abs(c.vy_m_s) <= limits.max_vy_m_s + kTol &&
                    std::abs(c.wz_rad_s) <= limits.max_wz_rad_s + kTol;
    if (ok) continue;
    if (violations++ == 0) {
      first = "at t=" + seconds(s.t) + " the command " + twist_text(c) + " exceeds the limits (|vx| <= " +
              num(limits.max_vx_m_s) + ", |vy| <= " + num(limits.max_vy_m_s) + ", |wz| <= " + num(limits.max_wz_rad_s) + ")";
    }
  }
  CheckResult r;
  r.passed = violations == 0;
  if (r.passed) {
    r.explanation = std::to_string(steps_.size()) + " commands within limits; peaks |vx| " + num(peak_vx) + " m/s, |vy| " +
                    num(peak_vy) + " m/s, |wz| " + num(peak_wz) + " rad/s";
  } else {
    r.explanation = first + "; " + std::to_string(violations) + " of " + std::to_string(steps_.size()) + " commands exceed them";
  }
  return r;
}

CheckResult RunLog::succeeds_before(std::string_view behavior, Time t) const {
  CheckResult r;
  const auto i = require_index(behavior, r);
  if (!i) return r;
  for (const StepRecord& s : steps_) {
    const BehaviorStatus st = s.behaviors[*i].status;
    if (st == BehaviorStatus::succeeded) {
      r.passed = s.t <= t;
      r.explanation = std::string(behavior) + " succeeded at t=" + seconds(s.t) + (r.passed ? ", not after " : ", after ") + seconds(t);
      return r;
    }
    if (st == BehaviorStatus::failed) {
      r.explanation = std::string(behavior) + " failed at t=" + seconds(s.t);
      for (const auto& e : events_) {
        if (e.name == failed_event_name(behavior)) {
          r.explanation += ": " + e.detail;
          break;
        }
      }
      return r;
    }
  }
  r.explanation = std::string(behavior) + " never succeeded in " + std::to_string(steps_.size()) + " steps";
  if (!steps_.empty()) {
    r.explanation += " up to t=" + seconds(steps_.back().t) + " (last status: " +
                     std::string(to_string(steps_.back().behaviors[*i].status)) + ")";
  }
  return r;
}

CheckResult RunLog::never_fails(std::string_view behavior) const {
  CheckResult r;
  const auto i = require_index(behavior, r);
  if (!i) return r;
  const std::string failed = failed_event_name(behavior);
  for (const auto& e : events_) {
    if (e.name == failed) {
      r.explanation = std::string(behavior) + " failed at t=" + seconds(e.t) + ": " + e.detail;
      return r;
    }
  }
  r.passed = true;
  r.explanation = std::string(behavior) + " did not fail in " + std::to_string(steps_.size()) + " steps";
  return r;
}

CheckResult RunLog::never_drives_toward_obstacle_closer_than(double distance_m, double min_speed_m_s) const {
  std::size_t violations = 0, moving = 0;
  std::string first;
  double closest = std::numeric_limits<double>::infinity();
  for (const StepRecord& s : steps_) {
    const double speed = std::hypot(s.command.vx_m_s, s.command.vy_m_s);
    if (!(speed > min_speed_m_s)) continue;
    ++moving;
    closest = std::min(closest, s.clearance_m);
    if (s.clearance_m >= distance_m) continue;
    if (violations++ == 0) {
      first = "at t=" + seconds(s.t) + " the command " + twist_text(s.command) + " drives toward an obstacle " +
              num(s.clearance_m) + " m from the footprint, closer than " + num(distance_m) + " m";
    }
  }
  CheckResult r;
  r.passed = violations == 0;
  if (r.passed) {
    r.explanation = std::to_string(moving) + " translating commands, the closest obstacle along the motion " + num(closest) +
                    " m (limit " + num(distance_m) + " m)";
  } else {
    r.explanation = first + "; " + std::to_string(violations) + " of " + std::to_string(moving) + " translating commands do";
  }
  return r;
}

CheckResult RunLog::event_before(std::string_view name, Time t) const {
  CheckResult r;
  for (const auto& e : events_) {
    if (e.name != name) continue;
    r.passed = e.t <= t;
    r.explanation = "event " + std::string(name) + " at t=" + seconds(e.t) + (r.passed ? ", not after " : ", after ") + seconds(t);
    return r;
  }
  r.explanation = "event " + std::string(name) + " never happened (" + std::to_string(events_.size()) + " events:";
  for (std::size_t k = 0; k < events_.size() && k < 5; ++k) r.explanation += " " + events_[k].name;
  r.explanation += events_.size() > 5 ? " ...)" : ")";
  return r;
}

CheckResult RunLog::commands_equal(const std::vector<trace::CommandRecord>& expected) const {
  CheckResult r;
  const std::size_t n = std::min(expected.size(), steps_.size());
  for (std::size_t k = 0; k < n; ++k) {
    const auto& e = expected[k];
    const auto& s = steps_[k];
    if (e.stamp != s.t || !(e.twist == s.command)) {
      r.explanation = "command " + std::to_string(k) + " differs: expected " + twist_text(e.twist) + " at t=" + seconds(e.stamp) +
                      ", got " + twist_text(s.command) + " at t=" + seconds(s.t);
      return r;
    }
  }
  if (expected.size() != steps_.size()) {
    r.explanation = "the first " + std::to_string(n) + " commands are equal, but " + std::to_string(expected.size()) +
                    " were expected and " + std::to_string(steps_.size()) + " produced";
    return r;
  }
  r.passed = true;
  r.explanation = std::to_string(n) + " commands equal bit for bit";
  return r;
}

BehaviorStatus RunLog::status_at(std::string_view behavior, Time t) const {
  const auto i = behavior_index(behavior);
  if (!i) return BehaviorStatus::idle;
  BehaviorStatus st = BehaviorStatus::idle;
  for (const StepRecord& s : steps_) {
    if (s.t > t) break;
    st = s.behaviors[*i].status;
  }
  return st;
}

// --- BehaviorHarness ---------------------------------------------------------------------------

struct BehaviorHarness::Attached {
  std::unique_ptr<CBehavior> behavior;
  ParameterValues params;
  SourceLocation where;
  InputId input = 0;
  BehaviorStatus last = BehaviorStatus::idle;
};

// Keeps the trace's commands and events; TraceResources publishes the readings.
class BehaviorHarness::Sink final : public trace::TraceResources {
 public:
  Sink(const std::vector<trace::ChannelInfo>& channels, Duration max_age, RunLog& log)
      : TraceResources(channels, max_age), log_(log) {}
  void on_command(const trace::ChannelInfo& /*c*/, const trace::CommandRecord& r) override { log_.recorded_.push_back(r); }
  void on_event(const trace::ChannelInfo& /*c*/, const trace::EventRecord& r) override {
    log_.events_.push_back(HarnessEvent{r.stamp, "trace:" + r.name, {}});
  }

 private:
  RunLog& log_;
};

BehaviorHarness::BehaviorHarness(HarnessOptions options)
    : options_(std::move(options)) {
  if (options_.period <= Duration{0}) throw std::invalid_argument("BehaviorHarness: period must be positive");
  coordinator_ = std::make_unique<CBehaviorCoordinator>(CoordinatorConfig{options_.mode, {}, {}, {}});
}

BehaviorHarness::~BehaviorHarness() = default;

void BehaviorHarness::load_trace(const std::filesystem::path& trace_path) {
  if (replay_) throw std::logic_error("BehaviorHarness: a trace is already loaded");
  // First pass: the channel declarations (resources must exist before behaviors activate) and the
  // last stamp (where the run ends). Streams: nothing is kept but the channels.
  auto source = std::make_unique<trace::TraceSource>(trace_path);
  trace::TraceSummary summary = trace::summarize_trace(source->trace());
  warning_ = summary.warning;
  const auto& channels = summary.channels;
  // Checked before any resource exists, so a failed load leaves the harness as it was.
  if (!options_.laser.empty() && trace::find_channel(channels, options_.laser, trace::ChannelKind::kLaser) == nullptr) {
    throw std::invalid_argument("BehaviorHarness: the trace " + trace_path.string() + " has no laser channel '" +
                                options_.laser + "'");
  }
  if (!options_.localization_channel.empty() &&
      trace::find_channel(channels, options_.localization_channel, trace::ChannelKind::kOdometry) == nullptr) {
    throw std::invalid_argument("BehaviorHarness: the trace " + trace_path.string() + " has no odometry channel '" +
                                options_.localization_channel + "' for the localization");
  }
  sink_ = std::make_unique<Sink>(channels, options_.resource_max_age, log_);
  sink_->add_to(table_);
  laser_ = options_.laser.empty() ? table_.first<LaserScan>() : table_.find<LaserScan>(options_.laser);
  if (!options_.localization_channel.empty()) localization_ = table_.find<OdometryReading>(options_.localization_channel);
  replay_ = std::make_unique<trace::TraceReplay>(std::make_unique<trace::TraceReader>(source->trace()));
  source_ = std::move(source);
  start_ = replay_->start_time();
  now_ = start_;
  last_record_ = summary.empty ? start_ : summary.last;
}

CBehavior& BehaviorHarness::attach(std::unique_ptr<CBehavior> behavior, ParameterValues params, CoordinatorInputConfig input,
                                   SourceLocation where) {
  if (started_) throw std::logic_error("BehaviorHarness: attach() after run() started");
  if (!behavior) throw std::invalid_argument("BehaviorHarness: attach() of a null behavior");
  if (input.name.empty()) input.name = std::string(behavior->name());
  const std::string name = input.name;
  Attached a;
  a.input = coordinator_->add_input(std::move(input));
  a.params = std::move(params);
  a.where = where;
  a.behavior = std::move(behavior);
  attached_.push_back(std::move(a));
  log_.names_.push_back(name);
  return *attached_.back().behavior;
}

const RunLog& BehaviorHarness::run(std::optional<Time> until, bool stop_when_done) {
  if (!replay_) throw std::logic_error("BehaviorHarness: run() before load_trace()");
  // One period past the last record: the behaviors see the last reading at least once.
  const Time end = until ? std::min(*until, last_record_ + options_.period) : last_record_ + options_.period;
  while (now_ <= end) {
    step_once();
    if (stop_when_done) {
      bool any_running = false;
      for (const auto& a : attached_) {
        if (coordinator_->input_config(a.input).role == InputRole::normal && a.behavior->running()) any_running = true;
      }
      if (!any_running) break;
    }
  }
  return log_;
}

void BehaviorHarness::step_once() {
  replay_->advance_to(now_, *sink_);
  if (localization_ != nullptr && localization_->has_reading()) {
    navi_.map_from_base = localization_->latest().pose;
    navi_.pose_stamp = localization_->stamp();
    navi_.localized = true;
  }
  BehaviorContext ctx;
  ctx.now = now_;
  ctx.period = options_.period;
  ctx.resources = &table_;
  ctx.navi = &navi_;
  ctx.base = options_.base;
  if (!started_) {
    started_ = true;
    for (auto& a : attached_) a.behavior->activate(a.params, ctx, a.where);
  }
  StepRecord rec;
  rec.t = now_;
  rec.behaviors.reserve(attached_.size());
  for (auto& a : attached_) {
    CBehavior& b = *a.behavior;
    const auto command = b.step(ctx);
    if (b.envelope()) {
      coordinator_->submit_envelope(a.input, *b.envelope(), now_);
    } else if (command) {
      coordinator_->submit(a.input, *command, now_);
    } else {
      coordinator_->withdraw(a.input);
    }
    const BehaviorStatus st = b.status();
    if (st != a.last) {
      if (st == BehaviorStatus::succeeded) log_.events_.push_back(HarnessEvent{now_, done_event_name(b.name()), {}});
      if (st == BehaviorStatus::failed) {
        log_.events_.push_back(HarnessEvent{now_, failed_event_name(b.name()), std::string(b.failure_reason())});
      }
      a.last = st;
    }
    rec.behaviors.push_back(BehaviorSample{command, b.envelope(), st});
  }
  const CoordinatorOutput& out = coordinator_->update(now_);
  rec.command = out.command;
  rec.safety_limited = out.safety_limited;
  rec.all_expired = out.all_expired;
  rec.clearance_m = clearance_along(out.command);
  log_.steps_.push_back(std::move(rec));
  now_ += options_.period;
}

double BehaviorHarness::clearance_along(const Twist2D& command) const noexcept {
  if (laser_ == nullptr || !laser_->has_reading()) return std::numeric_limits<double>::infinity();
  return footprint_clearance_m(laser_->latest(), options_.laser_in_body, options_.robot_radius_m, command);
}

double footprint_clearance_m(const LaserScan& scan, const Pose2D& laser_in_body, double robot_radius_m,
                             const Twist2D& command) noexcept {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double speed = std::hypot(command.vx_m_s, command.vy_m_s);
  if (!(speed > 0.0)) return kInf;
  const double ux = command.vx_m_s / speed, uy = command.vy_m_s / speed;
  const Pose2D& m = laser_in_body;
  const double r = robot_radius_m;
  double best = kInf;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double range = scan.ranges_m[i];
    if (!(range >= scan.range_min_m && range <= scan.range_max_m)) continue;
    // CARMEN logs mark "no return" with the maximum range: it is not an obstacle.
    if (range >= scan.range_max_m) continue;
    const double a = m.theta_rad + scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double x = m.x_m + range * std::cos(a), y = m.y_m + range * std::sin(a);
    const double along = x * ux + y * uy;
    const double across = -x * uy + y * ux;
    // Points in the corridor swept by the footprint moving along u, ahead of the centre.
    if (along <= 0.0 || std::abs(across) > r) continue;
    best = std::min(best, along - r);
  }
  return best;
}

CheckResult RunLog::event_never_happens(std::string_view name) const {
  CheckResult r;
  for (const auto& e : events_) {
    if (e.name != name) continue;
    r.explanation = "event " + std::string(name) + " at t=" + seconds(e.t) + (e.detail.empty() ? "" : ": " + e.detail);
    return r;
  }
  r.passed = true;
  r.explanation = "event " + std::string(name) + " never happened in " + std::to_string(steps_.size()) + " steps";
  return r;
}

}  // namespace tripodal::testing
