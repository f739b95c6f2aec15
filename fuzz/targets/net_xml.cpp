// Native XML nets (docs/net-format.md): a net that loads saves and reloads to the same net (the
// saved text is a fixed point); a net that does not load has every error located.
#include "../fuzz_target.hpp"
#include "tripodal/core/net_loader.hpp"

namespace {

// Loads, saves, reloads and saves again: both saved texts must be equal.
void round_trip(tripodal::fuzz::Bytes bytes, tripodal::NetFormat format, const char* name) {
  using namespace tripodal;
  Diagnostics d;
  LoadOptions options;
  options.format = format;
  const auto net = load_net_from_string(fuzz::as_text(bytes), name, d, options);
  if (!net) {
    fuzz::require(d.has_errors(), "a net that does not load reports an error");
    fuzz::require_located(ConfigError(d), name);
    return;
  }
  std::string saved;
  try {
    saved = net_to_string(*net, format);
  } catch (const ConfigError&) {
    return;  // documented: not every net can be represented in every format
  }
  Diagnostics d2;
  const auto again = load_net_from_string(saved, "saved", d2, options);
  fuzz::require(again.has_value(), "a saved net loads again", d2.str() + "\n--- saved:\n" + saved);
  fuzz::require(net_to_string(*again, format) == saved, "saving a reloaded net gives the same text", saved);
}

}  // namespace

#ifndef TRIPODAL_FUZZ_NET_FORMAT
#define TRIPODAL_FUZZ_NET_FORMAT native_xml
#endif

TRIPODAL_FUZZ_TARGET(bytes) {
  round_trip(bytes, tripodal::NetFormat::TRIPODAL_FUZZ_NET_FORMAT, "fuzz.net");
}
