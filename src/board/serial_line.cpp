#include "tripodal/board/serial_line.hpp"

#include <algorithm>

namespace tripodal::board {

SerialLine::SerialLine(const Clock& clock, std::uint32_t baud) noexcept {
  const Duration byte_time{10'000'000'000LL / std::max<std::uint32_t>(baud, 1)};
  for (End* end : {&host_, &board_}) {
    end->clock_ = &clock;
    end->byte_time_ = byte_time;
  }
  host_.out_ = &to_board_;
  host_.in_ = &to_host_;
  board_.out_ = &to_host_;
  board_.in_ = &to_board_;
}

bool SerialLine::End::write(std::span<const std::uint8_t> bytes) noexcept {
  if (!connected_) return true;  // the bytes leave, nobody receives them
  Direction& d = *out_;
  if (Direction::kCapacity - d.size < bytes.size()) return false;
  Time t = std::max(d.line_free, clock_->now());
  for (std::uint8_t b : bytes) {
    t += byte_time_;
    const std::size_t slot = (d.head + d.size) % Direction::kCapacity;
    d.bytes[slot] = b;
    d.arrival[slot] = t;
    ++d.size;
  }
  d.line_free = t;
  sent_ += bytes.size();
  return true;
}

std::ptrdiff_t SerialLine::End::read(std::span<std::uint8_t> out, Time /*deadline*/) noexcept {
  // Simulated time does not pass inside a read: what arrived by now is all there is.
  Direction& d = *in_;
  const Time now = clock_->now();
  std::size_t n = 0;
  while (n < out.size() && d.size > 0 && d.arrival[d.head] <= now) {
    out[n++] = d.bytes[d.head];
    d.head = (d.head + 1) % Direction::kCapacity;
    --d.size;
  }
  return static_cast<std::ptrdiff_t>(n);
}

}  // namespace tripodal::board
