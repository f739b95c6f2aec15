// format_seconds: the one way logs, reports, drawings and tools print a Time or a Duration.
#include "tripodal/core/time.hpp"

#include <catch2/catch.hpp>
#include <limits>

using namespace tripodal;
using namespace std::chrono_literals;

TEST_CASE("format_seconds prints fixed decimals, rounded half away from zero") {
  CHECK(format_seconds(1234567891ns) == "1.235");
  CHECK(format_seconds(1234567891ns, 6) == "1.234568");
  CHECK(format_seconds(1234567891ns, 0) == "1");
  CHECK(format_seconds(1500ms, 0) == "2");
  CHECK(format_seconds(0ns) == "0.000");
  CHECK(format_seconds(2s, 1) == "2.0");
  CHECK(format_seconds(-2500ms, 1) == "-2.5");
  CHECK(format_seconds(-2500ms, 0) == "-3");
  // A value that rounds to zero carries no sign.
  CHECK(format_seconds(-1ns) == "0.000");
  // Nine decimals (or more asked) show every nanosecond.
  CHECK(format_seconds(1ns, 9) == "0.000000001");
  CHECK(format_seconds(1ns, 12) == "0.000000001");
}

TEST_CASE("format_seconds with kExactDigits prints the exact value without trailing zeros") {
  CHECK(format_seconds(2500ms, kExactDigits) == "2.5");
  CHECK(format_seconds(1s, kExactDigits) == "1");
  CHECK(format_seconds(100ms, kExactDigits) == "0.1");
  CHECK(format_seconds(-1us, kExactDigits) == "-0.000001");
  CHECK(format_seconds(0ns, kExactDigits) == "0");
  // Integer arithmetic: no double rounding even for large times.
  CHECK(format_seconds(Duration{1'000'000'000'123'456'789}, kExactDigits) == "1000000000.123456789");
  CHECK(format_seconds(Duration{std::numeric_limits<std::int64_t>::min()}, kExactDigits) == "-9223372036.854775808");
}

TEST_CASE("from_seconds saturates at kMaxSeconds and maps NaN to zero") {
  CHECK(from_seconds(1.5) == 1500ms);
  CHECK(from_seconds(1e300) == from_seconds(kMaxSeconds));
  CHECK(from_seconds(-1e300) == -from_seconds(kMaxSeconds));
  CHECK(from_seconds(std::numeric_limits<double>::infinity()) == from_seconds(kMaxSeconds));
  CHECK(from_seconds(std::numeric_limits<double>::quiet_NaN()) == Duration{0});
  CHECK(to_seconds(from_seconds(kMaxSeconds)) == kMaxSeconds);
}
