// The disinfection robot's actuators as behaviors a process net marks (seed 001, sections 2.5 and
// 3.4): the UV lamp, the atomizer (dry fog) and the voice prompt. They do not drive the base (a
// step gives no command); BoardMonitor (board_monitor.hpp), which sees the supervisor's
// activations in the sequencing loop, sends their board commands: on at activation, off at
// deactivation, so a process that ends or faults always switches them off.
#pragma once

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"

namespace tripodal::board {

/// What the actuator behaviors share: no command for the base; BoardMonitor acts on activation.
class CActuatorBehavior : public CBehavior {
 protected:
  void on_activate(const ParameterSet& /*params*/, const BehaviorContext& /*context*/) override {}
  std::optional<Twist2D> on_step(const BehaviorContext& /*context*/) noexcept override { return std::nullopt; }
};

/// The UV lamp on while active; never finishes.
class BhUvLamp final : public CActuatorBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
};

/// The atomizer (and its fan: parameter fan) on while active; never finishes. The board stops it
/// when the tank runs dry (BoardMonitor posts board.tank_empty).
class BhAtomize final : public CActuatorBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
};

/// Plays the WT2003S track `track` once; succeeds at its first step.
class BhVoicePrompt final : public CActuatorBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  std::optional<Twist2D> on_step(const BehaviorContext& /*context*/) noexcept override {
    succeed();
    return std::nullopt;
  }
};

/// The voice chip's tracks the disinfection task plays.
inline constexpr double kTrackAddDisinfectant = 3;

/// Registers BhUvLamp, BhAtomize and BhVoicePrompt.
void register_board_behaviors(BehaviorRegistry& registry);

}  // namespace tripodal::board
