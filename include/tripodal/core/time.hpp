// Time as the whole framework counts it: integer nanoseconds since the epoch of the clock in use.
// Everything that needs the time receives it as an argument or from an injected Clock, so a
// simulation or a trace replay runs faster than real time and repeats exactly. A point in time
// (Time) and a span (Duration) are distinct types: t1 - t0 is a Duration, t + d a Time, t1 + t0
// does not compile.
#pragma once

#include <chrono>
#include <cstdint>
#include <string>

namespace tripodal {

/// A span of time. Integer nanoseconds keep stepping exact and deterministic.
using Duration = std::chrono::nanoseconds;

/// The epoch every Time counts from: that of the injected Clock in use (core/clock.hpp) — the
/// start of a simulation, a trace's own stamps, or the steady clock's. Not a clock itself: it has
/// no now(); it only makes Time a point, not a span.
struct TimeEpoch {
  using rep = Duration::rep;
  using period = Duration::period;
  using duration = Duration;
  using time_point = std::chrono::time_point<TimeEpoch, Duration>;
  static constexpr bool is_steady = true;
};

/// A point in time: the duration since the epoch of the clock that produced it.
using Time = TimeEpoch::time_point;

/// Seconds (as a double) of a duration; for reports and SI-unit arithmetic.
[[nodiscard]] constexpr double to_seconds(Duration d) noexcept {
  return std::chrono::duration<double>(d).count();
}

/// Seconds (as a double) since the epoch; for reports, logs and file formats.
[[nodiscard]] constexpr double to_seconds(Time t) noexcept { return to_seconds(t.time_since_epoch()); }

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

/// The time `seconds` after the epoch, rounded to the nearest nanosecond.
[[nodiscard]] constexpr Time time_from_seconds(double seconds) noexcept { return Time{from_seconds(seconds)}; }

/// Nanoseconds since the epoch, for file formats and atomics; time_from_ns() is its inverse.
[[nodiscard]] constexpr std::int64_t to_ns(Time t) noexcept { return t.time_since_epoch().count(); }
[[nodiscard]] constexpr Time time_from_ns(std::int64_t ns) noexcept { return Time{Duration{ns}}; }

/// digits for format_seconds: as many decimals as the duration needs to be exact (at most 9).
inline constexpr int kExactDigits = -1;

/// Seconds of a duration as text, without a unit, for logs, reports and drawings: `digits`
/// decimals rounded half away from zero (format_seconds(1234567891ns) is "1.235"), or with
/// kExactDigits the exact value without trailing zeros ("2.5", "1", "-0.000001").
[[nodiscard]] std::string format_seconds(Duration d, int digits = 3);
/// format_seconds of the time since the epoch.
[[nodiscard]] inline std::string format_seconds(Time t, int digits = 3) { return format_seconds(t.time_since_epoch(), digits); }

}  // namespace tripodal
