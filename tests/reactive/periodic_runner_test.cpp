// The wall-clock runtime's periodic thread (reactive/periodic_runner.hpp): absolute deadlines, the
// overrun budget, the run of overruns that raises a deadline fault, and the thread options asked of
// an unprivileged process. The clocks are the test's own (JumpClock-like), so what is checked does
// not depend on the machine's load.
#include "tripodal/reactive/periodic_runner.hpp"

#include <atomic>
#include <catch2/catch.hpp>
#include <string>
#include <thread>
#include <vector>

#include "tripodal/reactive/control_loop.hpp"
#include "tripodal_reactive_internal/sim_loop_driver.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

// Time moves only when a cycle says so (sleep_until jumps to the deadline): the cycles' lengths are
// exactly what the test makes them.
class StepClock final : public Clock {
 public:
  [[nodiscard]] Time now() const noexcept override { return time_from_ns(now_.load()); }
  void sleep_until(Time deadline) const noexcept override {
    if (to_ns(deadline) > now_.load()) now_.store(to_ns(deadline));
  }
  void spend(Duration d) const noexcept { now_.fetch_add(d.count()); }

 private:
  mutable std::atomic<std::int64_t> now_{0};
};

}  // namespace

TEST_CASE("A periodic thread runs at absolute deadlines and counts overruns beyond its budget", "[threads]") {
  StepClock clock;
  std::vector<Time> woke;
  std::atomic<int> cycles{0};
  LoopTimingOptions o;
  o.budget = 3ms;  // a cycle may end up to 3 ms after its deadline
  // Cycle 3 takes 2.5 ms (within budget), cycle 5 takes 4.5 ms (an overrun, ticks skipped).
  PeriodicRunner runner(
      "motion", 1ms, clock,
      [&](Time now) {
        woke.push_back(now);
        const int i = cycles.fetch_add(1);
        if (i == 3) clock.spend(2500us);
        if (i == 5) clock.spend(4500us);
      },
      o);
  CHECK(runner.budget() == 3ms);
  runner.start();
  while (cycles.load() < 12) std::this_thread::yield();
  runner.stop();
  REQUIRE(woke.size() >= 12);
  CHECK(woke[0] == Time{1ms});
  CHECK(woke[3] == Time{4ms});
  CHECK(woke[4] == Time{7ms});  // 4 ms + 2.5 ms ended at 6.5 ms: tick 5 and 6 skipped
  CHECK(woke[5] == Time{8ms});
  CHECK(woke[6] == Time{13ms});  // 8 + 4.5 = 12.5 ms
  const LoopStatistics& s = runner.statistics();
  CHECK(runner.overruns() == 1);
  CHECK(s.overruns() == 1);
  CHECK(s.skipped_ticks() == 2 + 4);
  CHECK(runner.deadline_faults() == 0);  // not asked for
}

TEST_CASE("A starved periodic thread raises one deadline fault per run of overruns", "[threads]") {
  // The loop's work made slow by an injected hook: cycles 10..19 take two periods each, then it
  // recovers, then cycles 30..32 are slow again (a run shorter than the limit: no fault).
  StepClock clock;
  std::atomic<int> cycles{0};
  LoopTimingOptions o;
  o.deadline_overruns = 4;
  PeriodicRunner runner(
      "motion", 1ms, clock,
      [&](Time) {
        const int i = cycles.fetch_add(1);
        if ((i >= 10 && i < 20) || (i >= 30 && i < 33)) clock.spend(2ms);
      },
      o);
  runner.start();
  while (cycles.load() < 40) std::this_thread::yield();
  runner.stop();
  CHECK(runner.overruns() == 13);
  CHECK(runner.deadline_faults() == 1);  // ten in a row: one fault, not two
  CHECK(runner.statistics().max_execution() == 2ms);
}

TEST_CASE("A periodic thread refuses a bad period and runs unprivileged with a one-line warning", "[threads]") {
  SteadyClock clock;
  CHECK_THROWS_WITH(PeriodicRunner("x", 0ms, clock, [](Time) {}), Catch::Contains("'x': the period must be > 0"));
  CHECK_THROWS_WITH(PeriodicRunner("x", 1ms, clock, nullptr), Catch::Contains("no cycle"));
  std::atomic<int> cycles{0};
  LoopTimingOptions o;
  o.realtime_priority = 80;
  o.cpu = 0;  // (not lock_memory: mlockall would lock this whole test process, sanitizer shadow included)
  PeriodicRunner runner(
      "motion", 1ms, clock, [&](Time) { cycles.fetch_add(1); }, o);
  runner.start();
  CHECK_THROWS_AS(runner.start(), std::logic_error);
  while (cycles.load() < 5) std::this_thread::yield();
  runner.stop();
  runner.stop();  // idempotent
  const ThreadSetup& s = runner.setup();
  INFO("granted: SCHED_FIFO " << s.realtime << ", pinned " << s.pinned << "; " << s.warning);
  CHECK_FALSE(s.memory_locked);
  if (s.realtime && s.pinned) {
    CHECK(s.warning.empty());
  } else {
    CHECK(s.warning.find("warning: loop 'motion': not permitted: ") == 0);
    CHECK(s.warning.find('\n') == std::string::npos);
    CHECK(s.warning.find(s.realtime ? "CPU 0" : "SCHED_FIFO 80") != std::string::npos);
    CHECK(s.warning.find("running with normal scheduling") != std::string::npos);
  }
}

TEST_CASE("The simulated-time scheduler runs the instant's hook once, then the entries due in the order added") {
  SimClock clock;
  SimLoopDriver driver(clock);
  std::vector<std::string> log;
  driver.set_before_instant([&](Time t) { log.push_back("advance " + format_seconds(t.time_since_epoch())); });
  driver.add(50ms, [&](Time t) { log.push_back("sequencing " + format_seconds(t.time_since_epoch())); });
  driver.add(20ms, [&](Time t) { log.push_back("loop " + format_seconds(t.time_since_epoch())); });
  CHECK_THROWS_WITH(driver.add(0ms, [](Time) {}), Catch::Contains("a period must be > 0"));
  CHECK(driver.run_until(Time{100ms}) == 3 + 6);
  CHECK(clock.now() == Time{100ms});
  CHECK(log == std::vector<std::string>{"advance 0.000", "sequencing 0.000", "loop 0.000", "advance 0.020", "loop 0.020",
                                        "advance 0.040", "loop 0.040", "advance 0.050", "sequencing 0.050", "advance 0.060",
                                        "loop 0.060", "advance 0.080", "loop 0.080", "advance 0.100", "sequencing 0.100",
                                        "loop 0.100"});
  log.clear();
  CHECK(driver.run_for(10ms) == 0);  // nothing due before 0.120
  CHECK(log.empty());
  CHECK(clock.now() == Time{110ms});
}
