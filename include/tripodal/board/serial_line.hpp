// A simulated UART line between the host and the simulated board, in process and in simulated
// time: each byte arrives one character time (10 bits at the baud rate: 86.8 us at 115200) after
// the previous one left, so round trips and link utilisation are those of the real line. Both
// ends are ByteStreams; nothing blocks (a read returns what has arrived by the clock's now).
// Carried by a real byte stream (a pseudo-terminal: `tripodal run --board pty`), every byte
// crosses the kernel's tty and the line only keeps the simulated times at which they arrive.
// A line may be noisy (LineNoise: bytes corrupted, dropped or duplicated at seeded random), so
// both ends' decoders are tested against what a real cable does to bytes.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/clock.hpp"

namespace tripodal::board {

/// What a noisy line does to the bytes one end sends, each byte on its own: probabilities per
/// byte in [0, 1] (0: a clean line), drawn from a generator seeded with `seed` so a run repeats.
struct LineNoise {
  double corrupt = 0.0;    ///< one of the byte's 8 bits flipped
  double drop = 0.0;       ///< the byte never arrives
  double duplicate = 0.0;  ///< the byte arrives twice
  std::uint64_t seed = 1;
  [[nodiscard]] bool any() const noexcept { return corrupt > 0.0 || drop > 0.0 || duplicate > 0.0; }
};

class SerialLine {
 public:
  /// One direction: a fixed ring of bytes with their arrival times.
  class End final : public ByteStream {
   public:
    bool write(std::span<const std::uint8_t> bytes) noexcept override;
    std::ptrdiff_t read(std::span<std::uint8_t> out, Time deadline) noexcept override;
    /// Cuts the line (a board that stops answering): writes are lost until reconnected.
    void set_connected(bool connected) noexcept { connected_ = connected; }
    [[nodiscard]] std::uint64_t bytes_sent() const noexcept { return sent_; }
    /// Bytes the carrier failed to deliver in its time limit (dropped from the line).
    [[nodiscard]] std::uint64_t bytes_lost() const noexcept { return lost_; }
    /// Makes what this end sends noisy (LineNoise{} makes it clean again).
    void set_noise(const LineNoise& noise) noexcept;
    /// What the noise did to the bytes this end sent.
    [[nodiscard]] std::uint64_t bytes_corrupted() const noexcept { return corrupted_; }
    [[nodiscard]] std::uint64_t bytes_dropped() const noexcept { return dropped_; }
    [[nodiscard]] std::uint64_t bytes_duplicated() const noexcept { return duplicated_; }
    /// Carried: opens this end's device again (the carrier's reopen) and forgets what the old
    /// one still owed either way (lost). In process there is no device: false.
    bool reopen() noexcept override;
    /// Carried: the carrier's check (its settings read back); in process always fine.
    [[nodiscard]] std::string_view check() noexcept override;

   private:
    friend class SerialLine;
    struct Direction {
      static constexpr std::size_t kCapacity = 8192;
      std::array<std::uint8_t, kCapacity> bytes{};
      std::array<Time, kCapacity> arrival{};
      std::size_t head = 0;
      std::size_t size = 0;
      std::size_t filled = 0;  // queued bytes, from head, that have arrived (all without a carrier)
      Time line_free{};  // when the transmitter finishes the last queued byte
    };
    enum class Fill { done, stalled, failed };
    const Clock* clock_ = nullptr;
    Duration byte_time_{0};
    Direction* out_ = nullptr;
    Direction* in_ = nullptr;
    End* peer_ = nullptr;
    bool connected_ = true;
    std::uint64_t sent_ = 0;
    std::uint64_t lost_ = 0;
    LineNoise noise_;
    std::uint64_t rng_ = 0;
    std::uint64_t corrupted_ = 0;
    std::uint64_t dropped_ = 0;
    std::uint64_t duplicated_ = 0;
    ByteStream* carrier_ = nullptr;  // this end's side of the real stream, when carried
    const Clock* carrier_clock_ = nullptr;
    Duration carrier_timeout_{0};
    Fill fill_from_carrier(Direction& d, std::size_t due) noexcept;
    bool put(std::span<const std::uint8_t> bytes) noexcept;  // onto the line as they are
    double uniform() noexcept;                                // [0, 1) from rng_
    void forget_owed(Direction& d, std::uint64_t& lost) noexcept;
  };

  SerialLine(const Clock& clock, std::uint32_t baud = 115200) noexcept;
  SerialLine(const SerialLine&) = delete;
  SerialLine& operator=(const SerialLine&) = delete;

  [[nodiscard]] End& host() noexcept { return host_; }
  [[nodiscard]] End& board() noexcept { return board_; }
  /// Carries the line over a real byte stream: what the host end writes goes into `host_side` and
  /// is read from `board_side`, and the reverse. Reads wait (on `real_clock`, at most
  /// `timeout` per read) for bytes that are due but still in the kernel; bytes that do not come
  /// in that time are lost (bytes_lost). Both streams must outlive the line.
  void carry_over(ByteStream& host_side, ByteStream& board_side, const Clock& real_clock,
                  Duration timeout = std::chrono::seconds(1)) noexcept;

  /// Both directions noisy alike (each end's generator seeded from `noise.seed` and its side).
  void set_noise(const LineNoise& noise) noexcept;

  /// One character: start bit, 8 data bits, stop bit.
  [[nodiscard]] Duration byte_time() const noexcept { return host_.byte_time_; }

 private:
  End::Direction to_board_;
  End::Direction to_host_;
  End host_;
  End board_;
};

}  // namespace tripodal::board
