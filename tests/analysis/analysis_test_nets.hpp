// Generated nets with known state spaces, shared by the analysis tests and benchmarks:
// Kanban (the structure of Kanban2-test001.pnml with N tokens per stage), token rings, dining
// philosophers and chains (one long sequence, for scaling).
#pragma once

#include <string>

#include "tripodal/core/petri_net.hpp"

namespace tripodal::test {

/// Kanban with `n` kanbans per stage: 16 places, 16 transitions (160 states for n = 1, 4,600 for
/// n = 2, 58,400 for n = 3, 454,475 for n = 4, 2,546,432 for n = 5).
inline PetriNet kanban_net(Tokens n) {
  PetriNet net;
  net.id = "kanban" + std::to_string(n);
  for (int i = 1; i <= 4; ++i) {
    const std::string s = std::to_string(i);
    net.add_place(Place{.id = "P" + s, .initial_tokens = n});
    net.add_place(Place{.id = "Pm" + s});
    net.add_place(Place{.id = "Pback" + s});
    net.add_place(Place{.id = "Pout" + s});
  }
  for (int i = 1; i <= 4; ++i) {
    const std::string s = std::to_string(i);
    net.add_transition(Transition{.id = "tok" + s});
    net.add_arc("Pm" + s, "tok" + s);
    net.add_arc("tok" + s, "Pout" + s);
    net.add_transition(Transition{.id = "tredo" + s});
    net.add_arc("Pm" + s, "tredo" + s);
    net.add_arc("tredo" + s, "Pback" + s);
    net.add_transition(Transition{.id = "tback" + s});
    net.add_arc("Pback" + s, "tback" + s);
    net.add_arc("tback" + s, "Pm" + s);
  }
  net.add_transition(Transition{.id = "tin4"});
  net.add_arc("P4", "tin4");
  net.add_arc("tin4", "Pm4");
  net.add_transition(Transition{.id = "tout1"});
  net.add_arc("Pout1", "tout1");
  net.add_arc("tout1", "P1");
  net.add_transition(Transition{.id = "tsynch4_23"});
  for (const char* p : {"Pout4", "P2", "P3"}) net.add_arc(p, "tsynch4_23");
  for (const char* p : {"P4", "Pm2", "Pm3"}) net.add_arc("tsynch4_23", p);
  net.add_transition(Transition{.id = "tsynch1_23"});
  for (const char* p : {"Pout2", "Pout3", "P1"}) net.add_arc(p, "tsynch1_23");
  for (const char* p : {"Pm1", "P2", "P3"}) net.add_arc("tsynch1_23", p);
  return net;
}

/// `places` places in a ring, `tokens` tokens on the first; each transition moves one token to
/// the next place. States: C(places + tokens - 1, tokens).
inline PetriNet ring_of_tokens(std::size_t places, Tokens tokens) {
  PetriNet net;
  net.id = "ring" + std::to_string(places) + "x" + std::to_string(tokens);
  for (std::size_t i = 0; i < places; ++i) {
    net.add_place(Place{.id = "p" + std::to_string(i), .initial_tokens = i == 0 ? tokens : 0});
  }
  for (std::size_t i = 0; i < places; ++i) {
    const std::string t = "t" + std::to_string(i);
    net.add_transition(Transition{.id = t});
    net.add_arc("p" + std::to_string(i), t);
    net.add_arc(t, "p" + std::to_string((i + 1) % places));
  }
  return net;
}

/// Dining philosophers, each taking the left fork then the right one: deadlocks when every
/// philosopher holds a left fork.
inline PetriNet philosophers_net(std::size_t n) {
  PetriNet net;
  net.id = "philosophers" + std::to_string(n);
  for (std::size_t i = 0; i < n; ++i) {
    const std::string s = std::to_string(i);
    net.add_place(Place{.id = "think" + s, .initial_tokens = 1});
    net.add_place(Place{.id = "fork" + s, .initial_tokens = 1});
    net.add_place(Place{.id = "left" + s});
    net.add_place(Place{.id = "eat" + s});
  }
  for (std::size_t i = 0; i < n; ++i) {
    const std::string s = std::to_string(i);
    const std::string right = "fork" + std::to_string((i + 1) % n);
    net.add_transition(Transition{.id = "takeLeft" + s});
    net.add_arc("think" + s, "takeLeft" + s);
    net.add_arc("fork" + s, "takeLeft" + s);
    net.add_arc("takeLeft" + s, "left" + s);
    net.add_transition(Transition{.id = "takeRight" + s});
    net.add_arc("left" + s, "takeRight" + s);
    net.add_arc(right, "takeRight" + s);
    net.add_arc("takeRight" + s, "eat" + s);
    net.add_transition(Transition{.id = "release" + s});
    net.add_arc("eat" + s, "release" + s);
    net.add_arc("release" + s, "think" + s);
    net.add_arc("release" + s, "fork" + s);
    net.add_arc("release" + s, right);
  }
  return net;
}

/// A process that is one long sequence: `places` places p0..p(n-1), a token on p0, immediate
/// transitions t_i moving it from p_i to p_(i+1), and p(n-1) the success outcome. Its state
/// space is linear (n states, n - 1 edges, no deadlock, the outcome reached from every state),
/// so the work to verify it should be too: the scaling benchmark and tests use it.
inline PetriNet chain_net(std::size_t places) {
  PetriNet net;
  net.id = "chain" + std::to_string(places);
  for (std::size_t i = 0; i < places; ++i) {
    net.add_place(Place{.id = "p" + std::to_string(i),
                        .initial_tokens = i == 0 ? Tokens{1} : Tokens{0},
                        .outcome = i + 1 == places ? Outcome::success : Outcome::none});
  }
  for (std::size_t i = 0; i + 1 < places; ++i) {
    const std::string t = "t" + std::to_string(i);
    net.add_transition(Transition{.id = t});
    net.add_arc("p" + std::to_string(i), t);
    net.add_arc(t, "p" + std::to_string(i + 1));
  }
  return net;
}

}  // namespace tripodal::test
