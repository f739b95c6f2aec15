#include "tripodal/board/frame.hpp"

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

namespace tripodal::board {

std::uint8_t crc8(std::span<const std::uint8_t> bytes, std::uint8_t crc) noexcept {
  // Continues from `crc`: one byte at a time, each step the CRC of the single byte crc ^ b.
  for (std::uint8_t b : bytes) {
    const std::array<std::uint8_t, 1> one{static_cast<std::uint8_t>(crc ^ b)};
    crc = checksum(ChecksumKind::crc8_smbus, one);
  }
  return crc;
}

std::size_t encode_frame(std::span<const std::uint8_t> body, std::span<std::uint8_t> out, const FrameFormat& format,
                         std::size_t uncounted) noexcept {
  if (body.size() <= uncounted) return 0;
  const std::size_t n = body.size() - uncounted;  // the Length field
  if (n > format.max_length) return 0;
  const bool long_frame = n > format.max_short_length;
  const bool with_checksum = format.checksum != ChecksumKind::none;
  const std::size_t header = long_frame ? 3 : 2;
  const std::size_t total = header + body.size() + (with_checksum ? 1 : 0);
  if (out.size() < total) return 0;
  out[0] = long_frame ? format.flag_long : format.flag_short;
  out[1] = static_cast<std::uint8_t>(n & 0xFFU);
  if (long_frame) out[2] = static_cast<std::uint8_t>(n >> 8);
  std::memcpy(out.data() + header, body.data(), body.size());
  if (with_checksum) out[header + body.size()] = checksum(format.checksum, out.first(header + body.size()));
  return total;
}

namespace {
std::size_t encode_with_prefix(std::span<const std::uint8_t> prefix, std::span<const std::uint8_t> payload,
                               std::span<std::uint8_t> out, const FrameFormat& format, std::size_t uncounted) noexcept {
  // The body is small enough to stage on the stack.
  std::array<std::uint8_t, kMaxLength + 1> body{};
  const std::size_t n = prefix.size() + payload.size();
  if (n > body.size()) return 0;
  std::memcpy(body.data(), prefix.data(), prefix.size());
  if (!payload.empty()) std::memcpy(body.data() + prefix.size(), payload.data(), payload.size());
  return encode_frame(std::span<const std::uint8_t>(body.data(), n), out, format, uncounted);
}
}  // namespace

std::size_t encode_request(std::uint8_t cmd, std::span<const std::uint8_t> payload, std::span<std::uint8_t> out,
                           const FrameFormat& format) noexcept {
  const std::array<std::uint8_t, 2> prefix{format.type_byte, cmd};
  return encode_with_prefix(prefix, payload, out, format, format.length_rule == LengthRule::cmd_payload ? 1 : 0);
}

std::size_t encode_response(std::uint8_t resp, std::span<const std::uint8_t> payload, std::span<std::uint8_t> out,
                            const FrameFormat& format) noexcept {
  const std::array<std::uint8_t, 1> prefix{resp};
  return encode_with_prefix(prefix, payload, out, format, 0);
}

std::string_view to_string(DecodeErrorKind kind) noexcept {
  switch (kind) {
    case DecodeErrorKind::none: return "none";
    case DecodeErrorKind::garbage: return "garbage";
    case DecodeErrorKind::empty: return "empty";
    case DecodeErrorKind::oversize: return "oversize";
    case DecodeErrorKind::checksum: return "checksum";
    case DecodeErrorKind::truncated: return "truncated";
  }
  return "?";
}

std::string describe(const DecodeError& e) {
  switch (e.kind) {
    case DecodeErrorKind::none: return "no error";
    case DecodeErrorKind::garbage:
      return fmt::format("stream offset {}: garbage: {} byte(s) skipped; expected a Flag 0x{:02x} or 0x{:02x}", e.offset, e.length,
                         e.flag_short, e.flag_long);
    case DecodeErrorKind::empty:
      return fmt::format("stream offset {}: empty frame: Length 0; expected at least 1 (the CMD or Resp byte)", e.offset);
    case DecodeErrorKind::oversize:
      return fmt::format("stream offset {}: oversize frame: Length {}; expected at most {}", e.offset, e.length, kMaxLength);
    case DecodeErrorKind::checksum: {
      std::string m = fmt::format("stream offset {}: checksum mismatch: frame of Length {} carries CHKSUM 0x{:02x}, expected 0x{:02x} ({})",
                                  e.offset, e.length, e.carried, e.computed, to_string(e.expected));
      if (e.fits < kChecksumKindCount) {
        m += fmt::format("; the frame fits {}{}", e.fits == static_cast<std::uint8_t>(ChecksumKind::sum8) ? "an " : "",
                         to_string(static_cast<ChecksumKind>(e.fits)));
      }
      if (e.fits_other_length_rule) m += "; the frame fits if Length is read by the other rule (TYPE counted or not)";
      return m;
    }
    case DecodeErrorKind::truncated:
      return fmt::format("stream offset {}: truncated frame: Length {} but the frame's bytes stopped coming", e.offset, e.length);
  }
  return "?";
}

void FrameDecoder::fail(DecodeErrorKind kind, std::uint32_t length, std::uint8_t carried, std::uint8_t computed) noexcept {
  last_error_ = DecodeError{kind,          offset_,          length, carried, computed, format_.checksum, kChecksumKindCount,
                            false, format_.flag_short, format_.flag_long};
  switch (kind) {
    case DecodeErrorKind::empty: ++stats_.empty; break;
    case DecodeErrorKind::oversize: ++stats_.oversize; break;
    case DecodeErrorKind::checksum: ++stats_.checksum; break;
    case DecodeErrorKind::truncated: ++stats_.truncated; break;
    default: break;
  }
  // Only the Flag is given up: the candidate's other bytes are scanned again. Those skipped
  // before the next Flag are the remains of this error, not a new one.
  ++begin_;
  ++offset_;
  in_garbage_ = true;
}

void FrameDecoder::skip_garbage() noexcept {
  const std::uint8_t* first = buffer_.data() + begin_;
  const std::uint8_t* last = buffer_.data() + end_;
  const std::uint8_t* flag = std::find_if(first, last, [this](std::uint8_t b) { return is_flag(b); });
  const auto skipped = static_cast<std::size_t>(flag - first);
  if (skipped == 0) return;
  if (!in_garbage_) {
    // A new run: one error, located at its first byte.
    ++stats_.garbage_runs;
    last_error_ = DecodeError{DecodeErrorKind::garbage, offset_, 0, 0, 0, format_.checksum, kChecksumKindCount,
                              false, format_.flag_short, format_.flag_long};
    in_garbage_ = true;
  }
  if (last_error_.kind == DecodeErrorKind::garbage) last_error_.length += static_cast<std::uint32_t>(skipped);
  stats_.garbage_bytes += skipped;
  begin_ += skipped;
  offset_ += skipped;
  if (begin_ < end_) in_garbage_ = false;  // the run ended at a Flag
}

bool FrameDecoder::is_flag(std::uint8_t b) const noexcept {
  if (b == format_.flag_short || b == format_.flag_long) return true;
  // Table 3-2 read per frame: CheckSumEn clear, no CHKSUM.
  return format_.checksum_optional && (b == (format_.flag_short & ~kFlagChecksumEn) || b == (format_.flag_long & ~kFlagChecksumEn));
}

// A frame failed its checksum: which other dialect would it fit? Another known checksum over the
// same bytes, or the same checksum with Length read by the other rule (one byte more or less).
void FrameDecoder::diagnose(const std::uint8_t* p, std::size_t header, std::size_t extra, std::size_t length,
                            std::size_t avail) noexcept {
  const std::size_t covered = header + extra + length;
  const std::span<const std::uint8_t> frame(p, covered);
  for (ChecksumKind k : {ChecksumKind::crc8_smbus, ChecksumKind::sum8, ChecksumKind::xor8}) {
    if (k == format_.checksum || checksum(k, frame) != p[covered]) continue;
    last_error_.fits = static_cast<std::uint8_t>(k);
    ++stats_.fits[static_cast<std::size_t>(k)];
    break;
  }
  const bool typed = header < avail && p[header] == format_.type_byte;  // a request or an echo
  if (!typed) return;
  // TYPE uncounted here: the other rule counts it, so the frame is one byte shorter; counted
  // here: the other rule adds one byte.
  const std::size_t other = extra == 1 ? covered - 1 : covered + 1;
  if (other + 1 > avail || other <= header) return;
  if (checksum(format_.checksum, std::span<const std::uint8_t>(p, other)) == p[other]) {
    last_error_.fits_other_length_rule = true;
    ++stats_.fits_other_length_rule;
  }
}

bool FrameDecoder::scan() noexcept {
  while (true) {
    skip_garbage();
    const std::size_t avail = end_ - begin_;
    if (avail < 2) return false;
    const std::uint8_t* p = buffer_.data() + begin_;
    const bool long_frame = (p[0] & kFlagLongFrame) != 0;
    const bool with_checksum = (p[0] & kFlagChecksumEn) != 0 && format_.checksum != ChecksumKind::none;
    const std::size_t header = long_frame ? 3 : 2;
    if (avail < header) return false;
    const std::size_t length = long_frame ? (p[1] | (static_cast<std::size_t>(p[2]) << 8)) : p[1];
    if (length == 0) {
      fail(DecodeErrorKind::empty, 0);
      continue;
    }
    if (length > format_.max_length) {
      fail(DecodeErrorKind::oversize, static_cast<std::uint32_t>(length));
      continue;
    }
    // The thesis's rule leaves a request's TYPE out of Length: every request has one; among
    // responses only the SYNC echo, which starts with it.
    std::size_t extra = 0;
    if (format_.length_rule == LengthRule::cmd_payload) {
      if (side_ == FrameSide::requests) {
        extra = 1;
      } else {
        if (avail <= header) return false;
        extra = p[header] == format_.type_byte ? 1 : 0;
      }
    }
    const std::size_t total = header + extra + length + (with_checksum ? 1 : 0);
    if (avail < total) return false;
    if (with_checksum) {
      const std::uint8_t computed = checksum(format_.checksum, std::span<const std::uint8_t>(p, total - 1));
      if (computed != p[total - 1]) {
        fail(DecodeErrorKind::checksum, static_cast<std::uint32_t>(length), p[total - 1], computed);
        diagnose(p, header, extra, length, avail);  // p: still the failed candidate's bytes
        continue;
      }
    }
    frame_.long_frame = long_frame;
    frame_.body = std::span<const std::uint8_t>(p + header, extra + length);
    frame_.bytes = std::span<const std::uint8_t>(p, total);
    drop_ = total;
    ++stats_.frames;
    return true;
  }
}

void FrameDecoder::compact() noexcept {
  if (begin_ == 0) return;
  const std::size_t n = end_ - begin_;
  if (n > 0) std::memmove(buffer_.data(), buffer_.data() + begin_, n);
  begin_ = 0;
  end_ = n;
}

FrameDecoder::Result FrameDecoder::decode(std::span<const std::uint8_t> input) noexcept {
  Result result;
  if (drop_ > 0) {
    begin_ += drop_;
    offset_ += drop_;
    drop_ = 0;
  }
  while (true) {
    if (scan()) {
      result.frame = true;
      return result;
    }
    const std::size_t remaining = input.size() - result.consumed;
    if (remaining == 0) return result;
    if (buffer_.size() - end_ < remaining) compact();
    const std::size_t n = std::min(remaining, buffer_.size() - end_);
    std::memcpy(buffer_.data() + end_, input.data() + result.consumed, n);
    end_ += n;
    result.consumed += n;
    stats_.bytes += n;
  }
}

std::size_t FrameDecoder::feed(std::span<const std::uint8_t> input) noexcept {
  return feed(input, [](const FrameView&) noexcept {});
}

FrameDecoder::Result FrameDecoder::abandon_partial() noexcept {
  if (drop_ > 0) {
    begin_ += drop_;
    offset_ += drop_;
    drop_ = 0;
  }
  Result result;
  if (!partial()) return result;
  const std::uint8_t* p = buffer_.data() + begin_;
  std::uint32_t length = 0;
  if (end_ - begin_ >= 2) length = p[1];
  if ((p[0] & kFlagLongFrame) != 0 && end_ - begin_ >= 3) length |= static_cast<std::uint32_t>(p[2]) << 8;
  fail(DecodeErrorKind::truncated, length);
  result.frame = scan();
  return result;
}

void FrameDecoder::reset() noexcept {
  begin_ = end_ = drop_ = 0;
  in_garbage_ = false;
}

}  // namespace tripodal::board
