#include "tripodal/core/net_simulation.hpp"

#include <fmt/format.h>

#include <algorithm>


namespace tripodal {

namespace {

std::string time_column(Time t) { return fmt::format("{:>10} s", format_seconds(t)); }

// Turns firings into trace entries while a run lasts. The marked places are kept up to date from
// each firing's changes, so an entry costs O(marked places), not O(places): simulating a net of a
// million places must not copy its marking per firing.
class TraceObserver final : public EngineObserver {
 public:
  TraceObserver(const PetriNet& net, std::span<const Tokens> marking, std::vector<TraceEntry>& trace)
      : net_(net), trace_(trace) {
    for (PlaceIndex p = 0; p < marking.size(); ++p) {
      if (marking[p] != 0) marked_.emplace_back(p, marking[p]);
    }
  }

 protected:
  void on_firing(const Firing& f) override {
    TraceEntry e;
    e.kind = TraceEntry::Kind::firing;
    e.time = f.time;
    e.transition = f.transition;
    e.name = std::string(f.transition_id);
    e.detail = net_.transition(f.transition).description;
    e.event = std::string(f.event);
    for (const PlaceChange& c : f.changes) {
      const Tokens now = f.marking_after[c.place];
      const auto at = std::lower_bound(marked_.begin(), marked_.end(), c.place,
                                       [](const auto& m, PlaceIndex p) { return m.first < p; });
      if (at != marked_.end() && at->first == c.place) {
        if (now == 0) {
          marked_.erase(at);
        } else {
          at->second = now;
        }
      } else if (now != 0) {
        marked_.insert(at, {c.place, now});
      }
    }
    e.marked_after = marked_;
    trace_.push_back(std::move(e));
  }

 private:
  const PetriNet& net_;
  std::vector<TraceEntry>& trace_;
  std::vector<std::pair<PlaceIndex, Tokens>> marked_;
};

class ObserverGuard {
 public:
  ObserverGuard(Engine& engine, EngineObserver& observer) : engine_(engine), observer_(observer) {
    engine_.add_observer(observer_);
  }
  ~ObserverGuard() { engine_.remove_observer(observer_); }
  ObserverGuard(const ObserverGuard&) = delete;
  ObserverGuard& operator=(const ObserverGuard&) = delete;

 private:
  Engine& engine_;
  EngineObserver& observer_;
};

std::string format_marked(const PetriNet& net, const std::vector<std::pair<PlaceIndex, Tokens>>& marked) {
  std::string out;
  for (const auto& [p, k] : marked) {
    if (!out.empty()) out += ' ';
    out += net.place(p).id;
    if (k > 1) out += ':' + std::to_string(k);
  }
  return out.empty() ? std::string("(empty)") : out;
}

}  // namespace

std::string format_marking(const PetriNet& net, std::span<const Tokens> marking) {
  std::string out;
  for (PlaceIndex p = 0; p < marking.size(); ++p) {
    if (marking[p] == 0) continue;
    if (!out.empty()) out += ' ';
    out += net.place(p).id;
    if (marking[p] > 1) out += ':' + std::to_string(marking[p]);
  }
  return out.empty() ? std::string("(empty)") : out;
}

std::string SimulationResult::str(const PetriNet& net) const {
  std::string out;
  for (const TraceEntry& e : trace) {
    out += time_column(e.time);
    switch (e.kind) {
      case TraceEntry::Kind::firing:
        out += "  fire " + e.name;
        if (!e.event.empty()) out += " [" + e.event + "]";
        if (!e.detail.empty()) out += "  " + e.detail;
        out += "  -> " + format_marked(net, e.marked_after);
        break;
      case TraceEntry::Kind::fact_set: out += "  set " + e.name + " = " + e.detail; break;
      case TraceEntry::Kind::event_dropped:
        out += "  drop " + e.name + " (no enabled transition waits for it)";
        break;
      case TraceEntry::Kind::error: out += "  error: " + e.detail; break;
    }
    out += '\n';
  }
  out += time_column(end_time) + "  end: ";
  switch (outcome) {
    case Outcome::none: out += "no outcome"; break;
    case Outcome::success: out += "success at " + outcome_place; break;
    case Outcome::fault: out += "fault at " + outcome_place + ": " + fault_message; break;
  }
  out += "; marking " + format_marking(net, final_marking) + '\n';
  return out;
}

NetSimulation::NetSimulation(const PetriNet& net, const ParameterValues& parameters, SimulationOptions options)
    : options_(options), engine_(net, parameters, options.engine) {}

void NetSimulation::validate(const EventScript& script) const {
  Diagnostics problems;
  const PetriNet& net = engine_.net();
  for (const ScriptEntry& e : script.entries) {
    if (e.kind == ScriptEntry::Kind::event) {
      if (!options_.allow_unknown_events && !engine_.event_id(e.name)) {
        problems.error(e.name_where, "no transition of net '" + net.id + "' waits for event '" + e.name + "'");
      }
      continue;
    }
    const VariableDecl* decl = net.find_fact(e.name);
    if (decl == nullptr) {
      std::string facts;
      for (const auto& f : net.facts) facts += (facts.empty() ? "" : ", ") + f.name;
      problems.error(e.name_where, "unknown fact '" + e.name + "' (net '" + net.id + "' declares: " +
                                       (facts.empty() ? std::string("none") : facts) + ")");
    } else if (!parse_value(decl->type, e.value_text)) {
      problems.error(e.value_where, "value '" + e.value_text + "' of fact '" + e.name + "' is not a " +
                                        std::string(to_string(decl->type)));
    }
  }
  if (problems.has_errors()) throw ConfigError(std::move(problems));
}

SimulationResult NetSimulation::run(const EventScript& script) {
  validate(script);
  SimulationResult result;
  engine_.reset(Time{});
  TraceObserver observer(engine_.net(), engine_.marking(), result.trace);
  const ObserverGuard guard(engine_, observer);

  // Records what a step reports besides firings; false when the simulation must stop on error.
  auto record = [&](const StepResult& r) {
    for (const auto& name : r.unconsumed_events) {
      result.trace.push_back(TraceEntry{TraceEntry::Kind::event_dropped, engine_.now(), 0, name, {}, {}, {}});
    }
    if (r.ok()) return true;
    result.status = r.status;
    result.error = r.error;
    result.trace.push_back(TraceEntry{TraceEntry::Kind::error, engine_.now(), 0, {}, r.error, {}, {}});
    return false;
  };
  auto finished = [&] { return options_.stop_at_outcome && engine_.outcome().outcome != Outcome::none; };

  const auto& entries = script.entries;
  std::size_t next_entry = 0;
  bool running = record(engine_.step(Time{}));
  while (running && !finished()) {
    Time next = options_.end_time;
    if (next_entry < entries.size()) next = std::min(next, entries[next_entry].time);
    if (const auto deadline = engine_.next_deadline()) next = std::min(next, *deadline);
    next = std::max(next, engine_.now());
    running = record(engine_.step(next));
    while (running && !finished() && next_entry < entries.size() && entries[next_entry].time <= next) {
      const ScriptEntry& e = entries[next_entry++];
      if (e.kind == ScriptEntry::Kind::event) {
        running = record(engine_.step(next, {std::string_view(e.name)}));
      } else {
        const VariableDecl* decl = engine_.net().find_fact(e.name);
        Value value = *parse_value(decl->type, e.value_text);
        result.trace.push_back(TraceEntry{TraceEntry::Kind::fact_set, next, 0, e.name, to_string(value), {}, {}});
        engine_.set_fact(e.name, std::move(value));
        running = record(engine_.step(next));
      }
    }
    if (next >= options_.end_time) break;
  }

  result.end_time = engine_.now();
  const OutcomeState o = engine_.outcome();
  result.outcome = o.outcome;
  result.outcome_place = std::string(o.place_id);
  result.fault_message = std::string(o.message);
  result.final_marking.assign(engine_.marking().begin(), engine_.marking().end());
  return result;
}

}  // namespace tripodal
