// Driving by hand as an ordinary input of the behavior coordinator: BhTeleop is a behavior like any
// other, bound to the coordinator input "operator" the robot configures at assembly, and its input
// is a resource (TeleopResource) an operator console (the monitor) sets from its own thread. While
// the operator drives, the lock "operator" masks the task's behaviors; the safety inputs stay.
#pragma once

#include <mutex>
#include <string>
#include <string_view>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"

namespace tripodal {

/// The coordinator input, lock and resource names of driving by hand.
inline constexpr std::string_view kTeleopInput = "operator";
inline constexpr std::string_view kTeleopResource = "teleop";

/// What the operator asks for.
struct TeleopReading {
  Time stamp{};
  bool engaged = false;  ///< driving by hand; false: BhTeleop gives no command
  Twist2D command;       ///< body frame
  friend bool operator==(const TeleopReading&, const TeleopReading&) = default;
};

/// The operator's command as a resource (output information "teleop"). set() may be called from
/// any thread; the reactive loop takes the latest at the start of its cycle (poll).
class TeleopResource final : public TypedResource<TeleopReading> {
 public:
  static const ModuleManifest& static_manifest();
  explicit TeleopResource(std::string name = std::string(kTeleopResource))
      : TypedResource<TeleopReading>(std::move(name), Duration{0}, static_manifest()) {}
  /// Drive at `command` (engaged) or stop driving by hand (not engaged), from `stamp` on.
  void set(bool engaged, const Twist2D& command, Time stamp);

 protected:
  void on_poll(Time now) noexcept override;

 private:
  std::mutex mutex_;
  TeleopReading pending_;
  bool dirty_ = false;
};

/// The velocity the operator gives, while the resource named by `input` is engaged; nothing
/// otherwise. Never finishes; the robot runs it from its start on the input "operator".
class BhTeleop final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const TypedResource<TeleopReading>* input_ = nullptr;
};

/// Registers BhTeleop.
void register_teleop_behavior(BehaviorRegistry& registry);

}  // namespace tripodal
