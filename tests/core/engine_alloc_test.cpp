// Proves the engine's steady-state step is allocation-free: a replaced global operator new counts
// allocations around many steps. Its own executable, so the replacement affects no other suite.
#include <catch2/catch.hpp>

#include "../support/counting_new.hpp"
#include "engine_test_nets.hpp"
#include "tripodal/core/engine.hpp"

using namespace tripodal;

TEST_CASE("steady-state steps do not allocate: firings, delays, events, bindings, outcomes") {
  const PetriNet ring = test::ring_net(100, Duration{1000});
  Engine engine(ring);
  Time now{};
  engine.step(now);
  const std::size_t before = test::allocations();
  std::size_t firings = 0;
  for (int i = 0; i < 1000; ++i) {
    now += Duration{1000};
    firings += engine.step(now).firings;
  }
  CHECK(firings == 100'000);
  CHECK(test::allocations() == before);

  const PetriNet net = test::pr_cleaning_net(1.0);
  Engine pr(net, {{"wheel_type", Value{std::string("differential")}}});
  const EventId lost = *pr.event_id("localizer.lost");
  const EventId ok = *pr.event_id("localizer.ok");
  pr.step(Time{});
  const std::size_t before_pr = test::allocations();
  Time t{};
  std::size_t dropped = 0;
  for (int i = 0; i < 1000; ++i) {
    t += from_seconds(0.1);
    const EventId e = i % 2 == 0 ? lost : ok;
    dropped += pr.step(t, std::span<const EventId>(&e, 1)).unconsumed_events.size();
    dropped += pr.step(t, {"localizer.ok", "unknown.event"}).unconsumed_events.size();
    (void)pr.outcome();
  }
  CHECK(dropped > 0);
  CHECK(pr.outcome().outcome == Outcome::none);
  CHECK(test::allocations() == before_pr);
}
