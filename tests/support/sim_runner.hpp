// Test support: a Simulator and control loops stepped together on one SimClock, without a robot,
// for the simulator's tests (a Robot on the simulator does the same in Robot::run_until). Every
// physics period the simulator advances to t first (its sensors sample at t), then the loop cycles
// due by t run on those readings and write the wheel commands applied over the next period.
// Needs the reactive area's internal target (tripodal_reactive_internal) for its scheduler.
#pragma once

#include <algorithm>
#include <chrono>
#include <cstddef>

#include "tripodal/reactive/control_loop.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal_reactive_internal/sim_loop_driver.hpp"

namespace tripodal::test {

class SimRunner final {
 public:
  /// The clock is moved to the simulator's time if it is behind.
  SimRunner(sim::Simulator& sim, SimClock& clock, Duration physics_period = std::chrono::milliseconds(10))
      : sim_(sim),
        clock_(clock),
        driver_(clock),
        period_(physics_period.count() > 0 ? physics_period : std::chrono::milliseconds(10)) {
    clock_.set(sim_.now());
  }
  /// Adds a loop (not owned); its first cycle is at the current time.
  void add(ControlLoop& loop) { driver_.add(loop); }
  /// Paces every physics period to wall time (nullptr: as fast as possible). Not owned.
  void set_pacer(sim::RealtimePacer* pacer) noexcept { pacer_ = pacer; }
  /// Runs until `until`; returns the number of loop cycles run.
  std::size_t run_until(Time until) {
    // Cycles due now run first, on the readings the simulator sampled at this time.
    std::size_t cycles = driver_.run_until(std::max(clock_.now(), sim_.now()));
    while (sim_.now() < until) {
      const Time t = std::min(sim_.now() + period_, until);
      sim_.step_until(t);
      cycles += driver_.run_until(t);
      if (pacer_ != nullptr) pacer_->pace(t);
    }
    return cycles;
  }
  std::size_t run_for(Duration d) { return run_until(clock_.now() + d); }

 private:
  sim::Simulator& sim_;
  SimClock& clock_;
  SimLoopDriver driver_;
  Duration period_;
  sim::RealtimePacer* pacer_ = nullptr;
};

}  // namespace tripodal::test
