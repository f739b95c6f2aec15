#include "tripodal/board/embedded_board.hpp"

#include <algorithm>

namespace tripodal::board {

namespace {
// Both ends speak the robot's profile: the firmware takes the host's unless given its own.
FirmwareConfig with_protocol(FirmwareConfig firmware, const BoardHardwareConfig& host) {
  if (!firmware.protocol) firmware.protocol = host.link.protocol;
  return firmware;
}

std::unique_ptr<PseudoTerminal> open_carrier(BoardLine carrier, const Clock& clock, std::uint32_t baud) {
  if (carrier == BoardLine::in_process) return nullptr;
  return std::make_unique<PseudoTerminal>(clock, SerialSettings{baud});
}
}  // namespace

EmbeddedBoard::EmbeddedBoard(const FirmwareConfig& firmware, BoardPlant& plant, const BoardHardwareConfig& host,
                             std::uint32_t baud, BoardLine carrier)
    : tick_(firmware.tick),
      pty_(open_carrier(carrier, real_clock_, baud)),
      port_(pty_ ? std::make_unique<SerialPort>(pty_->slave_path(), real_clock_, SerialSettings{baud}) : nullptr),
      line_(clock_, baud),
      firmware_(with_protocol(firmware, host), line_.board(), plant),
      host_(line_.host(), host) {
  if (pty_) line_.carry_over(*port_, *pty_, real_clock_);
}

std::filesystem::path EmbeddedBoard::device() const { return pty_ ? pty_->slave_path() : std::filesystem::path{}; }

void EmbeddedBoard::advance_to(Time now) noexcept {
  while (clock_.now() < now) {
    clock_.set(std::min(now, firmware_.now() + tick_));
    firmware_.run_until(clock_.now());
  }
}

}  // namespace tripodal::board
