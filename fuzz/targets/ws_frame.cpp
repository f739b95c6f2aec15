// The monitor server's WebSocket frames from clients (src/monitor/wire.cpp, RFC 6455 5.2): any
// bytes, read frame after frame from one connection's buffer as the server reads them.
// Properties: a frame never uses more bytes than it was given and is not complete one byte
// earlier; the payload limit holds; an unmasked client frame or reserved bits are refused with
// a reason; a decoded frame, masked again with any key, decodes to the same frame.
#include <cstdint>
#include <string>
#include <string_view>

#include "../fuzz_target.hpp"
#include "tripodal_monitor_internal/wire.hpp"

namespace {

constexpr std::size_t kMaxPayload = 1024;

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  using monitor::WsParse;
  std::string_view buffer = fuzz::as_text(bytes);
  for (int frames = 0; frames < 16 && !buffer.empty(); ++frames) {
    const WsParse p = monitor::parse_ws_frame(buffer, kMaxPayload);
    if (p.status == WsParse::Status::error) {
      fuzz::require(!p.error.empty(), "a refused frame says why");
      return;
    }
    if (p.status == WsParse::Status::incomplete) {
      fuzz::require(p.consumed == 0, "an unfinished frame consumes nothing");
      return;
    }
    fuzz::require(p.consumed >= 6 && p.consumed <= buffer.size(), "a frame uses header, mask and payload of the bytes given");
    fuzz::require(p.frame.payload.size() <= kMaxPayload, "the payload limit holds");
    const auto b0 = static_cast<std::uint8_t>(buffer[0]);
    fuzz::require((b0 & 0x70U) == 0, "reserved bits are refused");
    fuzz::require((static_cast<std::uint8_t>(buffer[1]) & 0x80U) != 0, "unmasked client frames are refused");
    const WsParse shorter = monitor::parse_ws_frame(buffer.substr(0, p.consumed - 1), kMaxPayload);
    fuzz::require(shorter.status == WsParse::Status::incomplete, "a frame is not complete one byte early");
    // Masked again (ws_client_frame writes fin frames with the shortest length encoding).
    if (p.frame.fin) {
      const std::string again = monitor::ws_client_frame(p.frame.opcode, p.frame.payload, 0xA5C3F00FU);
      const WsParse q = monitor::parse_ws_frame(again, kMaxPayload);
      fuzz::require(q.status == WsParse::Status::complete && q.consumed == again.size() &&
                        q.frame.opcode == p.frame.opcode && q.frame.payload == p.frame.payload && q.frame.fin,
                    "a decoded frame re-encodes to itself");
    }
    buffer.remove_prefix(p.consumed);
  }
}
