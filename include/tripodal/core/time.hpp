// Time as the whole framework counts it: integer nanoseconds since the epoch of the clock in use.
// Everything that needs the time receives it as an argument or from an injected Clock, so a
// simulation or a trace replay runs faster than real time and repeats exactly.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace tripodal {

/// A span of time. Integer nanoseconds keep stepping exact and deterministic.
using Duration = std::chrono::nanoseconds;

/// A point in time, as the duration since the epoch of the clock that produced it.
using Time = std::chrono::nanoseconds;

/// Seconds (as a double) of a duration; for reports and SI-unit arithmetic.
[[nodiscard]] constexpr double to_seconds(Duration d) noexcept {
  return std::chrono::duration<double>(d).count();
}

/// The largest magnitude from_seconds converts exactly enough: 9e9 s (285 years); a Duration of
/// 64-bit nanoseconds ends at 9.22e9 s.
inline constexpr double kMaxSeconds = 9.0e9;

/// A duration from seconds, rounded to the nearest nanosecond. Saturates at +-kMaxSeconds (NaN
/// gives 0): seconds read from a file can be anything, and converting a double beyond the range
/// of the integer is undefined behaviour (found by fuzzing event scripts).
[[nodiscard]] constexpr Duration from_seconds(double seconds) noexcept {
  if (seconds != seconds) return Duration{0};
  const double s = seconds > kMaxSeconds ? kMaxSeconds : seconds < -kMaxSeconds ? -kMaxSeconds : seconds;
  return std::chrono::round<Duration>(std::chrono::duration<double>(s));
}

/// digits for format_seconds: as many decimals as the duration needs to be exact (at most 9).
inline constexpr int kExactDigits = -1;

/// Seconds of a duration as text, without a unit, for logs, reports and drawings: `digits`
/// decimals rounded half away from zero (format_seconds(1234567891ns) is "1.235"), or with
/// kExactDigits the exact value without trailing zeros ("2.5", "1", "-0.000001").
[[nodiscard]] std::string format_seconds(Duration d, int digits = 3);

}  // namespace tripodal
