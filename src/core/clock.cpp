#include "tripodal/core/clock.hpp"

#include <cerrno>
#include <thread>
#if defined(__linux__)
#include <time.h>
#endif

namespace tripodal {

SteadyClock::SteadyClock() noexcept : start_(std::chrono::steady_clock::now()) {}

Time SteadyClock::now() const noexcept {
  return Time{std::chrono::duration_cast<Duration>(std::chrono::steady_clock::now() - start_)};
}

void Clock::sleep_until(Time deadline) const noexcept {
  while (now() < deadline) std::this_thread::yield();
}

void SteadyClock::sleep_until(Time deadline) const noexcept {
#if defined(__linux__)
  // libstdc++'s steady_clock is CLOCK_MONOTONIC: the deadline converts to that clock's timespec.
  const auto abs = std::chrono::duration_cast<std::chrono::nanoseconds>(start_.time_since_epoch()) + deadline.time_since_epoch();
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(abs.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(abs.count() % 1'000'000'000);
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
#else
  std::this_thread::sleep_until(start_ + deadline.time_since_epoch());
#endif
}

Time ScaledClock::now() const noexcept {
  return Time{Duration{static_cast<Duration::rep>(static_cast<double>(to_ns(wall_.now())) * speed_)}};
}

void ScaledClock::sleep_until(Time deadline) const noexcept {
  // The wall instant at which now() reaches the deadline (rounded up, so that now() >= deadline).
  const double wall_ns = static_cast<double>(to_ns(deadline)) / speed_;
  wall_.sleep_until(Time{Duration{static_cast<Duration::rep>(wall_ns) + 1}});
}

Duration ScaledClock::wall_duration(Duration d) const noexcept {
  return Duration{static_cast<Duration::rep>(static_cast<double>(d.count()) / speed_)};
}

void SimClock::advance(Duration d) noexcept {
  if (d.count() > 0) now_.fetch_add(d.count(), std::memory_order_acq_rel);
}

bool SimClock::set(Time t) noexcept {
  Time::rep current = now_.load(std::memory_order_acquire);
  while (to_ns(t) >= current) {
    if (now_.compare_exchange_weak(current, to_ns(t), std::memory_order_acq_rel)) return true;
  }
  return false;
}

}  // namespace tripodal
