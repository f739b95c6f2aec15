#include "tripodal/core/time.hpp"

#include <fmt/format.h>

#include <cstdlib>

namespace tripodal {

std::string format_seconds(Duration d, int digits) {
  // Integer arithmetic on the nanoseconds, so that the text is the value a Time holds and not the
  // nearest double (0.1 s stays "0.1", 1e9 s keeps its last digits).
  const std::int64_t ns = d.count();
  const bool negative = ns < 0;
  // The magnitude as unsigned, which also holds the most negative count.
  std::uint64_t mag = negative ? 0U - static_cast<std::uint64_t>(ns) : static_cast<std::uint64_t>(ns);
  int decimals = digits;
  if (digits < 0 || digits > 9) {
    decimals = 9;
  } else {
    std::uint64_t unit = 1;
    for (int i = digits; i < 9; ++i) unit *= 10U;
    mag = (mag + unit / 2U) / unit * unit;  // half away from zero, as a printed table expects
  }
  const std::uint64_t whole = mag / 1'000'000'000U;
  std::string frac = fmt::format("{:09d}", mag % 1'000'000'000U);
  frac.resize(static_cast<std::size_t>(decimals));
  if (digits < 0) {
    while (!frac.empty() && frac.back() == '0') frac.pop_back();
  }
  const bool zero = whole == 0 && frac.find_first_not_of('0') == std::string::npos;
  return fmt::format("{}{}{}{}", negative && !zero ? "-" : "", whole, frac.empty() ? "" : ".", frac);
}

}  // namespace tripodal
