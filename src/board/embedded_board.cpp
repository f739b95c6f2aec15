#include "tripodal/board/embedded_board.hpp"

#include <algorithm>

namespace tripodal::board {

EmbeddedBoard::EmbeddedBoard(const FirmwareConfig& firmware, BoardPlant& plant, const BoardHardwareConfig& host,
                             std::uint32_t baud)
    : tick_(firmware.tick), line_(clock_, baud), firmware_(firmware, line_.board(), plant), host_(line_.host(), host) {}

void EmbeddedBoard::advance_to(Time now) noexcept {
  while (clock_.now() < now) {
    clock_.set(std::min(now, firmware_.now() + tick_));
    firmware_.run_until(clock_.now());
  }
}

}  // namespace tripodal::board
