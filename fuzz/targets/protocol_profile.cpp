// A control board's protocol profile (board/protocol_profile.hpp): any text is either a profile
// whose look-ups agree with its command table, or located errors.
#include "../fuzz_target.hpp"
#include "tripodal/board/frame.hpp"
#include "tripodal/board/protocol_profile.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  try {
    const board::ProtocolProfile p = board::parse_protocol_profile(fuzz::as_text(bytes), "fuzz.yaml");
    for (const board::CommandSpec& c : p.commands) {
      fuzz::require(p.id(c.command) == c.id && p.command_of(c.id) == c.command, "an id and its command look each other up");
      fuzz::require(board::max_payload_bytes(c.request) + 2 <= board::kMaxLength + 1, "a request fits the buffer");
    }
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.yaml");
  }
}
