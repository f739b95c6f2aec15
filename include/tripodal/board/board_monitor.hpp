// BoardMonitor: the sequencing-loop module that turns what the control board's link and panel
// report into process-supervisor events (seed 001, section 3.3: link monitoring; section 2.5: the
// buttons). Each sequencing period it reads the resource "board_link" (BoardLinkReading: on the
// robot's own threads, the snapshot the reactive loop's thread hands over, never the link itself)
// and posts
//   board.link_lost       the host missed a response (missing, late or corrupt): a fault, whose
//                         message is "link lost" (a recovery rule matches it: the details are the
//                         event's message); with link_grace_s > 0, only when the link is still lost
//                         that long after the loss (a blip shorter than that is no fault)
//   board.link_restored   SYNC answered again after a loss
//   board.link_blip       SYNC answered again within link_grace_s: the task goes on (the board's
//                         watchdog held the motors meanwhile); not a fault
//   board.start / board.pause / board.home   a panel button pressed (held edge)
//   board.emergency_stop  the e-stop pressed: the board has already braked; a fault
//   board.tank_empty / board.tank_refilled   the liquid level module's empty flag changed
//   board.battery_low     the battery at or below battery_low_percent (and not charging); again
//                         every 3 s while it stays low
// and keeps the fact `board_linked` (the link synchronised) for the nets' guards (PrBoardReconnect
// waits on it). Start pressed with no task running asks the planner for the task the parameter
// start_task names (the robot waiting at its dock starts its round), or logs that none is named.
// It only reads: the actuators are command channels the behaviors write (actuator_behaviors.hpp).
// A fault is also reported as the module's failure ("<module>.fault"), so every running process
// fails unless its net takes the event, and the planner's recovery rules decide.
#pragma once

#include <cstdint>
#include <string>

#include "tripodal/board/board_hardware.hpp"
#include "tripodal/processes/module.hpp"

namespace tripodal::board {

class BoardMonitor final : public CModule {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  /// Throws ConfigError when the robot's hardware is not a board.
  void on_start(ModuleContext& context) override;
  /// Throws std::runtime_error (the module's fault) on a link loss or an emergency stop.
  void on_update(ModuleContext& context) override;
  void on_configure(const ParameterSet& params) override;

 private:
  void start_pressed(ModuleContext& context) const;

  bool started_ = false;
  bool link_up_ = false;
  std::uint64_t losses_seen_ = 0;
  // A loss not yet a fault: within link_grace_ of lost_at_ (link_grace_ > 0).
  bool pending_loss_ = false;
  Time lost_at_{};
  Duration link_grace_{0};
  std::uint8_t held_ = 0;
  bool tank_empty_ = false;
  bool battery_low_ = false;
  Time next_low_post_{};
  double battery_low_percent_ = 15.0;
  std::string start_task_;
  static constexpr Duration kBatteryLowRepeat{std::chrono::seconds(3)};
};

/// Registers the module type "BoardMonitor".
void register_board_modules(ModuleRegistry& registry);

}  // namespace tripodal::board
