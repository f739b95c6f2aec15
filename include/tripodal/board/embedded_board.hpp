// The simulated control board wired in process to the host side: BoardFirmware and BoardHardware
// joined by a SerialLine, in simulated time. What a simulated robot of hardware type "board"
// embeds (sim/sim_board.hpp gives it the simulator's world): every request and response crosses
// the line byte for byte, at the line's character time; over a real pseudo-terminal when asked
// (the host's end a SerialPort on the slave device, exactly as on the robot).
#pragma once

#include <cstdint>
#include <memory>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/board_hardware.hpp"
#include "tripodal/board/serial_line.hpp"
#include "tripodal/core/clock.hpp"

namespace tripodal::board {

/// What carries the bytes between the two sides.
enum class BoardLine {
  in_process,       ///< the simulated line alone (SerialLine)
  pseudo_terminal,  ///< the simulated line's timing, the bytes through a kernel pseudo-terminal
};

class EmbeddedBoard {
 public:
  /// `plant` is the board's world (not owned); power-on at time zero. With a pseudo-terminal,
  /// throws std::runtime_error when none can be opened.
  EmbeddedBoard(const FirmwareConfig& firmware, BoardPlant& plant, const BoardHardwareConfig& host,
                std::uint32_t baud = 115200, BoardLine carrier = BoardLine::in_process);
  EmbeddedBoard(const EmbeddedBoard&) = delete;
  EmbeddedBoard& operator=(const EmbeddedBoard&) = delete;

  /// Runs the firmware's 1 ms ticks up to `now`, the line's time moving with each tick: the robot
  /// only stops at its loops' instants, but a request sent at one control period must be answered
  /// (bytes travelling at 115200 baud) before the next, as on the real line.
  void advance_to(Time now) noexcept;

  [[nodiscard]] BoardFirmware& firmware() noexcept { return firmware_; }
  [[nodiscard]] BoardHardware& host() noexcept { return host_; }
  [[nodiscard]] SerialLine& line() noexcept { return line_; }
  /// The pseudo-terminal's slave device the host side opened (empty in process).
  [[nodiscard]] std::filesystem::path device() const;
  /// The host's port on that device (nullptr in process): the one the link reopens.
  [[nodiscard]] SerialPort* port() noexcept { return port_.get(); }

 private:
  SimClock clock_;  // the line's: moves tick by tick up to the robot's clock
  Duration tick_;
  SteadyClock real_clock_;               // bounds the waits on the pseudo-terminal
  std::unique_ptr<PseudoTerminal> pty_;  // the board's side of the carrier
  std::unique_ptr<SerialPort> port_;     // the host's side: the slave device, opened as on the robot
  SerialLine line_;
  BoardFirmware firmware_;
  BoardHardware host_;
};

}  // namespace tripodal::board
