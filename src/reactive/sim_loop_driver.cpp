#include "sim_loop_driver.hpp"

#include <stdexcept>

namespace tripodal {

void SimLoopDriver::add(ControlLoop& loop) {
  entries_.push_back({[&loop](Time now) { (void)loop.step(now); }, loop.period(), clock_.now()});
}

void SimLoopDriver::add(Duration period, Step step) {
  if (period <= Duration{0}) throw std::invalid_argument("SimLoopDriver: a period must be > 0");
  entries_.push_back({std::move(step), period, clock_.now()});
}

std::size_t SimLoopDriver::run_until(Time until) {
  std::size_t steps = 0;
  for (;;) {
    Entry* next = nullptr;
    for (Entry& e : entries_) {
      if (e.next <= until && (next == nullptr || e.next < next->next)) next = &e;
    }
    if (next == nullptr) break;
    const Time t = next->next;
    clock_.set(t);
    if (before_instant_ && (!instant_ || *instant_ < t)) {
      before_instant_(t);
      instant_ = t;
    }
    next->step(t);
    next->next += next->period;
    ++steps;
  }
  clock_.set(until);
  return steps;
}

}  // namespace tripodal
