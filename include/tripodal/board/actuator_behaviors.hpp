// The disinfection robot's actuators as behaviors a process net marks (seed 001, sections 2.5 and
// 3.4): the UV lamp, the atomizer (dry fog), the voice prompt and the LCD. They do not drive the
// base (a step gives no command); each writes the board's command channels (board_hardware.hpp)
// while active, and the behavior coordinator fuses them like any command. When a process ends or
// faults its behaviors are withdrawn and the channels fall to their safe values: lamp and fog off.
#pragma once

#include <string>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"

namespace tripodal::board {

/// The UV lamp on (channel uv_lamp) while active; never finishes.
class BhUvLamp final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& /*params*/, const BehaviorContext& /*context*/) override {}
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;
};

/// The atomizer on (channel atomizer at 1) and its fan (channel atomizer_fan: parameter fan)
/// while active; never finishes. The board stops the fog when the tank runs dry (BoardMonitor
/// posts board.tank_empty).
class BhAtomize final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  bool fan_ = true;
};

/// Plays the WT2003S track `track` once (channel voice): writes it at its first step, succeeds at
/// the next, when the board has been given it.
class BhVoicePrompt final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  double track_ = 0.0;
};

/// Shows `text` on the LCD's first line (channel lcd) while active; never finishes.
class BhLcdText final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  ChannelValue text_;
};

/// The robot's state on the LCD's first line while active: `state` (a word the net gives, e.g.
/// DISINFECT, PAUSED), the battery's and the tank's levels from the board's resources, e.g.
/// "DISINFECT B 67% T 80%" ("--" for a level not read yet). Never finishes.
class BhLcdStatus final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  std::string state_;
};

/// The voice chip's tracks the disinfection task plays (the WT2003S's flash, in this order).
inline constexpr double kTrackStart = 1;
inline constexpr double kTrackStop = 2;
inline constexpr double kTrackAddDisinfectant = 3;
inline constexpr double kTrackBatteryLow = 4;

/// Registers BhUvLamp, BhAtomize, BhVoicePrompt, BhLcdText and BhLcdStatus.
void register_board_behaviors(BehaviorRegistry& registry);

}  // namespace tripodal::board
