#include "tripodal/reactive/control_loop.hpp"

#include <algorithm>
#include <stdexcept>

namespace tripodal {

std::string LoopEvent::event_name() const {
  switch (kind) {
    case Kind::behavior_succeeded: return done_event_name(behavior);
    case Kind::behavior_failed: return failed_event_name(behavior);
    case Kind::controller_fault: return std::string(loop) + ".controller_fault";
    case Kind::controller_recovered: return std::string(loop) + ".controller_recovered";
    case Kind::behavior_signal:
      return std::string(reason);
  }
  return {};
}

ControlLoop::ControlLoop(ControlLoopOptions options, ResourceTable& resources, CBehaviorCoordinator coordinator,
                         std::unique_ptr<CController> controller)
    : options_(std::move(options)),
      resources_(resources),
      coordinator_(std::move(coordinator)),
      controller_(std::move(controller)) {
  if (options_.period.count() <= 0) throw std::invalid_argument("control loop '" + options_.name + "': period must be > 0");
  if (options_.max_behaviors == 0) throw std::invalid_argument("control loop '" + options_.name + "': max_behaviors must be > 0");
  if (controller_) base_ = controller_->capabilities();
  const std::size_t n = options_.max_behaviors;
  slots_.resize(n);
  path_.reserve(options_.max_path_points);
  local_events_.resize(std::max<std::size_t>(options_.event_capacity, 1));
  // Everything the loop thread touches while holding the mutex is sized here, so applying
  // changes never allocates on the loop's side.
  pending_activations_.reserve(2 * n);
  pending_deactivations_.reserve(2 * n);
  pending_locks_.reserve(64);
  retired_.reserve(4 * n);
  events_out_.reserve(local_events_.size());
  path_shared_.reserve(options_.max_path_points);
  slot_generation_.assign(n, 0);
  slot_input_.assign(n, 0);
  slot_used_.assign(n, 0);
  slot_status_.assign(n, BehaviorStatus::idle);
}

ControlLoop::~ControlLoop() = default;

BehaviorHandle ControlLoop::activate(std::unique_ptr<CBehavior> behavior, const ParameterValues& params,
                                     std::string_view input, const SourceLocation& where) {
  if (!behavior) throw std::invalid_argument("control loop '" + options_.name + "': null behavior");
  const std::string_view input_name = input.empty() ? behavior->name() : input;
  const std::optional<InputId> id = coordinator_.find_input(input_name);
  if (!id) {
    throw std::invalid_argument("control loop '" + options_.name + "': the coordinator has no input named '" +
                                std::string(input_name) + "' for " + std::string(behavior->name()));
  }
  std::lock_guard lock(mutex_);
  retired_.clear();  // destroyed here, on the supervisor's thread, not in a cycle
  BehaviorContext context;
  context.now = time_from_ns(last_now_.load(std::memory_order_acquire));
  context.period = options_.period;
  context.resources = &resources_;
  context.navi = &navi_shared_;
  context.base = base_;
  behavior->activate(params, context, where);
  const ChannelBinding channels = bind_channels(*behavior, where);

  // One behavior per input: the previous one on this input leaves in the same batch.
  for (std::uint32_t s = 0; s < slot_used_.size(); ++s) {
    if (slot_used_[s] && slot_input_[s] == *id) deactivate_locked(BehaviorHandle{s, slot_generation_[s]});
  }
  std::uint32_t slot = 0;
  while (slot < slot_used_.size() && slot_used_[slot]) ++slot;
  if (slot == slot_used_.size()) {
    throw std::invalid_argument("control loop '" + options_.name + "': all " + std::to_string(slot_used_.size()) +
                                " behavior slots are in use");
  }
  const std::uint32_t generation = ++slot_generation_[slot];
  slot_used_[slot] = 1;
  slot_input_[slot] = *id;
  slot_status_[slot] = behavior->status();
  pending_activations_.push_back({std::move(behavior), *id, slot, generation, channels});
  return {slot, generation};
}

ControlLoop::ChannelBinding ControlLoop::bind_channels(const CBehavior& behavior, const SourceLocation& where) const {
  ChannelBinding b;
  const std::vector<ChannelWrite>& writes = behavior.manifest().writes;
  for (std::size_t i = 0; i < writes.size() && i < kMaxBehaviorChannels; ++i) {
    const std::string_view name = behavior.channel_name(i);
    const std::optional<ChannelId> id = coordinator_.find_channel(name);
    if (!id) {
      throw ConfigError(where, "behavior " + std::string(behavior.name()) + " writes the command channel '" + std::string(name) +
                                   "', which the hardware does not export (" + exported_channels() + ")");
    }
    if (coordinator_.channel_spec(*id).type != writes[i].type) {
      throw ConfigError(where, "behavior " + std::string(behavior.name()) + " writes the command channel '" + std::string(name) +
                                   "' as " + std::string(to_string(writes[i].type)) + ", and the hardware exports it as " +
                                   std::string(to_string(coordinator_.channel_spec(*id).type)));
    }
    b.ids[i] = *id;
    ++b.count;
  }
  return b;
}

std::string ControlLoop::exported_channels() const {
  if (coordinator_.channel_count() == 0) return "it exports none";
  std::string out = "it exports";
  for (ChannelId c = 0; c < coordinator_.channel_count(); ++c) {
    out += (c == 0 ? " " : ", ") + coordinator_.channel_spec(c).name + " (" +
           std::string(to_string(coordinator_.channel_spec(c).type)) + ")";
  }
  return out;
}

void ControlLoop::set_command_output(CommandChannels* channels) {
  if (channels != nullptr) {
    bool same = channels->size() == coordinator_.channel_count();
    for (ChannelId c = 0; same && c < coordinator_.channel_count(); ++c)
      same = channels->spec(c).name == coordinator_.channel_spec(c).name;
    if (!same) {
      throw std::invalid_argument("control loop '" + options_.name +
                                  "': the command output's channels are not the coordinator's, in its order");
    }
  }
  channels_out_ = channels;
}

bool ControlLoop::deactivate(BehaviorHandle handle) {
  std::lock_guard lock(mutex_);
  return deactivate_locked(handle);
}

bool ControlLoop::deactivate_locked(BehaviorHandle handle) {
  if (handle.slot >= slot_used_.size() || !slot_used_[handle.slot] || slot_generation_[handle.slot] != handle.generation) {
    return false;
  }
  slot_used_[handle.slot] = 0;
  slot_status_[handle.slot] = BehaviorStatus::idle;
  // Still waiting to join the loop: it never will.
  for (auto it = pending_activations_.begin(); it != pending_activations_.end(); ++it) {
    if (it->slot == handle.slot && it->generation == handle.generation) {
      retired_.push_back(std::move(it->behavior));
      pending_activations_.erase(it);
      return true;
    }
  }
  pending_deactivations_.push_back({handle.slot, handle.generation});
  return true;
}

bool ControlLoop::deactivate(std::string_view input) {
  const std::optional<InputId> id = coordinator_.find_input(input);
  if (!id) return false;
  std::lock_guard lock(mutex_);
  for (std::uint32_t s = 0; s < slot_used_.size(); ++s) {
    if (slot_used_[s] && slot_input_[s] == *id) return deactivate_locked(BehaviorHandle{s, slot_generation_[s]});
  }
  return false;
}

bool ControlLoop::set_navigation(const NavigationData& navi) {
  std::lock_guard lock(mutex_);
  const bool new_path = navi.path_id != navi_shared_.path_id || (navi.path_id == 0 && navi.path.size() != path_shared_.size());
  navi_shared_ = navi;
  bool complete = true;
  if (new_path) {
    const std::size_t n = std::min(navi.path.size(), options_.max_path_points);
    path_shared_.assign(navi.path.begin(), navi.path.begin() + static_cast<std::ptrdiff_t>(n));
    complete = n == navi.path.size();
    path_dirty_ = true;
  }
  navi_shared_.path = path_shared_;
  navi_dirty_ = true;
  return complete;
}

NavigationFeedback ControlLoop::navigation_feedback() const {
  std::lock_guard lock(mutex_);
  return feedback_shared_;
}

void ControlLoop::hold_changes() {
  std::lock_guard lock(mutex_);
  ++holding_;
}

void ControlLoop::release_changes() {
  std::lock_guard lock(mutex_);
  if (holding_ > 0) --holding_;
}

void ControlLoop::set_lock(std::string_view lock_name, bool engaged, Time stamp) {
  const std::optional<LockId> id = coordinator_.find_lock(lock_name);
  if (!id) throw std::invalid_argument("control loop '" + options_.name + "': no coordinator lock named '" + std::string(lock_name) + "'");
  std::lock_guard lock(mutex_);
  pending_locks_.push_back({*id, engaged, stamp});
}

void ControlLoop::collect_events(std::vector<LoopEvent>& out) {
  std::lock_guard lock(mutex_);
  out.insert(out.end(), events_out_.begin(), events_out_.end());
  events_out_.clear();
  retired_.clear();
}

std::optional<BehaviorStatus> ControlLoop::status(BehaviorHandle handle) const {
  std::lock_guard lock(mutex_);
  if (handle.slot >= slot_generation_.size() || slot_generation_[handle.slot] != handle.generation) return std::nullopt;
  return slot_status_[handle.slot];
}

void ControlLoop::retire(Slot& slot) noexcept {
  coordinator_.withdraw(slot.input);
  coordinator_.withdraw_channels(slot.input);
  if (slot.behavior) {
    slot.behavior->deactivate();
    // Handed to the supervisor's side for destruction; if that buffer is full (the supervisor
    // has not called in for a long time) it is destroyed here.
    if (retired_.size() < retired_.capacity()) retired_.push_back(std::move(slot.behavior));
    slot.behavior.reset();
  }
  slot.active = false;
  slot.last_status = BehaviorStatus::idle;
}

void ControlLoop::push_event(const LoopEvent& event) noexcept {
  const std::size_t cap = local_events_.size();
  local_events_[(local_head_ + local_count_) % cap] = event;
  if (local_count_ < cap) {
    ++local_count_;
  } else {
    local_head_ = (local_head_ + 1) % cap;  // full: the oldest is dropped
  }
}

void ControlLoop::apply_pending() noexcept {
  // A report that a path was followed to its end stays until the next report: the behavior that
  // made it has finished and reports no more, and the sequencing layer, slower than this loop,
  // must not miss it (the coverage planner records a section as finished from it).
  if (feedback_.path_id != 0 || !feedback_shared_.reached_end) feedback_shared_ = feedback_;
  if (holding_ > 0) {
    deferred_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  for (const PendingDeactivation& d : pending_deactivations_) {
    Slot& slot = slots_[d.slot];
    if (slot.active && slot.generation == d.generation) retire(slot);
  }
  pending_deactivations_.clear();
  for (PendingActivation& a : pending_activations_) {
    Slot& slot = slots_[a.slot];
    if (slot.active) retire(slot);
    slot.behavior = std::move(a.behavior);
    slot.input = a.input;
    slot.channels = a.channels;
    slot.generation = a.generation;
    slot.active = true;
    slot.last_status = BehaviorStatus::running;
  }
  pending_activations_.clear();
  for (const PendingLock& l : pending_locks_) coordinator_.set_lock(l.lock, l.engaged, l.stamp);
  pending_locks_.clear();
  if (navi_dirty_) {
    navi_ = navi_shared_;
    if (path_dirty_) path_.assign(path_shared_.begin(), path_shared_.end());  // within the reserved capacity
    navi_.path = path_;
    navi_dirty_ = path_dirty_ = false;
  }
  // Hand events over; the supervisor's buffer has the ring's capacity.
  const std::size_t cap = local_events_.size();
  while (local_count_ > 0 && events_out_.size() < events_out_.capacity()) {
    events_out_.push_back(local_events_[local_head_]);
    local_head_ = (local_head_ + 1) % cap;
    --local_count_;
  }
  for (std::uint32_t s = 0; s < slots_.size(); ++s) {
    const Slot& slot = slots_[s];
    if (slot.active && slot_generation_[s] == slot.generation) slot_status_[s] = slot.last_status;
  }
}

const CycleReport& ControlLoop::step(Time now) noexcept {
  if (mutex_.try_lock()) {
    apply_pending();
    mutex_.unlock();
  } else {
    deferred_.fetch_add(1, std::memory_order_relaxed);
  }
  last_now_.store(to_ns(now), std::memory_order_release);
  resources_.poll_all(now);

  BehaviorContext context;
  context.now = now;
  context.period = options_.period;
  context.resources = &resources_;
  context.navi = &navi_;
  context.base = base_;
  feedback_ = NavigationFeedback{};
  context.feedback = &feedback_;
  // The previous cycle's fusion (report_ still holds it): what the safety override did to the
  // winner's command goes to the winner alone, so a behavior learns that it is held still.
  const CoordinatorOutput& last = report_.coordinator;
  safety_.limited = last.safety_limited;
  safety_.requested = last.requested;
  safety_.allowed = last.command;
  safety_.limited_by = last.limited_by;

  std::uint32_t active = 0;
  for (Slot& slot : slots_) {
    if (!slot.active) continue;
    CBehavior& b = *slot.behavior;
    context.safety = last.winner_id && *last.winner_id == slot.input ? &safety_ : nullptr;
    const std::optional<Twist2D> command = b.step(context);
    if (const std::string_view signal = b.take_signal(); !signal.empty()) {
      LoopEvent e;
      e.kind = LoopEvent::Kind::behavior_signal;
      e.stamp = now;
      e.handle = {static_cast<std::uint32_t>(&slot - slots_.data()), slot.generation};
      e.behavior = b.name();
      e.input = coordinator_.input_config(slot.input).name;
      e.reason = signal;
      e.loop = options_.name;
      push_event(e);
    }
    if (b.envelope()) {
      coordinator_.submit_envelope(slot.input, *b.envelope(), now);
    } else if (command) {
      coordinator_.submit(slot.input, *command, now);
    } else {
      coordinator_.withdraw(slot.input);
    }
    for (std::uint8_t i = 0; i < slot.channels.count; ++i) {
      if (const std::optional<ChannelValue>& w = b.channel_write(i)) {
        coordinator_.submit_channel(slot.input, slot.channels.ids[i], *w, now);
      } else {
        coordinator_.withdraw_channel(slot.input, slot.channels.ids[i]);
      }
    }
    const BehaviorStatus status = b.status();
    if (status != slot.last_status) {
      if (status == BehaviorStatus::succeeded || status == BehaviorStatus::failed) {
        LoopEvent e;
        e.kind = status == BehaviorStatus::succeeded ? LoopEvent::Kind::behavior_succeeded : LoopEvent::Kind::behavior_failed;
        e.stamp = now;
        e.handle = {static_cast<std::uint32_t>(&slot - slots_.data()), slot.generation};
        e.behavior = b.name();
        e.input = coordinator_.input_config(slot.input).name;
        e.reason = b.failure_reason();
        e.loop = options_.name;
        push_event(e);
      }
      slot.last_status = status;
    }
    if (status == BehaviorStatus::running) ++active;
  }

  report_.now = now;
  report_.active_behaviors = active;
  report_.coordinator = coordinator_.update(now);
  if (channels_out_ != nullptr) {
    for (ChannelId c = 0; c < coordinator_.channel_count(); ++c) channels_out_->set(c, coordinator_.channel_output(c).value);
  }
  if (controller_) {
    controller_->set_command(report_.coordinator.command, now);
    report_.controller_status = controller_->update(now);
    const bool fault = report_.controller_status == ControlStatus::hardware_fault;
    if (fault != controller_faulted_) {
      LoopEvent e;
      e.kind = fault ? LoopEvent::Kind::controller_fault : LoopEvent::Kind::controller_recovered;
      e.stamp = now;
      e.loop = options_.name;
      push_event(e);
      controller_faulted_ = fault;
    }
    if (odometry_out_ != nullptr) odometry_out_->publish(controller_->odometry());
  }
  cycles_.fetch_add(1, std::memory_order_relaxed);
  return report_;
}

}  // namespace tripodal
