#include "tripodal/behaviors/teleop.hpp"

namespace tripodal {

const ModuleManifest& TeleopResource::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("TeleopResource", ModuleKind::resource)
                                      .description("the operator's drive command, set by an operator console")
                                      .output("teleop")
                                      .build();
  return m;
}

void TeleopResource::set(bool engaged, const Twist2D& command, Time stamp) {
  std::lock_guard lock(mutex_);
  pending_ = TeleopReading{stamp, engaged, command};
  dirty_ = true;
}

void TeleopResource::on_poll(Time /*now*/) noexcept {
  // Never waits: a set() in progress is taken at the next cycle.
  std::unique_lock lock(mutex_, std::try_to_lock);
  if (!lock.owns_lock() || !dirty_) return;
  dirty_ = false;
  edit() = pending_;
  commit();
}

const ModuleManifest& BhTeleop::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("BhTeleop", ModuleKind::behavior)
                                      .description("the velocity an operator gives by hand (the monitor's console), body frame")
                                      .input("teleop")
                                      .output("behavior_command")
                                      .text("input", std::string(kTeleopResource), "the TeleopResource to follow")
                                      .build();
  return m;
}

void BhTeleop::on_activate(const ParameterSet& params, const BehaviorContext& context) {
  input_ = context.resources != nullptr ? context.resources->find<TeleopReading>(params.string("input")) : nullptr;
  if (input_ == nullptr) fail("no teleop input");
}

std::optional<Twist2D> BhTeleop::on_step(const BehaviorContext& /*context*/) noexcept {
  const TeleopReading& r = input_->latest();
  if (!r.engaged) return std::nullopt;
  return r.command;
}

void register_teleop_behavior(BehaviorRegistry& registry) {
  registry.add<BhTeleop>();
}

}  // namespace tripodal
