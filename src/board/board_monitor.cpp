#include "tripodal/board/board_monitor.hpp"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <stdexcept>
#include <string>

namespace tripodal::board {

const ModuleManifest& BoardMonitor::static_manifest() {
  static const ModuleManifest m =
      ManifestBuilder("BoardMonitor", ModuleKind::other, Layer::sequencing)
          .description("the control board's link and panel as supervisor events (docs/board-protocol.md)")
          .input("board_link")
          .outputs({"board_linked", "board.link_lost", "board.link_restored", "board.link_blip", "board.start", "board.pause",
                    "board.home", "board.emergency_stop", "board.tank_empty", "board.tank_refilled", "board.battery_low"})
          .number("battery_low_percent", 15.0, "%", "at or below this the task must end and the robot charge", 0.0, 100.0)
          // A host without real-time scheduling (a desktop, a shared machine) is now and then not
          // scheduled for longer than the board's watchdog (200 ms): the board stops the motors and
          // the host resynchronises at its next cycle. Such a blip is not worth failing the task for.
          .number("link_grace_s", 0.0, "s",
                  "a lost link answering SYNC again within this is a blip (board.link_blip), not a fault; 0: every "
                  "loss is a fault at once (a real-time host)",
                  0.0, 60.0)
          .text("start_task", std::string(),
                "the task the start button starts when none runs, in plain words (\"disinfect the room 2111\"); "
                "empty: the button only resumes a paused task")
          .build();
  return m;
}

void BoardMonitor::on_start(ModuleContext& context) {
  if (dynamic_cast<BoardHost*>(context.hardware) == nullptr) {
    const std::string type = context.hardware != nullptr ? std::string(context.hardware->manifest().name) : "none";
    throw ConfigError(where(), fmt::format("module BoardMonitor reads the control board; expected hardware of type "
                                           "'board' (hardware: {{type: board}}), this robot's is '{}'",
                                           type));
  }
  started_ = true;
  link_up_ = false;
  losses_seen_ = 0;
  pending_loss_ = false;
}

void BoardMonitor::on_configure(const ParameterSet& params) {
  battery_low_percent_ = params.number("battery_low_percent");
  link_grace_ = from_seconds(params.number("link_grace_s"));
  start_task_ = params.string("start_task");
}

// With a task running the button is the nets' (PrDisinfection resumes on board.start); at rest it
// starts the profile's task, as an operator at the dock expects of the robot's one start button.
void BoardMonitor::start_pressed(ModuleContext& context) const {
  if (context.task_running) return;
  if (start_task_.empty()) {
    spdlog::warn(
        "{}: start button pressed, no task running and none to start: BoardMonitor's parameter start_task "
        "names none (e.g. start_task: \"disinfect the room 2111\")",
        where().str());
    return;
  }
  spdlog::info("start button pressed, no task running: \"{}\" (BoardMonitor's start_task)", start_task_);
  context.command(start_task_);
}

void BoardMonitor::on_update(ModuleContext& context) {
  if (!started_ || context.resources == nullptr) return;
  const TypedResource<BoardLinkReading>* resource = context.resources->find<BoardLinkReading>("board_link");
  if (resource == nullptr || !resource->has_reading()) return;
  const BoardLinkReading& link = resource->latest();
  std::string fault;
  const auto lost = [&](Time at) {
    context.post("board.link_lost",
                 fmt::format("link lost at {:.3f} s: no valid response from the board ({} missed, {} error responses so far)",
                             to_seconds(at), link.stats.missed, link.stats.error_responses));
    fault = "link lost";
  };
  if (link.stats.link_losses > losses_seen_) {
    // Counted, not taken: the snapshot may skip a period, never a loss.
    losses_seen_ = link.stats.link_losses;
    context.set_fact("board_linked", Value{false});
    link_up_ = false;
    if (link_grace_.count() > 0 && !pending_loss_) {
      pending_loss_ = true;  // a fault only if SYNC is not answered again within the grace
      lost_at_ = link.lost_at;
    } else if (link_grace_.count() == 0) {
      lost(link.lost_at);
    }
  } else if (!link_up_ && link.synchronised) {
    if (pending_loss_) {
      context.post("board.link_blip",
                   fmt::format("link lost at {:.3f} s and SYNC answered again {:.0f} ms later: the task goes on",
                               to_seconds(lost_at_), to_seconds(link.stamp - lost_at_) * 1000.0));
      pending_loss_ = false;
    } else if (link.stats.link_losses > 0) {
      context.post("board.link_restored", "SYNC answered again");
    }
    context.set_fact("board_linked", Value{true});
    link_up_ = true;
  }
  if (pending_loss_ && context.now - lost_at_ >= link_grace_) {
    pending_loss_ = false;
    lost(lost_at_);
  }
  // Buttons from the DRIVE response of every control period: a press is a held edge.
  const std::uint8_t held = link.synchronised && link.has_drive ? link.buttons : held_;
  const auto pressed = static_cast<std::uint8_t>(held & ~held_);
  held_ = held;
  if ((pressed & kButtonStart) != 0) {
    context.post("board.start", "start button");
    start_pressed(context);
  }
  if ((pressed & kButtonPause) != 0) context.post("board.pause", "pause button");
  if ((pressed & kButtonHome) != 0) context.post("board.home", "home button");
  if ((pressed & kButtonEmergencyStop) != 0) {
    context.post("board.emergency_stop", "emergency stop pressed");
    if (fault.empty()) fault = "emergency stop pressed: the board braked the wheels";
  }
  if (link.tank_empty != tank_empty_) {
    tank_empty_ = link.tank_empty;
    context.post(tank_empty_ ? "board.tank_empty" : "board.tank_refilled",
                 fmt::format("disinfectant tank at {} %", link.tank_percent));
  }
  if (link.has_battery) {
    const BatteryState& b = link.battery;
    const bool low = !b.charging && b.percent <= battery_low_percent_;
    // Posted again every battery period (3 s) while low: a process that starts after the edge
    // (the disinfection of the next section after a drive) hears it too and ends for the charge.
    if (low && (!battery_low_ || context.now >= next_low_post_)) {
      context.post("board.battery_low", fmt::format("battery at {} % ({} mV)", b.percent, b.voltage_mv));
      next_low_post_ = context.now + kBatteryLowRepeat;
    }
    battery_low_ = low;
  }
  if (!fault.empty()) throw std::runtime_error(fault);
}

void register_board_modules(ModuleRegistry& registry) { registry.add<BoardMonitor>(); }

}  // namespace tripodal::board
