#include "tripodal/board/serial_line.hpp"

#include <algorithm>
#include <array>

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
  host_.peer_ = &board_;
  board_.peer_ = &host_;
}

void SerialLine::set_noise(const LineNoise& noise) noexcept {
  LineNoise to_host = noise;
  to_host.seed = noise.seed ^ 0x9E3779B97F4A7C15ULL;  // the two directions draw independently
  host_.set_noise(noise);
  board_.set_noise(to_host);
}

void SerialLine::End::set_noise(const LineNoise& noise) noexcept {
  noise_ = noise;
  rng_ = noise.seed;
}

// splitmix64: small, seeded, the same on every platform (std:: distributions are not).
double SerialLine::End::uniform() noexcept {
  std::uint64_t z = (rng_ += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30U)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27U)) * 0x94D049BB133111EBULL;
  z ^= z >> 31U;
  return static_cast<double>(z >> 11U) * 0x1.0p-53;
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
  if (!noise_.any()) {
    if (!put(bytes)) return false;
    sent_ += bytes.size();
    return true;
  }
  // Each byte may be dropped, corrupted (one bit) or doubled on its way; in chunks, no allocation.
  constexpr std::size_t kChunk = 128;
  while (!bytes.empty()) {
    const std::span<const std::uint8_t> in = bytes.first(std::min(kChunk, bytes.size()));
    bytes = bytes.subspan(in.size());
    std::array<std::uint8_t, 2 * kChunk> noisy{};
    std::size_t n = 0;
    for (std::uint8_t b : in) {
      if (uniform() < noise_.drop) {
        ++dropped_;
        continue;
      }
      if (uniform() < noise_.corrupt) {
        b = static_cast<std::uint8_t>(b ^ (1U << static_cast<unsigned>(uniform() * 8.0)));
        ++corrupted_;
      }
      noisy[n++] = b;
      if (uniform() < noise_.duplicate) {
        noisy[n++] = b;
        ++duplicated_;
      }
    }
    if (!put(std::span<const std::uint8_t>(noisy.data(), n))) return false;
    sent_ += in.size();
  }
  return true;
}

bool SerialLine::End::put(std::span<const std::uint8_t> bytes) noexcept {
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
  return true;
}

// The bytes due by now come out of the carrier in the order they went in; the simulated clock
// stands still meanwhile, so the wait is in real time, bounded by the carrier's timeout.
SerialLine::End::Fill SerialLine::End::fill_from_carrier(Direction& d, std::size_t due) noexcept {
  const Time give_up = carrier_clock_->now() + carrier_timeout_;
  while (d.filled < due) {
    std::array<std::uint8_t, 256> chunk{};
    const std::size_t want = std::min(chunk.size(), d.size - d.filled);
    const std::ptrdiff_t n = carrier_->read(std::span(chunk.data(), want), carrier_clock_->now() + kMaxReadWait);
    if (n < 0) return Fill::failed;
    if (n == 0 && carrier_clock_->now() >= give_up) return Fill::stalled;
    for (std::ptrdiff_t i = 0; i < n; ++i) d.bytes[(d.head + d.filled++) % Direction::kCapacity] = chunk[static_cast<std::size_t>(i)];
  }
  return Fill::done;
}

void SerialLine::End::forget_owed(Direction& d, std::uint64_t& lost) noexcept {
  lost += d.size - d.filled;
  d.size = d.filled;
}

bool SerialLine::End::reopen() noexcept {
  if (carrier_ == nullptr || !carrier_->reopen()) return false;
  // The old device took what either side still owed with it. The reopen flushed the new one's
  // queues; what already sat in the other side's read queue (bytes echoed while another process
  // had turned echo on) is drained too, or the peer would take it for the bytes it is owed and
  // stay shifted by it for good.
  forget_owed(*in_, lost_);
  forget_owed(*out_, peer_->lost_);
  if (peer_->carrier_ != nullptr) {
    std::array<std::uint8_t, 256> stale{};
    while (peer_->carrier_->read(stale, carrier_clock_->now() + kMaxReadWait) > 0) {
    }
  }
  return true;
}

std::string_view SerialLine::End::check() noexcept { return carrier_ != nullptr ? carrier_->check() : std::string_view{}; }

std::ptrdiff_t SerialLine::End::read(std::span<std::uint8_t> out, Time /*deadline*/) noexcept {
  // Simulated time does not pass inside a read: what arrived by now is all there is.
  Direction& d = *in_;
  const Time now = clock_->now();
  std::size_t due = 0;
  while (due < d.size && due < out.size() && d.arrival[(d.head + due) % Direction::kCapacity] <= now) ++due;
  if (carrier_ != nullptr && d.filled < due) {
    const Fill fill = fill_from_carrier(d, due);
    if (fill != Fill::done) {
      forget_owed(d, lost_);  // the carrier broke or stalled: what it still owes never arrives
      due = std::min(due, d.size);
    }
    // The device failed (hung up, closed under us): say so, as the port itself would, so the
    // link reopens it (docs/board-protocol.md); what did arrive is delivered on the next read.
    if (fill == Fill::failed) return -1;
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
