// Guard expressions (docs/net-format.md): an expression that parses reparses from its own text to
// the same identifiers; one that does not has its column inside the text (or just past its end).
#include <vector>

#include "../fuzz_target.hpp"
#include "tripodal/core/guard.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  const std::string_view text = fuzz::as_text(bytes);
  try {
    const Guard g = Guard::parse(text);
    const Guard again = Guard::parse(g.text());
    fuzz::require(again.identifiers() == g.identifiers(), "a guard reparses from its text", g.text());
  } catch (const GuardSyntaxError& e) {
    fuzz::require(e.column() >= 1 && static_cast<std::size_t>(e.column()) <= text.size() + 1,
                  "a guard syntax error has a column within the text", e.what());
  }
}
