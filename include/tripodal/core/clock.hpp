// The injectable clock: a steady clock on a robot, a simulated clock in tests, the simulator and
// trace replay. Nothing in tripodal reads the wall clock directly; it asks a Clock.
#pragma once

#include <atomic>

#include "tripodal/core/time.hpp"

namespace tripodal {

/// Source of the current time for every component. Implementations are thread-safe.
class Clock {
 public:
  virtual ~Clock() = default;
  /// The current time since this clock's epoch; monotonic (never goes backwards).
  [[nodiscard]] virtual Time now() const noexcept = 0;
  /// Blocks the calling thread until now() >= deadline. The default yields in a loop (right for
  /// a clock another thread advances); SteadyClock sleeps on the OS's absolute monotonic timer.
  virtual void sleep_until(Time deadline) const noexcept;
  /// How long `d` of this clock lasts on the wall clock: the timeout to hand an OS wait (poll, a
  /// condition variable) that must end by a deadline of this clock. The default is `d` itself.
  [[nodiscard]] virtual Duration wall_duration(Duration d) const noexcept { return d; }
};

/// Monotonic real time (std::chrono::steady_clock); its epoch is the moment it was constructed.
class SteadyClock final : public Clock {
 public:
  SteadyClock() noexcept;
  [[nodiscard]] Time now() const noexcept override;
  /// Absolute-deadline sleep (clock_nanosleep TIMER_ABSTIME on CLOCK_MONOTONIC where available),
  /// so a periodic loop does not accumulate drift from relative sleeps.
  void sleep_until(Time deadline) const noexcept override;

 private:
  std::chrono::steady_clock::time_point start_;
};

/// The steady clock sped up `speed` times: the clock of a simulated robot on the wall-clock runtime
/// (`tripodal run --realtime SPEED`). now() is `speed` times the steady time since construction;
/// sleep_until() sleeps on the steady clock's absolute timer until the matching wall instant, so a
/// loop at a period P of this clock wakes every P / speed of wall time without drift.
class ScaledClock final : public Clock {
 public:
  /// `speed` > 0 (anything else counts as 1).
  explicit ScaledClock(double speed = 1.0) noexcept : speed_(speed > 0.0 ? speed : 1.0) {}
  [[nodiscard]] Time now() const noexcept override;
  void sleep_until(Time deadline) const noexcept override;
  /// `d` / speed: at 4x, 4 ms of this clock pass in 1 ms of wall time.
  [[nodiscard]] Duration wall_duration(Duration d) const noexcept override;
  [[nodiscard]] double speed() const noexcept { return speed_; }

 private:
  SteadyClock wall_;
  double speed_;
};

/// Simulated time that only moves when told to; starts at `start` (default 0).
class SimClock final : public Clock {
 public:
  explicit SimClock(Time start = Time{}) noexcept : now_(to_ns(start)) {}
  [[nodiscard]] Time now() const noexcept override { return time_from_ns(now_.load(std::memory_order_acquire)); }
  /// Moves the time forward by `d` (a negative `d` is ignored: the clock is monotonic).
  void advance(Duration d) noexcept;
  /// Sets the time to `t` if `t` is not earlier than now; returns false (and keeps now) otherwise.
  bool set(Time t) noexcept;

 private:
  std::atomic<Time::rep> now_;
};

}  // namespace tripodal
