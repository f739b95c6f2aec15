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

void SerialLine::carry_over(ByteStream& host_side, ByteStream& board_side, const Clock& real_clock, Duration timeout) noexcept {
  host_.carrier_ = &host_side;
  board_.carrier_ = &board_side;
  for (End* end : {&host_, &board_}) {
    end->carrier_clock_ = &real_clock;
    end->carrier_timeout_ = timeout;
  }
}

bool SerialLine::End::write(std::span<const std::uint8_t> bytes) noexcept {
  if (!connected_) return true;  // the bytes leave, nobody receives them
  Direction& d = *out_;
  if (Direction::kCapacity - d.size < bytes.size()) return false;
  if (carrier_ != nullptr && !carrier_->write(bytes)) return false;
  Time t = std::max(d.line_free, clock_->now());
  for (std::uint8_t b : bytes) {
    t += byte_time_;
    const std::size_t slot = (d.head + d.size) % Direction::kCapacity;
    d.bytes[slot] = b;  // overwritten by what the carrier delivers, when carried
    d.arrival[slot] = t;
    ++d.size;
    if (carrier_ == nullptr) ++d.filled;
  }
  d.line_free = t;
  sent_ += bytes.size();
  return true;
}

// The bytes due by now come out of the carrier in the order they went in; the simulated clock
// stands still meanwhile, so the wait is in real time, bounded by the carrier's timeout.
bool SerialLine::End::fill_from_carrier(Direction& d, std::size_t due) noexcept {
  const Time give_up = carrier_clock_->now() + carrier_timeout_;
  while (d.filled < due) {
    std::array<std::uint8_t, 256> chunk{};
    const std::size_t want = std::min(chunk.size(), d.size - d.filled);
    const std::ptrdiff_t n = carrier_->read(std::span(chunk.data(), want), carrier_clock_->now() + kMaxReadWait);
    if (n < 0 || (n == 0 && carrier_clock_->now() >= give_up)) return false;
    for (std::ptrdiff_t i = 0; i < n; ++i) d.bytes[(d.head + d.filled++) % Direction::kCapacity] = chunk[static_cast<std::size_t>(i)];
  }
  return true;
}

std::ptrdiff_t SerialLine::End::read(std::span<std::uint8_t> out, Time /*deadline*/) noexcept {
  // Simulated time does not pass inside a read: what arrived by now is all there is.
  Direction& d = *in_;
  const Time now = clock_->now();
  std::size_t due = 0;
  while (due < d.size && due < out.size() && d.arrival[(d.head + due) % Direction::kCapacity] <= now) ++due;
  if (carrier_ != nullptr && d.filled < due && !fill_from_carrier(d, due)) {
    lost_ += d.size - d.filled;  // the carrier broke or stalled: what it still owes never arrives
    d.size = d.filled;
    due = std::min(due, d.size);
  }
  for (std::size_t n = 0; n < due; ++n) {
    out[n] = d.bytes[d.head];
    d.head = (d.head + 1) % Direction::kCapacity;
    --d.size;
    --d.filled;
  }
  return static_cast<std::ptrdiff_t>(due);
}

}  // namespace tripodal::board
