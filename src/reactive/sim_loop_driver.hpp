// The reactive layer's simulated-time scheduler, private to the framework: Robot::run_until steps
// its hardware, sequencing loop and control loops with it, and the tests' SimRunner the simulator
// with loops. Reached as "tripodal_reactive_internal/sim_loop_driver.hpp" (never installed): an
// application runs a simulated robot through Robot::run_until.
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/reactive/control_loop.hpp"

namespace tripodal {

/// Steps periodic work on the caller's thread, each entry at its own deadlines
/// (first + k * period), in time order, ties in the order the entries were added. At each instant
/// where something is due, the before-instant hook runs first (a simulator advanced to it).
class SimLoopDriver final {
 public:
  using Step = std::function<void(Time now)>;
  explicit SimLoopDriver(SimClock& clock) noexcept : clock_(clock) {}
  /// Adds `loop` (not owned); its first cycle is at the clock's current time.
  void add(ControlLoop& loop);
  /// Adds periodic work (a sequencing loop): `step` at the clock's current time, then every
  /// `period` (> 0; std::invalid_argument otherwise).
  void add(Duration period, Step step);
  /// Runs before the entries due at each instant (nullptr: none).
  void set_before_instant(Step hook) { before_instant_ = std::move(hook); }
  /// Advances the clock to `until`, running every step that falls due on the way; the clock ends
  /// at `until`. Returns the number of steps run. What a step throws propagates (the loops' own
  /// steps never throw).
  std::size_t run_until(Time until);
  std::size_t run_for(Duration d) { return run_until(clock_.now() + d); }

 private:
  struct Entry {
    Step step;
    Duration period;
    Time next;
  };
  SimClock& clock_;
  std::vector<Entry> entries_;
  Step before_instant_;
  std::optional<Time> instant_;  // the last instant the hook ran at
};

}  // namespace tripodal
