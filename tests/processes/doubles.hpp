// Test doubles for the sequencing and deliberate layers: behaviors that complete after a given
// amount of active (unpaused) time, a localizer and a section splitter, and the paper's process
// nets built in code (PrCleaning, PrAutoMove, PrGlobalLocalization) with the parameters the task
// templates pass. Shared by the processes, planner and robot suites.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "tripodal/core/clock.hpp"
#include "tripodal/core/petri_net.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/processes/behavior_host.hpp"

namespace tripodal::test {

/// Behaviors as a control loop would run them, without one: each works for `work` of unpaused
/// time after activation, then succeeds (or fails with `reason`).
class FakeBehaviors final : public BehaviorHost {
 public:
  struct Spec {
    Duration work{from_seconds(1.0)};
    bool fail = false;
    std::string reason = "blocked";
    bool throw_on_activate = false;
    bool throw_on_report = false;
    bool silent = false;  ///< stops being stepped: last_step stays at activation
  };
  struct State {
    bool active = false;
    Duration progress{0};
    BehaviorStatus state = BehaviorStatus::idle;
    ParameterValues params;
    Time last_step{};
  };

  std::map<std::string, Spec, std::less<>> specs;
  std::map<std::string, State, std::less<>> states;
  std::vector<std::string> log;  ///< "t=1.000 activate BhCleaning(section=A)", "... deactivate BhCleaning"
  bool paused = false;           ///< the robot stands still (e.g. localization lost)

  void add(const std::string& name, double work_s) { specs[name].work = from_seconds(work_s); }

  /// One control period of `dt` ending at `now`.
  void advance(Time now, Duration dt) {
    for (auto& [name, s] : states) {
      if (!s.active || s.state != BehaviorStatus::running) continue;
      const Spec& spec = specs.at(name);
      if (spec.silent) continue;
      s.last_step = now;
      if (!paused) s.progress += dt;
      if (s.progress >= spec.work) s.state = spec.fail ? BehaviorStatus::failed : BehaviorStatus::succeeded;
    }
  }

  [[nodiscard]] bool has(std::string_view behavior) const override { return specs.find(behavior) != specs.end(); }
  void activate(std::string_view behavior, const ParameterValues& params, Time now) override {
    const Spec& spec = specs.at(std::string(behavior));
    std::string text = stamp(now) + " activate " + std::string(behavior) + "(";
    bool first = true;
    for (const auto& [k, v] : params) {
      text += (first ? "" : ", ") + k + "=" + (std::holds_alternative<std::string>(v) ? std::get<std::string>(v) : to_string(v));
      first = false;
    }
    log.push_back(text + ")");
    if (spec.throw_on_activate) throw std::runtime_error("driver not ready");
    State& s = states[std::string(behavior)];
    s = State{true, Duration{0}, BehaviorStatus::running, params, now};
  }
  void deactivate(std::string_view behavior, Time now) override {
    log.push_back(stamp(now) + " deactivate " + std::string(behavior));
    State& s = states[std::string(behavior)];
    s.active = false;
    s.state = BehaviorStatus::idle;
  }
  [[nodiscard]] BehaviorReport report(std::string_view behavior) const override {
    if (specs.at(std::string(behavior)).throw_on_report) throw std::runtime_error("status register unreadable");
    auto it = states.find(behavior);
    if (it == states.end()) return {};
    BehaviorReport r;
    r.state = it->second.state;
    if (r.state == BehaviorStatus::failed) r.reason = specs.at(std::string(behavior)).reason;
    r.last_step = it->second.last_step;
    return r;
  }
  [[nodiscard]] bool active(std::string_view behavior) const {
    auto it = states.find(behavior);
    return it != states.end() && it->second.active;
  }

  static std::string stamp(Time t) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "t=%.3f", to_seconds(t));
    return buf;
  }
};

/// The section splitter's answer to the planner: sections(room).
class FakeSectionSplitter final : public TaskKnowledge {
 public:
  std::map<std::string, std::vector<std::string>> sections{{"3211", {"A", "B"}}, {"2111", {"C"}}};
  [[nodiscard]] ListResult list(std::string_view function, std::string_view argument) const override {
    if (function != "sections") return {false, {}, "unknown question '" + std::string(function) + "'"};
    auto it = sections.find(std::string(argument));
    if (it == sections.end()) return {false, {}, "unknown room '" + std::string(argument) + "'"};
    return {true, it->second, {}};
  }
};

inline Place place(std::string id, Tokens tokens = 0, std::string description = {}) {
  Place p;
  p.id = std::move(id);
  p.initial_tokens = tokens;
  p.description = std::move(description);
  return p;
}

inline Transition transition(std::string id, std::string event = {}, double delay_s = 0.0) {
  Transition t;
  t.id = std::move(id);
  t.event = std::move(event);
  t.delay = from_seconds(delay_s);
  return t;
}

inline void arcs(PetriNet& net, std::initializer_list<std::pair<const char*, const char*>> list) {
  for (const auto& [a, b] : list) net.add_arc(a, b);
}

/// A motion process in the shape of the paper's Fig. 3: idle -> the behavior runs while
/// localization is normal (P3) or paused while abnormal (P4); "<behavior>.done" with P3 marked
/// completes; P4 held for `fault_delay_s` is a "localization fault"; "<behavior>.failed" is a
/// fault with `failed_message`.
inline PetriNet motion_process_net(const std::string& id, const std::string& behavior,
                                   std::vector<std::pair<std::string, std::string>> params,
                                   std::vector<VariableDecl> decls, double fault_delay_s,
                                   const std::string& failed_message) {
  PetriNet net;
  net.id = id;
  net.level = NetLevel::low;
  net.parameters = std::move(decls);
  net.add_place(place("P0", 1, "Idle (Standby)"));
  Place p1 = place("P1", 0, "Execute behavior " + behavior);
  BehaviorBinding b{behavior, {}};
  for (auto& [k, v] : params) b.params.push_back(BindingParam{k, v, {}});
  p1.behavior = std::move(b);
  net.add_place(std::move(p1));
  net.add_place(place("P3", 1, "State: Normal localization"));
  net.add_place(place("P4", 0, "State: Abnormal localization"));
  Place ok = place("P5", 0, "Completion of given Process");
  ok.outcome = Outcome::success;
  net.add_place(std::move(ok));
  Place lf = place("P6", 0, "Fault: localization fault");
  lf.outcome = Outcome::fault;
  lf.fault_message = "localization fault";
  net.add_place(std::move(lf));
  Place bf = place("P7", 0, "Fault: behavior failed");
  bf.outcome = Outcome::fault;
  bf.fault_message = failed_message;
  net.add_place(std::move(bf));
  net.add_transition(transition("t0"));
  net.add_transition(transition("t2", "localizer.ok"));
  net.add_transition(transition("t3", "localizer.lost"));
  net.add_transition(transition("t4", behavior + ".done"));
  net.add_transition(transition("t5", {}, fault_delay_s));
  net.add_transition(transition("t6", behavior + ".failed"));
  arcs(net, {{"P0", "t0"}, {"t0", "P1"}, {"P4", "t2"}, {"t2", "P3"}, {"P3", "t3"}, {"t3", "P4"}, {"P1", "t4"},
             {"t4", "P5"}, {"P1", "t5"}, {"t5", "P6"}, {"P1", "t6"}, {"t6", "P7"}});
  net.add_arc("P3", "t4", 1, ArcKind::read);
  net.add_arc("P4", "t5", 1, ArcKind::read);
  return net;
}

inline VariableDecl decl(std::string name, ValueType type = ValueType::string, std::optional<Value> def = std::nullopt) {
  return VariableDecl{std::move(name), type, std::move(def), {}, {}};
}

/// PrCleaning: BhCleaning over the section given by the plan.
inline PetriNet pr_cleaning(double fault_delay_s = 5.0) {
  return motion_process_net("PrCleaning", "BhCleaning", {{"section", "$section"}, {"pattern", "balloon"}},
                            {decl("section"), decl("wheel_type", ValueType::string, Value{std::string("omni")})},
                            fault_delay_s, "cleaning behavior failed");
}

/// PrAutoMove: BhAutoMove to the goal given by the plan.
inline PetriNet pr_auto_move(double fault_delay_s = 5.0) {
  return motion_process_net("PrAutoMove", "BhAutoMove", {{"goal", "$goal"}}, {decl("goal")}, fault_delay_s,
                            "path blocked");
}

/// PrGlobalLocalization: BhGlobalLocalization until it reports done (or fails).
inline PetriNet pr_global_localization() {
  PetriNet net;
  net.id = "PrGlobalLocalization";
  net.add_place(place("P0", 1));
  Place p1 = place("P1", 0, "Execute behavior BhGlobalLocalization");
  p1.behavior = BehaviorBinding{"BhGlobalLocalization", {}};
  net.add_place(std::move(p1));
  Place ok = place("P2");
  ok.outcome = Outcome::success;
  net.add_place(std::move(ok));
  Place ko = place("P3");
  ko.outcome = Outcome::fault;
  ko.fault_message = "global localization failed";
  net.add_place(std::move(ko));
  net.add_transition(transition("t0"));
  net.add_transition(transition("t1", "BhGlobalLocalization.done"));
  net.add_transition(transition("t2", "BhGlobalLocalization.failed"));
  arcs(net, {{"P0", "t0"}, {"t0", "P1"}, {"P1", "t1"}, {"t1", "P2"}, {"P1", "t2"}, {"t2", "P3"}});
  return net;
}

}  // namespace tripodal::test
