// CBehaviorCoordinator: a core component of the reactive layer. Every sampling period it fuses the
// commands of the active behaviors into the one command the controller executes: priority
// arbitration (as ROS twist_mux, with locks as dead-man switches) or weighted-sum fusion (motor
// schemas), both under a safety override taking the most restrictive command. The same rules fuse
// each command channel the hardware exports (core/command_channel.hpp): the lamp, a joint, the LCD.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal {

enum class CoordinationMode : std::uint8_t {
  priority,      ///< the live, unmasked input of highest priority wins alone
  weighted_sum,  ///< live, unmasked inputs are averaged with their weights (motor schemas)
};
[[nodiscard]] std::string_view to_string(CoordinationMode mode) noexcept;

enum class InputRole : std::uint8_t {
  normal,  ///< takes part in arbitration or fusion
  safety,  ///< never wins; restricts the fused command (see CBehaviorCoordinator)
};

struct CoordinatorInputConfig {
  std::string name;        ///< usually the behavior's name, e.g. "BhGoToPose"
  int priority = 0;        ///< higher wins (priority mode); compared with lock priorities
  Duration timeout{0};     ///< a command older than this is ignored; 0 = never expires
  double weight = 1.0;     ///< weighted_sum mode; >= 0
  InputRole role = InputRole::normal;
};

/// A lock masks every input of priority <= its priority while engaged. A lock is engaged when
/// its latest message said so, or (dead-man switch) when its timeout > 0 and no message arrived
/// within the timeout, including before the first message.
struct CoordinatorLockConfig {
  std::string name;
  int priority = 0;
  Duration timeout{0};  ///< 0 = engaged only by an explicit message
};

struct CoordinatorConfig {
  CoordinationMode mode = CoordinationMode::priority;
  std::vector<CoordinatorInputConfig> inputs;
  std::vector<CoordinatorLockConfig> locks;
  std::vector<ChannelSpec> channels;  ///< the command channels the hardware exports
};

using InputId = std::uint32_t;
using LockId = std::uint32_t;
using ChannelId = std::uint32_t;

/// A command channel after update().
struct ChannelOutput {
  ChannelValue value;            ///< what the hardware is to apply
  std::string_view writer;       ///< the winning input; "weighted_sum"; "" when no live input wrote it
  bool live = false;             ///< a live, unmasked input wrote it (else: the safe or held value)
  bool safety_override = false;  ///< a safety input's write replaced the winner's
};

/// What update() produced.
struct CoordinatorOutput {
  Time stamp{};
  Twist2D command;               ///< explicit zero when nothing is live
  Twist2D requested;             ///< the fused command before the safety override
  std::string_view winner;       ///< priority: winning input; weighted: "weighted_sum"; "" if none
  std::optional<InputId> winner_id;
  bool all_expired = false;      ///< no normal input was live and unmasked: command is zero
  bool locked = false;           ///< at least one lock was engaged
  std::string_view lock;         ///< the engaged lock of highest priority
  bool safety_limited = false;   ///< a safety input changed the command
  std::string_view limited_by;   ///< when limited: the first live safety input (configuration order)
  std::uint32_t live_inputs = 0; ///< normal inputs live and unmasked this update
};

/// Fuses behavior commands. Configuration (constructor, add_input, add_lock) happens outside the
/// loop; submit(), withdraw(), set_lock() and update() are noexcept and allocate nothing.
/// Not thread-safe: the control loop's thread calls everything after configuration.
///
/// Rules, applied by update(now):
/// - An input is live when it has a command and (timeout == 0 or now - stamp <= timeout).
/// - Locks mask inputs whose priority <= the lock's priority (twist_mux semantics).
/// - priority mode: the live, unmasked normal input of highest priority wins; ties are broken by
///   configuration order (the earlier input wins), so the result never depends on timing.
/// - weighted_sum mode: sum(w_i * c_i) / sum(w_i) over live, unmasked normal inputs with w_i > 0;
///   the winner reported is "weighted_sum" (winner_id the input of largest weight).
/// - No live input: an explicit zero command, all_expired = true.
/// - Safety override: every live safety input (masked by locks like the others) contributes an
///   envelope (its behavior's VelocityEnvelope, or for a plain command c the envelope
///   [min(0,c), max(0,c)] per axis). The envelopes are intersected (most restrictive) and the
///   fused command is clamped into the intersection per axis; an empty intersection on an axis
///   gives 0 on that axis.
/// - Command channels, each on its own: a write is live when its input's timeout and the channel's
///   timeout both allow it; locks mask as above. Priority decides, or in weighted_sum mode the
///   weighted mean for numeric channels (is_numeric). A live safety input's write replaces the
///   result (an interlock: the lamp off while someone is near), the first in configuration order.
///   No live write: the channel's safe value, or its last value for a channel that holds.
///   Numeric results are clamped into the channel's [min, max].
class CBehaviorCoordinator final {
 public:
  explicit CBehaviorCoordinator(CoordinatorConfig config = {});

  /// Adds an input; throws std::invalid_argument for a duplicate name, negative weight or
  /// negative timeout.
  InputId add_input(CoordinatorInputConfig input);
  LockId add_lock(CoordinatorLockConfig lock);
  [[nodiscard]] std::optional<InputId> find_input(std::string_view name) const noexcept;
  [[nodiscard]] std::optional<LockId> find_lock(std::string_view name) const noexcept;
  [[nodiscard]] const CoordinatorInputConfig& input_config(InputId id) const noexcept;
  [[nodiscard]] std::size_t input_count() const noexcept { return inputs_.size(); }
  [[nodiscard]] CoordinationMode mode() const noexcept { return mode_; }
  void set_mode(CoordinationMode mode) noexcept { mode_ = mode; }

  /// Adds a command channel; throws std::invalid_argument for a duplicate or empty name.
  ChannelId add_channel(ChannelSpec spec);
  [[nodiscard]] std::optional<ChannelId> find_channel(std::string_view name) const noexcept;
  [[nodiscard]] const ChannelSpec& channel_spec(ChannelId id) const noexcept { return channels_[id].spec; }
  [[nodiscard]] std::size_t channel_count() const noexcept { return channels_.size(); }

  /// A new command from input `id`, stamped `stamp`.
  void submit(InputId id, const Twist2D& command, Time stamp) noexcept;
  /// A new envelope from safety input `id` (replaces a plain command for this input).
  void submit_envelope(InputId id, const VelocityEnvelope& envelope, Time stamp) noexcept;
  /// Input `id` has nothing to say any more (its behavior returned nothing or stopped).
  void withdraw(InputId id) noexcept;
  /// Input `id` writes `value` to channel `channel`, stamped `stamp`.
  void submit_channel(InputId id, ChannelId channel, const ChannelValue& value, Time stamp) noexcept;
  /// Input `id` no longer writes `channel` ...
  void withdraw_channel(InputId id, ChannelId channel) noexcept;
  /// ... or any channel.
  void withdraw_channels(InputId id) noexcept;
  /// A lock message: engaged or released, stamped `stamp` (refreshes the dead-man timer).
  void set_lock(LockId id, bool engaged, Time stamp) noexcept;

  /// Fuses at `now`; called once per sampling period (fixed rate) by the control loop.
  const CoordinatorOutput& update(Time now) noexcept;
  [[nodiscard]] const CoordinatorOutput& output() const noexcept { return output_; }
  /// Channel `id` as the last update() fused it (its safe value before the first).
  [[nodiscard]] const ChannelOutput& channel_output(ChannelId id) const noexcept { return channels_[id].output; }

  /// Forgets every submitted command and lock message (e.g. on loop restart).
  void reset() noexcept;

 private:
  struct ChannelWriteState {
    bool has = false;
    ChannelValue value;
    Time stamp{};
  };
  struct InputState {
    CoordinatorInputConfig config;
    std::vector<ChannelWriteState> channels;  // one per channel, by ChannelId
    bool has_command = false;
    bool has_envelope = false;
    Twist2D command;
    VelocityEnvelope envelope;
    Time stamp{};
  };
  struct LockState {
    CoordinatorLockConfig config;
    bool has_message = false;
    bool engaged = false;
    Time stamp{};
  };

  struct ChannelState {
    ChannelSpec spec;
    ChannelOutput output;
  };

  void fuse_channel(ChannelId id, Time now, bool masking, int mask_priority) noexcept;

  CoordinationMode mode_;
  std::vector<ChannelState> channels_;
  std::vector<InputState> inputs_;
  std::vector<LockState> locks_;
  CoordinatorOutput output_;
};

}  // namespace tripodal
