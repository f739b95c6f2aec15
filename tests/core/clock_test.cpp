#include "tripodal/core/clock.hpp"

#include <catch2/catch.hpp>
#include <thread>

#include "tripodal/version.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

TEST_CASE("SimClock moves only when told and never backwards") {
  SimClock clock(Time{5ms});
  CHECK(clock.now() == Time{5ms});
  clock.advance(10ms);
  CHECK(clock.now() == Time{15ms});
  clock.advance(-3ms);
  CHECK(clock.now() == Time{15ms});
  CHECK_FALSE(clock.set(Time{1ms}));
  CHECK(clock.now() == Time{15ms});
  CHECK(clock.set(Time{20ms}));
  CHECK(clock.now() == Time{20ms});
}

TEST_CASE("SteadyClock is monotonic and starts near zero") {
  SteadyClock clock;
  const Time a = clock.now();
  std::this_thread::sleep_for(1ms);
  const Time b = clock.now();
  CHECK(a >= Time{0ns});
  CHECK(b - a >= 1ms);
}

TEST_CASE("wall_duration: how long a clock's duration lasts on the wall, the timeout an OS wait needs") {
  // A poll() that must end by a deadline of a sped-up clock waits the wall time to it, not the
  // clock's own duration (the board simulator at --speed 4 once waited 4 ms per 1 ms pass).
  CHECK(ScaledClock(4.0).wall_duration(4ms) == 1ms);
  CHECK(ScaledClock(0.5).wall_duration(1ms) == 2ms);
  CHECK(ScaledClock(1.0).wall_duration(3ms) == 3ms);
  CHECK(SteadyClock().wall_duration(3ms) == 3ms);
  CHECK(SimClock().wall_duration(3ms) == 3ms);
}

TEST_CASE("seconds conversions round to the nearest nanosecond") {
  CHECK(to_seconds(1500ms) == Approx(1.5));
  CHECK(from_seconds(0.25) == 250ms);
  CHECK(from_seconds(1e-9) == 1ns);
}

TEST_CASE("version string matches the CMake project version") {
  CHECK(std::string(version_string()) == TRIPODAL_VERSION);
}
