// The control board's byte stream (docs/board-protocol.md): any bytes at all go through the
// streaming FrameDecoder. Properties: the frames found do not depend on how the stream is cut
// into reads; every byte is accounted for; each frame's body re-encodes into a frame that decodes
// to the same body; requests and responses split without reading past their bodies. The first
// byte picks the dialect (protocol_profile.hpp: the thesis's and tripodal-v1's Length rules, each
// checksum, CheckSumEn optional) and the side (requests or responses).
#include <algorithm>
#include <array>
#include <cstdint>
#include <vector>

#include "../fuzz_target.hpp"
#include "tripodal/board/commands.hpp"
#include "tripodal/board/frame.hpp"
#include "tripodal/board/protocol_profile.hpp"

namespace {

using Frames = std::vector<std::vector<std::uint8_t>>;

Frames decode(tripodal::board::FrameDecoder& decoder, tripodal::fuzz::Bytes bytes, std::size_t chunk) {
  Frames frames;
  for (std::size_t i = 0; i < bytes.size(); i += chunk) {
    decoder.feed(bytes.subspan(i, std::min(chunk, bytes.size() - i)),
                 [&](const tripodal::board::FrameView& f) { frames.emplace_back(f.body.begin(), f.body.end()); });
  }
  return frames;
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  using namespace tripodal::board;
  if (bytes.empty()) return;
  const std::array<FrameFormat, 6> formats{
      FrameFormat{0x10, 0x50, 0xA8, LengthRule::cmd_payload, ChecksumKind::crc8_smbus, false, 512, 255},
      kTripodalV1Format,
      FrameFormat{0x10, 0x50, 0xA8, LengthRule::cmd_payload, ChecksumKind::sum8, false, 512, 255},
      FrameFormat{0x10, 0x50, 0xA8, LengthRule::type_cmd_payload, ChecksumKind::xor8, false, 512, 255},
      FrameFormat{0x00, 0x40, 0xA8, LengthRule::cmd_payload, ChecksumKind::none, false, 512, 255},
      FrameFormat{0x10, 0x50, 0xA8, LengthRule::cmd_payload, ChecksumKind::crc8_smbus, true, 300, 100}};
  const FrameFormat& format = formats[(bytes[0] >> 4) % formats.size()];
  const FrameSide side = (bytes[0] & 0x80U) != 0 ? FrameSide::requests : FrameSide::responses;
  FrameDecoder whole(format, side);
  const Frames frames = decode(whole, bytes, bytes.size());
  // The same stream in reads of 1 to 16 bytes, as a serial port hands it over.
  FrameDecoder pieces(format, side);
  const Frames again = decode(pieces, bytes, 1 + bytes[0] % 16);
  fuzz::require(frames == again, "the frames found do not depend on the reads' sizes");
  fuzz::require(whole.stats().bytes == bytes.size(), "every byte fed is counted");
  fuzz::require(whole.stats().frames == frames.size(), "every frame delivered is counted");

  std::array<std::uint8_t, kMaxFrameBytes> out{};
  for (const std::vector<std::uint8_t>& body : frames) {
    fuzz::require(!body.empty() && body.size() <= format.max_length + 1U, "a frame's body is 1 to max_length (+ TYPE) bytes");
    // The thesis's rule leaves a request's TYPE (or an echo's) out of Length.
    const bool typed = format.length_rule == LengthRule::cmd_payload && (side == FrameSide::requests || body[0] == format.type_byte);
    const std::size_t n = encode_frame(body, out, format, typed ? 1 : 0);
    fuzz::require(n > 0, "a decoded body encodes");
    FrameDecoder check(format, side);
    const Frames one = decode(check, std::span<const std::uint8_t>(out.data(), n), n);
    fuzz::require(one.size() == 1 && one[0] == body, "an encoded body decodes to itself");
    if (const std::optional<Response> r = parse_response(body)) {
      fuzz::require(r->payload.size() + 1 == body.size(), "a response's payload is the body after Resp");
    }
    if (const std::optional<Request> r = parse_request(body)) {
      fuzz::require(r->payload.size() + 2 == body.size(), "a request's payload is the body after TYPE and CMD");
    }
  }
}
