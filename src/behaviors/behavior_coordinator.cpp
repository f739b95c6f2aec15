#include "tripodal/behaviors/behavior_coordinator.hpp"

#include <algorithm>
#include <stdexcept>

namespace tripodal {

std::string_view to_string(CoordinationMode mode) noexcept {
  switch (mode) {
    case CoordinationMode::priority: return "priority";
    case CoordinationMode::weighted_sum: return "weighted_sum";
  }
  return "?";
}

CBehaviorCoordinator::CBehaviorCoordinator(CoordinatorConfig config) : mode_(config.mode) {
  for (auto& ch : config.channels) add_channel(std::move(ch));
  for (auto& in : config.inputs) add_input(std::move(in));
  for (auto& lock : config.locks) add_lock(std::move(lock));
}

InputId CBehaviorCoordinator::add_input(CoordinatorInputConfig input) {
  if (find_input(input.name)) throw std::invalid_argument("coordinator input '" + input.name + "' already exists");
  if (!(input.weight >= 0.0)) throw std::invalid_argument("coordinator input '" + input.name + "': weight must be >= 0");
  if (input.timeout.count() < 0) throw std::invalid_argument("coordinator input '" + input.name + "': timeout must be >= 0");
  InputState s;
  s.config = std::move(input);
  s.channels.resize(channels_.size());
  inputs_.push_back(std::move(s));
  return static_cast<InputId>(inputs_.size() - 1);
}

LockId CBehaviorCoordinator::add_lock(CoordinatorLockConfig lock) {
  if (find_lock(lock.name)) throw std::invalid_argument("coordinator lock '" + lock.name + "' already exists");
  if (lock.timeout.count() < 0) throw std::invalid_argument("coordinator lock '" + lock.name + "': timeout must be >= 0");
  LockState s;
  s.config = std::move(lock);
  locks_.push_back(std::move(s));
  return static_cast<LockId>(locks_.size() - 1);
}

ChannelId CBehaviorCoordinator::add_channel(ChannelSpec spec) {
  if (spec.name.empty()) throw std::invalid_argument("a coordinator channel needs a name");
  if (find_channel(spec.name)) throw std::invalid_argument("coordinator channel '" + spec.name + "' already exists");
  ChannelState c;
  c.output.value = spec.safe;
  c.spec = std::move(spec);
  channels_.push_back(std::move(c));
  for (InputState& in : inputs_) in.channels.resize(channels_.size());
  return static_cast<ChannelId>(channels_.size() - 1);
}

std::optional<ChannelId> CBehaviorCoordinator::find_channel(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < channels_.size(); ++i) {
    if (channels_[i].spec.name == name) return static_cast<ChannelId>(i);
  }
  return std::nullopt;
}

void CBehaviorCoordinator::submit_channel(InputId id, ChannelId channel, const ChannelValue& value, Time stamp) noexcept {
  if (id >= inputs_.size() || channel >= channels_.size()) return;
  ChannelWriteState& w = inputs_[id].channels[channel];
  w.has = true;
  w.value = value;
  w.stamp = stamp;
}

void CBehaviorCoordinator::withdraw_channel(InputId id, ChannelId channel) noexcept {
  if (id >= inputs_.size() || channel >= channels_.size()) return;
  inputs_[id].channels[channel].has = false;
}

void CBehaviorCoordinator::withdraw_channels(InputId id) noexcept {
  if (id >= inputs_.size()) return;
  for (ChannelWriteState& w : inputs_[id].channels) w.has = false;
}

std::optional<InputId> CBehaviorCoordinator::find_input(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < inputs_.size(); ++i) {
    if (inputs_[i].config.name == name) return static_cast<InputId>(i);
  }
  return std::nullopt;
}

std::optional<LockId> CBehaviorCoordinator::find_lock(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < locks_.size(); ++i) {
    if (locks_[i].config.name == name) return static_cast<LockId>(i);
  }
  return std::nullopt;
}

const CoordinatorInputConfig& CBehaviorCoordinator::input_config(InputId id) const noexcept {
  return inputs_[id].config;
}

void CBehaviorCoordinator::submit(InputId id, const Twist2D& command, Time stamp) noexcept {
  if (id >= inputs_.size()) return;
  InputState& s = inputs_[id];
  s.has_command = true;
  s.has_envelope = false;
  s.command = command;
  s.stamp = stamp;
}

void CBehaviorCoordinator::submit_envelope(InputId id, const VelocityEnvelope& envelope, Time stamp) noexcept {
  if (id >= inputs_.size()) return;
  InputState& s = inputs_[id];
  s.has_command = true;
  s.has_envelope = true;
  s.envelope = envelope;
  s.stamp = stamp;
}

void CBehaviorCoordinator::withdraw(InputId id) noexcept {
  if (id >= inputs_.size()) return;
  inputs_[id].has_command = false;
  inputs_[id].has_envelope = false;
}

void CBehaviorCoordinator::set_lock(LockId id, bool engaged, Time stamp) noexcept {
  if (id >= locks_.size()) return;
  LockState& s = locks_[id];
  s.has_message = true;
  s.engaged = engaged;
  s.stamp = stamp;
}

void CBehaviorCoordinator::reset() noexcept {
  for (auto& s : inputs_) {
    s.has_command = false;
    s.has_envelope = false;
    for (ChannelWriteState& w : s.channels) w.has = false;
  }
  for (ChannelState& c : channels_) c.output = ChannelOutput{c.spec.safe, {}, false, false};
  for (auto& s : locks_) {
    s.has_message = false;
    s.engaged = false;
  }
  output_ = {};
}

namespace {

bool expired(Time now, Time stamp, Duration timeout) noexcept {
  return timeout.count() > 0 && now - stamp > timeout;
}

// Clamps `value` into [lo, hi]; an empty interval gives 0 (no agreement on that axis).
double clamp_axis(double value, double lo, double hi) noexcept {
  if (lo > hi) return 0.0;
  return std::clamp(value, lo, hi);
}

}  // namespace

const CoordinatorOutput& CBehaviorCoordinator::update(Time now) noexcept {
  CoordinatorOutput out;
  out.stamp = now;

  // Locks: the highest engaged priority masks every input at or below it.
  bool masking = false;
  int mask_priority = 0;
  for (const LockState& lock : locks_) {
    const bool dead_man = lock.config.timeout.count() > 0 &&
                          (!lock.has_message || expired(now, lock.stamp, lock.config.timeout));
    if (!(dead_man || (lock.has_message && lock.engaged))) continue;
    if (!masking || lock.config.priority > mask_priority) {
      mask_priority = lock.config.priority;
      out.lock = lock.config.name;
    }
    masking = true;
  }
  out.locked = masking;

  auto usable = [&](const InputState& s) noexcept {
    if (!s.has_command || expired(now, s.stamp, s.config.timeout)) return false;
    return !(masking && s.config.priority <= mask_priority);
  };

  Twist2D fused;
  if (mode_ == CoordinationMode::priority) {
    const InputState* best = nullptr;
    for (std::size_t i = 0; i < inputs_.size(); ++i) {
      const InputState& s = inputs_[i];
      if (s.config.role != InputRole::normal || !usable(s)) continue;
      ++out.live_inputs;
      // Strictly greater: on a tie the earlier-configured input keeps the lead.
      if (best == nullptr || s.config.priority > best->config.priority) {
        best = &s;
        out.winner_id = static_cast<InputId>(i);
      }
    }
    if (best != nullptr) {
      fused = best->command;
      out.winner = best->config.name;
    }
  } else {
    double total = 0.0;
    double heaviest = -1.0;
    for (std::size_t i = 0; i < inputs_.size(); ++i) {
      const InputState& s = inputs_[i];
      if (s.config.role != InputRole::normal || !usable(s) || s.config.weight <= 0.0) continue;
      ++out.live_inputs;
      const double w = s.config.weight;
      fused.vx_m_s += w * s.command.vx_m_s;
      fused.vy_m_s += w * s.command.vy_m_s;
      fused.wz_rad_s += w * s.command.wz_rad_s;
      total += w;
      if (w > heaviest) {
        heaviest = w;
        out.winner_id = static_cast<InputId>(i);
      }
    }
    if (total > 0.0) {
      fused.vx_m_s /= total;
      fused.vy_m_s /= total;
      fused.wz_rad_s /= total;
      out.winner = "weighted_sum";
    }
  }
  out.all_expired = out.live_inputs == 0;
  if (out.all_expired) fused = Twist2D{};

  out.requested = fused;

  // Safety override: intersect the envelopes of the live safety inputs, clamp into it.
  VelocityEnvelope env;
  bool any_safety = false;
  std::string_view first_limiter;
  for (const InputState& s : inputs_) {
    if (s.config.role != InputRole::safety || !usable(s)) continue;
    VelocityEnvelope e;
    if (s.has_envelope) {
      e = s.envelope;
    } else {
      e.vx_lo_m_s = std::min(0.0, s.command.vx_m_s);
      e.vx_hi_m_s = std::max(0.0, s.command.vx_m_s);
      e.vy_lo_m_s = std::min(0.0, s.command.vy_m_s);
      e.vy_hi_m_s = std::max(0.0, s.command.vy_m_s);
      e.wz_lo_rad_s = std::min(0.0, s.command.wz_rad_s);
      e.wz_hi_rad_s = std::max(0.0, s.command.wz_rad_s);
    }
    env.vx_lo_m_s = std::max(env.vx_lo_m_s, e.vx_lo_m_s);
    env.vx_hi_m_s = std::min(env.vx_hi_m_s, e.vx_hi_m_s);
    env.vy_lo_m_s = std::max(env.vy_lo_m_s, e.vy_lo_m_s);
    env.vy_hi_m_s = std::min(env.vy_hi_m_s, e.vy_hi_m_s);
    env.wz_lo_rad_s = std::max(env.wz_lo_rad_s, e.wz_lo_rad_s);
    env.wz_hi_rad_s = std::min(env.wz_hi_rad_s, e.wz_hi_rad_s);
    if (!any_safety) first_limiter = s.config.name;
    any_safety = true;
  }
  if (any_safety) {
    const Twist2D before = fused;
    fused.vx_m_s = clamp_axis(fused.vx_m_s, env.vx_lo_m_s, env.vx_hi_m_s);
    fused.vy_m_s = clamp_axis(fused.vy_m_s, env.vy_lo_m_s, env.vy_hi_m_s);
    fused.wz_rad_s = clamp_axis(fused.wz_rad_s, env.wz_lo_rad_s, env.wz_hi_rad_s);
    if (!(fused == before)) {
      out.safety_limited = true;
      out.limited_by = first_limiter;
    }
  }
  out.command = fused;
  output_ = out;
  for (std::size_t c = 0; c < channels_.size(); ++c) fuse_channel(static_cast<ChannelId>(c), now, masking, mask_priority);
  return output_;
}

void CBehaviorCoordinator::fuse_channel(ChannelId id, Time now, bool masking, int mask_priority) noexcept {
  ChannelState& ch = channels_[id];
  const ChannelSpec& spec = ch.spec;
  auto usable = [&](const InputState& s) noexcept {
    const ChannelWriteState& w = s.channels[id];
    if (!w.has || expired(now, w.stamp, s.config.timeout) || expired(now, w.stamp, spec.timeout)) return false;
    return !(masking && s.config.priority <= mask_priority);
  };
  ChannelOutput out;
  const bool weighted = mode_ == CoordinationMode::weighted_sum && is_numeric(spec.type);
  const InputState* best = nullptr;
  double total = 0.0, sum = 0.0;
  for (const InputState& s : inputs_) {
    if (s.config.role != InputRole::normal || !usable(s)) continue;
    if (weighted) {
      if (s.config.weight <= 0.0) continue;
      total += s.config.weight;
      sum += s.config.weight * s.channels[id].value.number;
    } else if (best == nullptr || s.config.priority > best->config.priority) {
      best = &s;  // strictly greater: ties go to the earlier input, as for motion
    }
  }
  if (weighted && total > 0.0) {
    out.value = ChannelValue::of(sum / total);
    out.writer = "weighted_sum";
    out.live = true;
  } else if (!weighted && best != nullptr) {
    out.value = best->channels[id].value;
    out.writer = best->config.name;
    out.live = true;
  }
  for (const InputState& s : inputs_) {
    if (s.config.role != InputRole::safety || !usable(s)) continue;
    out.safety_override = !out.live || !(out.value == s.channels[id].value);
    out.value = s.channels[id].value;
    out.writer = s.config.name;
    out.live = true;
    break;
  }
  if (!out.live) out.value = spec.hold ? ch.output.value : spec.safe;
  if (is_numeric(spec.type) && spec.min < spec.max) out.value.number = std::clamp(out.value.number, spec.min, spec.max);
  ch.output = out;
}

}  // namespace tripodal
