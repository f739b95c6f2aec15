#include "tripodal/behaviors/behavior.hpp"

#include <cmath>

namespace tripodal {

std::string_view to_string(BehaviorStatus status) noexcept {
  switch (status) {
    case BehaviorStatus::idle: return "idle";
    case BehaviorStatus::running: return "running";
    case BehaviorStatus::succeeded: return "succeeded";
    case BehaviorStatus::failed: return "failed";
  }
  return "?";
}

double SafetyFeedback::requested_speed_m_s() const noexcept { return std::hypot(requested.vx_m_s, requested.vy_m_s); }
double SafetyFeedback::allowed_speed_m_s() const noexcept { return std::hypot(allowed.vx_m_s, allowed.vy_m_s); }

std::string done_event_name(std::string_view behavior_name) { return std::string(behavior_name) + ".done"; }
std::string failed_event_name(std::string_view behavior_name) { return std::string(behavior_name) + ".failed"; }

void CBehavior::activate(const ParameterValues& params, const BehaviorContext& context,
                         const SourceLocation& where) {
  activate(ParameterSet::resolve(manifest(), params, where), context);
}

void CBehavior::activate(const ParameterSet& params, const BehaviorContext& context) {
  const std::vector<ChannelWrite>& writes = manifest().writes;
  if (writes.size() > kMaxBehaviorChannels) {
    throw ConfigError(SourceLocation{}, "behavior '" + std::string(name()) + "' declares " + std::to_string(writes.size()) +
                                            " channel writes, at most " + std::to_string(kMaxBehaviorChannels));
  }
  for (std::size_t i = 0; i < kMaxBehaviorChannels; ++i) {
    channel_names_[i] = i >= writes.size()            ? std::string()
                        : writes[i].parameter.empty() ? writes[i].name
                                                      : params.string(writes[i].parameter);
  }
  // Running before on_activate() so that a hook reporting an immediate outcome (goal already
  // reached, resource missing) is not overwritten.
  status_ = BehaviorStatus::running;
  failure_reason_ = {};
  envelope_.reset();
  clear_writes();
  steps_ = 0;
  try {
    on_activate(params, context);
  } catch (...) {
    status_ = BehaviorStatus::idle;
    throw;
  }
}

void CBehavior::deactivate() noexcept {
  if (status_ != BehaviorStatus::idle) on_deactivate();
  status_ = BehaviorStatus::idle;
  failure_reason_ = {};
  envelope_.reset();
  clear_writes();
}

std::optional<Twist2D> CBehavior::step(const BehaviorContext& context) noexcept {
  envelope_.reset();
  clear_writes();
  if (status_ != BehaviorStatus::running) return std::nullopt;
  ++steps_;
  std::optional<Twist2D> command = on_step(context);
  // A behavior that finished in this step has nothing more to command.
  if (status_ != BehaviorStatus::running) {
    envelope_.reset();
    clear_writes();
    return std::nullopt;
  }
  return command;
}

}  // namespace tripodal
