// The control-board link's framing (seed 001, section 3.3, Tables 3-1 to 3-6), byte for byte: the
// bottom of the board area, below the hardware type that drives a differential base through the
// board. The dialect (Flags, Length rule, checksum) is a FrameFormat from a protocol profile
// (protocol_profile.hpp); the functions without one speak tripodal-v1, the dialect of the golden
// frames before profiles. Encoding writes into caller storage; FrameDecoder finds frames in a byte
// stream across partial reads and resynchronises by re-scanning, without allocating.
// docs/board-protocol.md is the reference for every byte.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "tripodal/board/protocol_profile.hpp"

namespace tripodal::board {

/// Flag bits (Table 3-2): bit 6 LongFrame, bit 4 CheckSumEn, the rest zero.
inline constexpr std::uint8_t kFlagLongFrame = 0x40;
inline constexpr std::uint8_t kFlagChecksumEn = 0x10;
/// The two flags a frame may start with: short (8-bit Length) and long (16-bit Length), both with
/// the checksum; a frame without it is refused (it could not be told from line noise).
inline constexpr std::uint8_t kFlagShort = kFlagChecksumEn;                  // 0x10
inline constexpr std::uint8_t kFlagLong = kFlagLongFrame | kFlagChecksumEn;  // 0x50
/// The TYPE byte that opens the body of every request (Tables 3-3 and 3-4).
inline constexpr std::uint8_t kRequestType = 0xA8;
/// Largest Length field accepted: the thesis's 512-byte UART buffers (a profile may set less).
/// Length counts CMD or Resp and the payload, and a request's TYPE under tripodal-v1; never Flag,
/// Length or CHKSUM.
inline constexpr std::size_t kMaxLength = 512;
/// Largest Length of a short frame (one Length byte); longer bodies go in a long frame.
inline constexpr std::size_t kMaxShortLength = 255;
/// Flag + Len + LenH + an uncounted TYPE (the thesis's Length rule) + CHKSUM: the most a frame
/// adds to its Length.
inline constexpr std::size_t kMaxOverhead = 5;
inline constexpr std::size_t kMaxFrameBytes = kMaxLength + kMaxOverhead;

/// The checksum (CHKSUM): CRC-8 with polynomial x^8 + x^2 + x + 1 (0x07), initial value 0, no
/// reflection, no final XOR (CRC-8/SMBUS; check value 0xF4 over "123456789"), over every byte of
/// the frame before CHKSUM (Flag, Length bytes and body). Detects every error burst of up to 8
/// bits and every odd number of flipped bits, which a byte sum does not. Both shipped profiles'.
[[nodiscard]] std::uint8_t crc8(std::span<const std::uint8_t> bytes, std::uint8_t crc = 0) noexcept;

/// Which end's frames a decoder reads: under the thesis's Length rule a request carries a TYPE
/// byte its Length does not count; among responses only a SYNC echo does (it starts with TYPE).
enum class FrameSide : std::uint8_t { requests, responses };

/// A decoded frame's body (TYPE, CMD or Resp, payload: every byte between Length and CHKSUM),
/// viewing the decoder's storage: valid until the decoder is fed again.
struct FrameView {
  bool long_frame = false;
  std::span<const std::uint8_t> body;   ///< Length bytes, and the uncounted TYPE if any
  std::span<const std::uint8_t> bytes;  ///< the whole frame, Flag to CHKSUM (a SYNC echo sends it back)
};

/// Writes a frame with body `body` into `out` (short when its Length is at most the format's
/// max_short_length, long otherwise) and returns its size. Length counts the body less its first
/// `uncounted` bytes (1: a request's TYPE under the thesis's rule). 0 when Length would be 0 or
/// above the format's max_length or `out` is too small (nothing is written then).
[[nodiscard]] std::size_t encode_frame(std::span<const std::uint8_t> body, std::span<std::uint8_t> out,
                                       const FrameFormat& format = kTripodalV1Format, std::size_t uncounted = 0) noexcept;
/// A request: body = TYPE (0xA8), CMD, payload; Length by the format's rule. 0 on the same
/// conditions as encode_frame.
[[nodiscard]] std::size_t encode_request(std::uint8_t cmd, std::span<const std::uint8_t> payload, std::span<std::uint8_t> out,
                                         const FrameFormat& format = kTripodalV1Format) noexcept;
/// A response: body = Resp, payload; Length = Resp + payload.
[[nodiscard]] std::size_t encode_response(std::uint8_t resp, std::span<const std::uint8_t> payload, std::span<std::uint8_t> out,
                                          const FrameFormat& format = kTripodalV1Format) noexcept;

/// What went wrong in the byte stream. Every kind is counted (DecoderStats).
enum class DecodeErrorKind : std::uint8_t {
  none,
  garbage,    ///< bytes skipped while looking for a Flag (0x10 or 0x50)
  empty,      ///< Length 0: a frame has at least its CMD or Resp byte
  oversize,   ///< Length above 512
  checksum,   ///< CHKSUM differs from the profile's checksum of the frame
  truncated,  ///< a frame started but its remaining bytes never came (abandon_partial)
};
[[nodiscard]] std::string_view to_string(DecodeErrorKind kind) noexcept;

/// The latest error, located in the stream (offset of the byte that began the failed candidate).
struct DecodeError {
  DecodeErrorKind kind = DecodeErrorKind::none;
  std::uint64_t offset = 0;    ///< stream offset of the Flag (or first garbage byte)
  std::uint32_t length = 0;    ///< Length field (empty, oversize, checksum, truncated) or bytes skipped (garbage)
  std::uint8_t carried = 0;    ///< checksum: the CHKSUM byte received
  std::uint8_t computed = 0;   ///< checksum: the profile's checksum computed
  ChecksumKind expected = ChecksumKind::crc8_smbus;  ///< checksum: the profile's
  /// checksum: another known checksum the frame fits (kChecksumKindCount: none fits), the hint
  /// that the other end speaks another dialect.
  std::uint8_t fits = kChecksumKindCount;
  /// checksum: the frame fits its CHKSUM when Length is read by the other rule (TYPE counted or not).
  bool fits_other_length_rule = false;
  std::uint8_t flag_short = 0x10;  ///< garbage: the Flags that were looked for
  std::uint8_t flag_long = 0x50;
};
/// One line: "stream offset 17: checksum mismatch: frame of Length 3 carries CHKSUM 0x12, expected
/// 0xf4 (CRC-8/SMBUS); the frame fits an 8-bit sum".
[[nodiscard]] std::string describe(const DecodeError& error);

struct DecoderStats {
  std::uint64_t bytes = 0;           ///< bytes fed
  std::uint64_t frames = 0;          ///< valid frames delivered
  std::uint64_t garbage_bytes = 0;   ///< bytes skipped outside any frame
  std::uint64_t garbage_runs = 0;    ///< runs of skipped bytes between frames (each one error); the bytes
                                     ///< skipped after a refused candidate belong to its error
  std::uint64_t empty = 0;
  std::uint64_t oversize = 0;
  std::uint64_t checksum = 0;
  std::uint64_t truncated = 0;
  /// Checksum failures that another known checksum fits, per ChecksumKind, and those that fit
  /// the other Length rule: evidence of a dialect mismatch rather than line noise.
  std::array<std::uint64_t, kChecksumKindCount> fits{};
  std::uint64_t fits_other_length_rule = 0;
  /// Every error event: garbage runs, empty, oversize, checksum and truncated candidates.
  [[nodiscard]] std::uint64_t errors() const noexcept { return garbage_runs + empty + oversize + checksum + truncated; }
};

/// Finds frames in a byte stream. Bytes go into a fixed buffer; a candidate that fails (Length
/// 0 or above 512, bad CHKSUM) costs only its Flag byte: the scan resumes at the next byte, so a
/// frame that begins inside a corrupt or truncated one is still found (resynchronisation within
/// one frame, no buffer dropped). No allocation, no exception; one thread.
class FrameDecoder {
 public:
  /// A decoder of `side`'s frames in `format`'s dialect (by default tripodal-v1's responses).
  explicit FrameDecoder(const FrameFormat& format = kTripodalV1Format, FrameSide side = FrameSide::responses) noexcept
      : format_(format), side_(side) {}

  struct Result {
    std::size_t consumed = 0;  ///< bytes of the input taken (the rest: feed them again)
    bool frame = false;        ///< frame() holds a new frame
  };

  /// Takes bytes from `input` until one frame completes or the input is used up. After a frame,
  /// call again with the rest of the input (input.subspan(consumed)).
  Result decode(std::span<const std::uint8_t> input) noexcept;
  /// Feeds all of `input`, calling on_frame(const FrameView&) for each frame; returns their count.
  /// The entry point for a fuzz target: any bytes at all, no precondition.
  template <class OnFrame>
  std::size_t feed(std::span<const std::uint8_t> input, OnFrame&& on_frame) {
    std::size_t frames = 0;
    while (true) {
      const Result r = decode(input);
      if (r.frame) {
        ++frames;
        on_frame(frame());
      }
      input = input.subspan(r.consumed);
      if (!r.frame && input.empty()) return frames;
    }
  }
  /// Feeds all of `input` and drops the frames; returns their count (benchmarks, fuzzing).
  std::size_t feed(std::span<const std::uint8_t> input) noexcept;

  /// The latest frame (after a Result with frame == true).
  [[nodiscard]] const FrameView& frame() const noexcept { return frame_; }
  /// A frame has started (a Flag is buffered) but is not complete.
  [[nodiscard]] bool partial() const noexcept { return end_ > begin_ + drop_; }
  /// Gives up the partial frame at the front (its bytes did not come in time): counts it as
  /// truncated and re-scans the bytes buffered after its Flag. Returns whether a frame completed.
  Result abandon_partial() noexcept;
  /// Forgets buffered bytes (a port reopened); statistics stay.
  void reset() noexcept;

  [[nodiscard]] const DecoderStats& stats() const noexcept { return stats_; }
  [[nodiscard]] const DecodeError& last_error() const noexcept { return last_error_; }

 private:
  bool scan() noexcept;  // looks for a frame at the front; true when one is complete
  void fail(DecodeErrorKind kind, std::uint32_t length, std::uint8_t carried = 0, std::uint8_t computed = 0) noexcept;
  [[nodiscard]] bool is_flag(std::uint8_t b) const noexcept;
  void diagnose(const std::uint8_t* p, std::size_t header, std::size_t extra, std::size_t length, std::size_t avail) noexcept;
  void skip_garbage() noexcept;
  void compact() noexcept;

  // Twice a frame: a whole candidate plus what follows it always fits without moving bytes more
  // than once per frame.
  std::array<std::uint8_t, 2 * kMaxFrameBytes> buffer_{};
  FrameFormat format_;
  FrameSide side_;
  std::size_t begin_ = 0;  // first buffered byte not yet consumed
  std::size_t end_ = 0;    // one past the last buffered byte
  std::size_t drop_ = 0;   // bytes of the delivered frame to drop at the next call
  bool in_garbage_ = false;  // inside a run of skipped bytes (counted once)
  std::uint64_t offset_ = 0;  // stream offset of buffer_[begin_]
  FrameView frame_;
  DecoderStats stats_;
  DecodeError last_error_;
};

}  // namespace tripodal::board
