#include "tripodal/board/frame.hpp"

#include <algorithm>
#include <cstring>

#include <fmt/format.h>

namespace tripodal::board {
namespace {

constexpr std::array<std::uint8_t, 256> make_crc_table() noexcept {
  std::array<std::uint8_t, 256> table{};
  for (unsigned i = 0; i < 256; ++i) {
    unsigned c = i;
    for (int bit = 0; bit < 8; ++bit) c = (c & 0x80U) != 0 ? ((c << 1) ^ 0x07U) & 0xFFU : (c << 1) & 0xFFU;
    table[i] = static_cast<std::uint8_t>(c);
  }
  return table;
}
constexpr std::array<std::uint8_t, 256> kCrcTable = make_crc_table();

constexpr bool is_flag(std::uint8_t b) noexcept { return b == kFlagShort || b == kFlagLong; }

}  // namespace

std::uint8_t crc8(std::span<const std::uint8_t> bytes, std::uint8_t crc) noexcept {
  for (std::uint8_t b : bytes) crc = kCrcTable[static_cast<std::uint8_t>(crc ^ b)];
  return crc;
}

std::size_t encode_frame(std::span<const std::uint8_t> body, std::span<std::uint8_t> out) noexcept {
  const std::size_t n = body.size();
  if (n == 0 || n > kMaxLength) return 0;
  const bool long_frame = n > kMaxShortLength;
  const std::size_t header = long_frame ? 3 : 2;
  const std::size_t total = header + n + 1;
  if (out.size() < total) return 0;
  out[0] = long_frame ? kFlagLong : kFlagShort;
  out[1] = static_cast<std::uint8_t>(n & 0xFFU);
  if (long_frame) out[2] = static_cast<std::uint8_t>(n >> 8);
  std::memcpy(out.data() + header, body.data(), n);
  out[header + n] = crc8(out.first(header + n));
  return total;
}

namespace {
std::size_t encode_with_prefix(std::span<const std::uint8_t> prefix, std::span<const std::uint8_t> payload,
                               std::span<std::uint8_t> out) noexcept {
  // Assembles the body in place after the longest header, then lets encode_frame's layout decide:
  // the body is small enough to stage on the stack.
  std::array<std::uint8_t, kMaxLength> body{};
  const std::size_t n = prefix.size() + payload.size();
  if (n > kMaxLength) return 0;
  std::memcpy(body.data(), prefix.data(), prefix.size());
  if (!payload.empty()) std::memcpy(body.data() + prefix.size(), payload.data(), payload.size());
  return encode_frame(std::span<const std::uint8_t>(body.data(), n), out);
}
}  // namespace

std::size_t encode_request(std::uint8_t cmd, std::span<const std::uint8_t> payload, std::span<std::uint8_t> out) noexcept {
  const std::array<std::uint8_t, 2> prefix{kRequestType, cmd};
  return encode_with_prefix(prefix, payload, out);
}

std::size_t encode_response(std::uint8_t resp, std::span<const std::uint8_t> payload, std::span<std::uint8_t> out) noexcept {
  const std::array<std::uint8_t, 1> prefix{resp};
  return encode_with_prefix(prefix, payload, out);
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
      return fmt::format("stream offset {}: garbage: {} byte(s) skipped; expected a Flag 0x10 or 0x50", e.offset, e.length);
    case DecodeErrorKind::empty:
      return fmt::format("stream offset {}: empty frame: Length 0; expected at least 1 (the CMD or Resp byte)", e.offset);
    case DecodeErrorKind::oversize:
      return fmt::format("stream offset {}: oversize frame: Length {}; expected at most {}", e.offset, e.length, kMaxLength);
    case DecodeErrorKind::checksum:
      return fmt::format("stream offset {}: checksum mismatch: frame of Length {} carries CHKSUM 0x{:02x}, expected 0x{:02x}",
                         e.offset, e.length, e.carried, e.computed);
    case DecodeErrorKind::truncated:
      return fmt::format("stream offset {}: truncated frame: Length {} but the frame's bytes stopped coming", e.offset, e.length);
  }
  return "?";
}

void FrameDecoder::fail(DecodeErrorKind kind, std::uint32_t length, std::uint8_t carried, std::uint8_t computed) noexcept {
  last_error_ = DecodeError{kind, offset_, length, carried, computed};
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
  const std::uint8_t* flag = std::find_if(first, last, is_flag);
  const auto skipped = static_cast<std::size_t>(flag - first);
  if (skipped == 0) return;
  if (!in_garbage_) {
    // A new run: one error, located at its first byte.
    ++stats_.garbage_runs;
    last_error_ = DecodeError{DecodeErrorKind::garbage, offset_, 0, 0, 0};
    in_garbage_ = true;
  }
  if (last_error_.kind == DecodeErrorKind::garbage) last_error_.length += static_cast<std::uint32_t>(skipped);
  stats_.garbage_bytes += skipped;
  begin_ += skipped;
  offset_ += skipped;
  if (begin_ < end_) in_garbage_ = false;  // the run ended at a Flag
}

bool FrameDecoder::scan() noexcept {
  while (true) {
    skip_garbage();
    const std::size_t avail = end_ - begin_;
    if (avail < 2) return false;
    const std::uint8_t* p = buffer_.data() + begin_;
    const bool long_frame = p[0] == kFlagLong;
    const std::size_t header = long_frame ? 3 : 2;
    if (avail < header) return false;
    const std::size_t length = long_frame ? (p[1] | (static_cast<std::size_t>(p[2]) << 8)) : p[1];
    if (length == 0) {
      fail(DecodeErrorKind::empty, 0);
      continue;
    }
    if (length > kMaxLength) {
      fail(DecodeErrorKind::oversize, static_cast<std::uint32_t>(length));
      continue;
    }
    const std::size_t total = header + length + 1;
    if (avail < total) return false;
    const std::uint8_t computed = crc8(std::span<const std::uint8_t>(p, header + length));
    if (computed != p[total - 1]) {
      fail(DecodeErrorKind::checksum, static_cast<std::uint32_t>(length), p[total - 1], computed);
      continue;
    }
    frame_.long_frame = long_frame;
    frame_.body = std::span<const std::uint8_t>(p + header, length);
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
  if (p[0] == kFlagLong && end_ - begin_ >= 3) length |= static_cast<std::uint32_t>(p[2]) << 8;
  fail(DecodeErrorKind::truncated, length);
  result.frame = scan();
  return result;
}

void FrameDecoder::reset() noexcept {
  begin_ = end_ = drop_ = 0;
  in_garbage_ = false;
}

}  // namespace tripodal::board
