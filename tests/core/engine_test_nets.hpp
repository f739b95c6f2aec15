// Nets built in code for the engine, simulation and benchmark tests.
#pragma once

#include <string>

#include "tripodal/core/petri_net.hpp"

namespace tripodal::test {

inline Place make_place(std::string id, Tokens tokens = 0, std::string description = {}) {
  Place p;
  p.id = std::move(id);
  p.initial_tokens = tokens;
  p.description = std::move(description);
  return p;
}

inline Transition make_transition(std::string id, std::string event = {}, int priority = 0) {
  Transition t;
  t.id = std::move(id);
  t.event = std::move(event);
  t.priority = priority;
  return t;
}

/// The low-level net of the process PrCleaning (paper Fig. 3 / Table 2). The parameter
/// wheel_type ("differential" or "two_wheel") selects BhCleaning (t0) or BhCleaningTwoWheel
/// (t1); P3/P4 track normal/abnormal localization (t2 localizer.ok, t3 localizer.lost); a
/// behavior completes (t4/t6) only while localization is normal; if localization stays lost for
/// `fault_delay_s`, t5/t7 move the token to the fault place P6/P8 ("localization fault").
inline PetriNet pr_cleaning_net(double fault_delay_s = 5.0) {
  PetriNet net;
  net.id = "PrCleaning";
  net.level = NetLevel::low;
  net.parameters.push_back(VariableDecl{"wheel_type", ValueType::string, std::nullopt, "wheel mechanism", {}});

  net.add_place(make_place("P0", 1, "Idle (Standby)"));
  Place p1 = make_place("P1", 0, "Execute behavior BhCleaning");
  p1.behavior = BehaviorBinding{"BhCleaning", {}};
  net.add_place(std::move(p1));
  Place p2 = make_place("P2", 0, "Execute behavior BhCleaningTwoWheel");
  p2.behavior = BehaviorBinding{"BhCleaningTwoWheel", {}};
  net.add_place(std::move(p2));
  net.add_place(make_place("P3", 1, "State: Normal localization"));
  net.add_place(make_place("P4", 0, "State: Abnormal localization"));
  for (const char* id : {"P5", "P7"}) {
    Place p = make_place(id, 0, "Completion of given Process");
    p.outcome = Outcome::success;
    net.add_place(std::move(p));
  }
  for (const char* id : {"P6", "P8"}) {
    Place p = make_place(id, 0, "Fault: behavior is failed due to localization fault");
    p.outcome = Outcome::fault;
    p.fault_message = "localization fault";
    net.add_place(std::move(p));
  }

  Transition t0 = make_transition("t0");
  t0.description = "Start behavior BhCleaning";
  t0.guard = Guard::parse("wheel_type == 'differential'");
  net.add_transition(std::move(t0));
  Transition t1 = make_transition("t1");
  t1.description = "Start behavior BhCleaningTwoWheel";
  t1.guard = Guard::parse("wheel_type == 'two_wheel'");
  net.add_transition(std::move(t1));
  Transition t2 = make_transition("t2", "localizer.ok");
  t2.description = "Localizer finds the estimated position accords with the actual one";
  net.add_transition(std::move(t2));
  Transition t3 = make_transition("t3", "localizer.lost");
  t3.description = "Localizer finds the estimated position does not accord with the actual one";
  net.add_transition(std::move(t3));
  Transition t4 = make_transition("t4", "BhCleaning.done");
  t4.description = "Behavior BhCleaning completed successfully";
  net.add_transition(std::move(t4));
  Transition t5 = make_transition("t5");
  t5.description = "PS terminates BhCleaning due to the failure of localization";
  t5.delay = from_seconds(fault_delay_s);
  net.add_transition(std::move(t5));
  Transition t6 = make_transition("t6", "BhCleaningTwoWheel.done");
  t6.description = "Behavior BhCleaningTwoWheel completed successfully";
  net.add_transition(std::move(t6));
  Transition t7 = make_transition("t7");
  t7.description = "PS terminates BhCleaningTwoWheel due to the failure of localization";
  t7.delay = from_seconds(fault_delay_s);
  net.add_transition(std::move(t7));

  net.add_arc("P0", "t0");
  net.add_arc("t0", "P1");
  net.add_arc("P0", "t1");
  net.add_arc("t1", "P2");
  net.add_arc("P4", "t2");
  net.add_arc("t2", "P3");
  net.add_arc("P3", "t3");
  net.add_arc("t3", "P4");
  net.add_arc("P1", "t4");
  net.add_arc("P3", "t4", 1, ArcKind::read);
  net.add_arc("t4", "P5");
  net.add_arc("P1", "t5");
  net.add_arc("P4", "t5", 1, ArcKind::read);
  net.add_arc("t5", "P6");
  net.add_arc("P2", "t6");
  net.add_arc("P3", "t6", 1, ArcKind::read);
  net.add_arc("t6", "P7");
  net.add_arc("P2", "t7");
  net.add_arc("P4", "t7", 1, ArcKind::read);
  net.add_arc("t7", "P8");
  return net;
}

/// A ring of `n` places P0..P(n-1) and transitions T0..T(n-1), Ti: Pi -> P(i+1 mod n), one token
/// in P0. T0 waits `first_delay` (zero: immediate) or for `first_event` when given.
inline std::string numbered(char prefix, std::size_t i) {
  std::string s(1, prefix);
  s += std::to_string(i);  // append, not operator+: GCC 12 -Wrestrict misfires on the latter
  return s;
}

inline PetriNet ring_net(std::size_t n, Duration first_delay = Duration{0}, const std::string& first_event = {}) {
  PetriNet net;
  net.id = "ring";
  net.id += std::to_string(n);
  for (std::size_t i = 0; i < n; ++i) net.add_place(make_place(numbered('P', i), i == 0 ? 1 : 0));
  for (std::size_t i = 0; i < n; ++i) {
    Transition t = make_transition(numbered('T', i));
    if (i == 0) {
      t.delay = first_delay;
      t.event = first_event;
    }
    net.add_transition(std::move(t));
  }
  for (std::size_t i = 0; i < n; ++i) {
    net.add_arc(numbered('P', i), numbered('T', i));
    net.add_arc(numbered('T', i), numbered('P', (i + 1) % n));
  }
  return net;
}

}  // namespace tripodal::test
