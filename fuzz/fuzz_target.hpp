// The fuzzing harness's one seam (docs/fuzzing.md): a fuzz target is a function taking bytes,
// declared with TRIPODAL_FUZZ_TARGET, and the checks every parser's target shares: a rejected
// input must carry a location, a property that fails ends the run with a message libFuzzer keeps.
// Built only with -DTRIPODAL_FUZZ=ON (clang, libFuzzer, ASan + UBSan); never installed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "tripodal/core/diagnostic.hpp"

namespace tripodal::fuzz {

/// One input, as libFuzzer hands it over.
using Bytes = std::span<const std::uint8_t>;

/// The input as text (parsers of text formats take a string_view).
[[nodiscard]] inline std::string_view as_text(Bytes bytes) noexcept {
  return {reinterpret_cast<const char*>(bytes.data()), bytes.size()};
}

/// Ends the run when a property does not hold: prints `what` (and `detail`) and aborts, which
/// libFuzzer reports as a crash and saves the input as crash-<sha1>.
void require(bool ok, std::string_view what, std::string_view detail = {});

/// The property every loader's rejection must have: each error names the file it came from and
/// a place in it, a line (FILE:LINE:COL) or a byte ("at byte N" for binary formats). An empty
/// `file` accepts any non-empty name (loaders that report errors inside the files they include).
void require_located(const ConfigError& error, std::string_view file);

}  // namespace tripodal::fuzz

/// Defines the target: `TRIPODAL_FUZZ_TARGET(bytes) { ...parse bytes, check properties... }`.
/// Exceptions a parser documents (ConfigError and friends) are caught by the body; anything that
/// escapes it is a finding, as is a sanitizer report or a failed require().
#define TRIPODAL_FUZZ_TARGET(bytes)                                                        \
  static void tripodal_fuzz_one_input(tripodal::fuzz::Bytes bytes);                        \
  extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {      \
    tripodal_fuzz_one_input(tripodal::fuzz::Bytes(data, size));                            \
    return 0;                                                                              \
  }                                                                                        \
  static void tripodal_fuzz_one_input(tripodal::fuzz::Bytes bytes)
