#include "tripodal/core/clock.hpp"

namespace tripodal {

SteadyClock::SteadyClock() noexcept : start_(std::chrono::steady_clock::now()) {}

Time SteadyClock::now() const noexcept {
  return std::chrono::duration_cast<Time>(std::chrono::steady_clock::now() - start_);
}

void SimClock::advance(Duration d) noexcept {
  if (d.count() > 0) now_.fetch_add(d.count(), std::memory_order_acq_rel);
}

bool SimClock::set(Time t) noexcept {
  Time::rep current = now_.load(std::memory_order_acquire);
  while (t.count() >= current) {
    if (now_.compare_exchange_weak(current, t.count(), std::memory_order_acq_rel)) return true;
  }
  return false;
}

}  // namespace tripodal
