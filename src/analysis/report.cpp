// Text and JSON forms of an AnalysisReport. The JSON is built with nlohmann-json (ordered, so the
// keys come in the order docs/analysis.md lists them): strings escaped per RFC 8259, and a number
// that is not finite written as null, never as nan or inf.
#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdio>
#include <set>
#include <sstream>

#include "tripodal/analysis/analyzer.hpp"

namespace tripodal::analysis {

namespace {

using Json = nlohmann::ordered_json;

Json json_value(const Value& v) {
  switch (type_of(v)) {
    case ValueType::boolean: return std::get<bool>(v);
    case ValueType::number: return std::get<double>(v);
    case ValueType::string: return std::get<std::string>(v);
  }
  return nullptr;
}

std::string marking_text(const PetriNet& net, const Marking& m) {
  std::string out;
  for (PlaceIndex p = 0; p < m.size(); ++p) {
    if (m[p] == 0) continue;
    if (!out.empty()) out += ' ';
    out += net.place(p).id;
    if (m[p] > 1) out += "*" + std::to_string(m[p]);
  }
  return out.empty() ? "(empty)" : out;
}

std::string path_text(const PetriNet& net, const std::vector<TransitionIndex>& path) {
  if (path.empty()) return "(initial marking)";
  std::string out;
  for (const TransitionIndex t : path) {
    if (!out.empty()) out += " -> ";
    const Transition& tr = net.transition(t);
    out += tr.id;
    if (!tr.event.empty()) out += " [" + tr.event + "]";
  }
  return out;
}

// The events the path needs, in order, and the fact guards it assumes true.
std::vector<std::string> path_events(const PetriNet& net, const std::vector<TransitionIndex>& path) {
  std::vector<std::string> events;
  for (const TransitionIndex t : path) {
    if (!net.transition(t).event.empty()) events.push_back(net.transition(t).event);
  }
  return events;
}

std::vector<std::string> path_fact_guards(const PetriNet& net, const std::vector<TransitionIndex>& path) {
  std::vector<std::string> guards;
  std::set<TransitionIndex> seen;
  for (const TransitionIndex t : path) {
    const Transition& tr = net.transition(t);
    if (!tr.guard || !seen.insert(t).second) continue;
    for (const auto& id : tr.guard->identifiers()) {
      if (net.find_parameter(id) == nullptr) {
        guards.push_back(tr.id + ": " + tr.guard->text());
        break;
      }
    }
  }
  return guards;
}

std::string join(const std::vector<std::string>& items, std::string_view sep) {
  std::string out;
  for (const auto& s : items) {
    if (!out.empty()) out += sep;
    out += s;
  }
  return out;
}

std::string invariant_text(const PetriNet& net, const Invariant& inv, bool places) {
  std::string out;
  for (const auto& [i, w] : inv.weights) {
    if (!out.empty()) out += " + ";
    if (w != 1) out += std::to_string(w) + "*";
    out += places ? net.place(i).id : net.transition(i).id;
  }
  if (places) out += " = " + std::to_string(inv.token_sum);
  return out;
}

std::string bytes_text(std::size_t bytes) {
  char buf[32];
  if (bytes >= (std::size_t{1} << 20)) {
    std::snprintf(buf, sizeof buf, "%.1f MiB", static_cast<double>(bytes) / (1024.0 * 1024.0));
  } else {
    std::snprintf(buf, sizeof buf, "%.1f KiB", static_cast<double>(bytes) / 1024.0);
  }
  return buf;
}

void witness_text(std::ostringstream& out, const PetriNet& net, const Witness& w) {
  out << "  - marking: " << marking_text(net, w.marking) << '\n';
  out << "    path (" << w.path.size() << " firings): " << path_text(net, w.path) << '\n';
  const auto events = path_events(net, w.path);
  if (!events.empty()) out << "    events needed: " << join(events, ", ") << '\n';
  const auto guards = path_fact_guards(net, w.path);
  if (!guards.empty()) out << "    assumes fact guards true: " << join(guards, "; ") << '\n';
}

Json witness_json(const PetriNet& net, const Witness& w) {
  Json marking = Json::object();
  for (PlaceIndex p = 0; p < w.marking.size(); ++p) {
    if (w.marking[p] != 0) marking[net.place(p).id] = w.marking[p];
  }
  Json path = Json::array();
  for (const TransitionIndex t : w.path) {
    const Transition& tr = net.transition(t);
    path.push_back({{"transition", tr.id}, {"event", tr.event.empty() ? Json(nullptr) : Json(tr.event)}});
  }
  return {{"marking", std::move(marking)},
          {"path", std::move(path)},
          {"events", path_events(net, w.path)},
          {"fact_guards", path_fact_guards(net, w.path)}};
}

Json ids_json(const PetriNet& net, const std::vector<std::uint32_t>& items, bool places) {
  Json out = Json::array();
  for (const auto i : items) out.push_back(places ? net.place(i).id : net.transition(i).id);
  return out;
}

Json invariants_json(const PetriNet& net, const InvariantBasis& basis, bool places) {
  Json items = Json::array();
  for (const Invariant& inv : basis.invariants) {
    Json weights = Json::object();
    for (const auto& [n, w] : inv.weights) weights[places ? net.place(n).id : net.transition(n).id] = w;
    Json item = {{"weights", std::move(weights)}};
    if (places) item["token_sum"] = inv.token_sum;
    items.push_back(std::move(item));
  }
  return {{"complete", basis.complete}, {"items", std::move(items)}};
}

std::string_view kind_text(BoundKind k) {
  switch (k) {
    case BoundKind::exact: return "exact";
    case BoundKind::unbounded: return "unbounded";
    case BoundKind::at_least: return "at_least";
  }
  return "?";
}

double rate(const AnalysisReport& r) { return r.exploration_s > 0 ? static_cast<double>(r.expanded) / r.exploration_s : 0.0; }

}  // namespace

std::string format_text(const AnalysisReport& r, const PetriNet& net) {
  std::ostringstream out;
  out << "net '" << r.net_id << "': " << r.places << " places, " << r.transitions << " transitions; semantics: "
      << to_string(r.semantics);
  if (!r.parameters.empty()) {
    out << "; parameters:";
    for (const auto& [k, v] : r.parameters) out << ' ' << k << '=' << tripodal::to_string(v);
  }
  out << "\n\n";

  char buf[160];
  std::snprintf(buf, sizeof buf, "%.3f s, %.2f M states/s", r.exploration_s, rate(r) / 1e6);
  out << "reachability graph: " << r.states << " states, " << r.edges << " edges";
  if (r.complete()) {
    out << " (complete, " << buf << ")\n";
  } else {
    out << " -- INCOMPLETE: stopped by " << to_string(r.stop) << " after expanding " << r.expanded << " states ("
        << buf << "); the verdicts below cover only what was explored\n  " << incomplete_reason(r) << '\n';
  }
  std::snprintf(buf, sizeof buf, "%.1f", r.bytes_per_state);
  out << "memory: " << bytes_text(r.memory_bytes) << " (" << buf << " bytes per state, packed marking "
      << r.bytes_per_marking << " bytes)\n\n";

  if (r.deadlock_count == 0) {
    out << "deadlocks: none" << (r.complete() ? "" : " found so far") << '\n';
  } else {
    out << "deadlocks: " << r.deadlock_count << " (markings where nothing can fire and no outcome place is marked)\n";
    for (const Witness& w : r.deadlocks) witness_text(out, net, w);
    if (r.deadlocks.size() < r.deadlock_count) out << "  ... " << r.deadlock_count - r.deadlocks.size() << " more\n";
  }

  out << "\nbounds: ";
  switch (r.bounded) {
    case Verdict::pass: out << "bounded"; break;
    case Verdict::fail:
      out << (r.growth && r.growth->confirmed() ? "UNBOUNDED (pumping cycle)" : "UNBOUNDED (Karp-Miller)");
      break;
    default: out << "unknown"; break;
  }
  out << "; 1-safe: " << (r.safe == Verdict::pass ? "yes" : r.safe == Verdict::fail ? "NO" : "unknown") << '\n';
  for (PlaceIndex p = 0; p < r.places; ++p) {
    const PlaceBound& b = r.bounds[p];
    out << "  " << net.place(p).id << ": ";
    if (b.kind == BoundKind::unbounded) {
      out << "unbounded";
    } else {
      out << (b.kind == BoundKind::at_least ? ">= " : "") << b.max_seen;
    }
    if (b.structural) out << " (structural bound " << *b.structural << ")";
    if (b.may_be_unbounded && b.kind != BoundKind::unbounded) out << " (may be unbounded: omega in the over-approximation)";
    out << '\n';
  }
  if (r.coverability_ran) {
    const CoverabilityResult& c = r.coverability;
    out << "  coverability (Karp-Miller, " << c.nodes << " nodes" << (c.complete ? "" : ", incomplete")
        << (c.exact ? "" : ", over-approximation without inhibitor arcs and capacities") << ")";
    if (!c.pumped.empty()) {
      std::vector<std::string> names;
      for (const PlaceIndex p : c.pumped) names.push_back(net.place(p).id);
      out << ": repeating " << path_text(net, c.pump) << " after " << path_text(net, c.prefix) << " grows "
          << join(names, ", ");
    }
    out << '\n';
  }

  if (r.growth) {
    const GrowthWitness& g = *r.growth;
    out << "  " << (g.confirmed() ? "grows without end: " : "may grow without end: ") << net.place(g.place).id
        << ": after " << path_text(net, g.prefix) << ", repeating " << path_text(net, g.pump)
        << " adds tokens (" << g.before << " -> " << g.after
        << (g.confirmed() ? ", replayed " + std::to_string(g.rounds) + " more times" : "") << ")\n";
  }
  if (!r.double_started.empty()) {
    out << "\nbehaviors started twice: " << r.double_started.size()
        << " (a place binding a behavior or process holds 2 tokens)\n";
    for (const DoubleStart& d : r.double_started) {
      const Place& p = net.place(d.place);
      out << "  " << p.id << " ("
          << (p.behavior  ? p.behavior->behavior
              : p.process ? p.process->process
                          : std::string())
          << ")\n";
      if (!d.witness.marking.empty()) witness_text(out, net, d.witness);
    }
  }

  auto list = [&](const std::vector<std::uint32_t>& items, bool places) {
    std::vector<std::string> names;
    names.reserve(items.size());
    for (const auto i : items) names.push_back(places ? net.place(i).id : net.transition(i).id);
    return names.empty() ? std::string("none") : join(names, ", ");
  };
  const char* so_far = r.complete() ? "" : " (so far)";
  out << "\ndead transitions" << so_far << ": " << list(r.dead_transitions, false) << '\n';
  if (!r.guard_false.empty())
    out << "  guards false for these parameters: " << list(r.guard_false, false) << '\n';
  out << "never-marked places" << so_far << ": " << list(r.never_marked, true) << '\n';

  out << "\noutcome check: ";
  switch (r.outcome) {
    case Verdict::not_applicable: out << "not applicable (the net has no outcome place)\n"; break;
    case Verdict::unknown: out << "unknown (exploration incomplete)\n"; break;
    case Verdict::pass: out << "pass: an outcome place can be reached from every reachable marking\n"; break;
    case Verdict::fail:
      out << "FAIL: " << r.stuck_count << " reachable markings cannot reach any outcome place\n";
      for (const Witness& w : r.stuck) witness_text(out, net, w);
      if (r.stuck.size() < r.stuck_count) out << "  ... " << r.stuck_count - r.stuck.size() << " more\n";
      break;
  }

  if (r.structure_skipped) {
    out << "\ninvariants and coverability: not computed: " << r.places << " places + " << r.transitions
        << " transitions exceed the limit of " << r.max_structural_size
        << " (both grow faster than the net; raise it with --max-structural-size N)\n";
  }
  if (r.invariants_computed) {
    out << "\nplace invariants (" << r.p_invariants.invariants.size()
        << (r.p_invariants.complete ? "" : ", incomplete") << "):\n";
    for (const Invariant& inv : r.p_invariants.invariants) out << "  " << invariant_text(net, inv, true) << '\n';
    std::vector<std::uint32_t> uncovered;
    for (PlaceIndex p = 0; p < r.places; ++p) {
      if (r.p_invariants.covered[p] == 0) uncovered.push_back(p);
    }
    if (!uncovered.empty()) out << "  not covered: " << list(uncovered, true) << '\n';
    out << "transition invariants (" << r.t_invariants.invariants.size()
        << (r.t_invariants.complete ? "" : ", incomplete") << "):\n";
    for (const Invariant& inv : r.t_invariants.invariants) out << "  " << invariant_text(net, inv, false) << '\n';
  }
  // A cut search never says OK: it says what was found so far and that the rest is unknown.
  out << "\nverdict: ";
  if (r.ok()) {
    // Facts are free in the analysis: an OK that depends on them says so.
    out << "OK" << (r.assumed_facts.empty() ? "" : " under " + assumption_text(r.assumed_facts)) << '\n';
  } else if (!r.complete()) {
    const bool found = r.deadlock_count > 0 || r.bounded == Verdict::fail || !r.double_started.empty();
    out << (found ? "PROBLEMS FOUND; " : "") << "INCOMPLETE: not every reachable marking was explored ("
        << incomplete_reason(r) << ")\n";
  } else {
    out << "PROBLEMS FOUND\n";
  }
  return out.str();
}

std::string format_json(const AnalysisReport& r, const PetriNet& net) {
  Json parameters = Json::object();
  for (const auto& [k, v] : r.parameters) parameters[k] = json_value(v);
  Json deadlocks = Json::array();
  for (const Witness& w : r.deadlocks) deadlocks.push_back(witness_json(net, w));
  Json places = Json::array();
  for (PlaceIndex p = 0; p < r.places; ++p) {
    const PlaceBound& b = r.bounds[p];
    places.push_back({{"id", net.place(p).id},
                      {"max", b.kind == BoundKind::unbounded ? Json(nullptr) : Json(b.max_seen)},
                      {"kind", kind_text(b.kind)},
                      {"structural", b.structural ? Json(*b.structural) : Json(nullptr)},
                      {"may_be_unbounded", b.may_be_unbounded}});
  }
  Json coverability = nullptr;
  if (r.coverability_ran) {
    const CoverabilityResult& c = r.coverability;
    std::vector<std::uint32_t> omega;
    for (PlaceIndex p = 0; p < c.bounds.size(); ++p) {
      if (!c.bounds[p]) omega.push_back(p);
    }
    coverability = {{"complete", c.complete},
                    {"exact", c.exact},
                    {"nodes", c.nodes},
                    {"omega_places", ids_json(net, omega, true)},
                    {"prefix", ids_json(net, c.prefix, false)},
                    {"pump", ids_json(net, c.pump, false)},
                    {"pumped", ids_json(net, c.pumped, true)}};
  }
  Json stuck = Json::array();
  for (const Witness& w : r.stuck) stuck.push_back(witness_json(net, w));
  Json doubles = Json::array();
  for (const DoubleStart& d : r.double_started) {
    doubles.push_back(
        {{"place", net.place(d.place).id},
         {"witness", d.witness.marking.empty() ? Json(nullptr) : witness_json(net, d.witness)}});
  }
  Json growth = nullptr;
  if (r.growth) {
    growth = {{"place", net.place(r.growth->place).id},
              {"prefix", ids_json(net, r.growth->prefix, false)},
              {"pump", ids_json(net, r.growth->pump, false)},
              {"before", r.growth->before},
              {"after", r.growth->after},
              {"rounds", r.growth->rounds},
              {"confirmed", r.growth->confirmed()}};
  }
  Json invariants = nullptr;
  if (r.invariants_computed) {
    invariants = {{"place", invariants_json(net, r.p_invariants, true)},
                  {"transition", invariants_json(net, r.t_invariants, false)}};
  }
  const Json out = {
      {"net", {{"id", r.net_id}, {"places", r.places}, {"transitions", r.transitions}}},
      {"semantics", to_string(r.semantics)},
      {"parameters", std::move(parameters)},
      {"graph",
       {{"states", r.states},
        {"edges", r.edges},
        {"expanded", r.expanded},
        {"complete", r.complete()},
        {"stop_reason", to_string(r.stop)},
        {"max_states", r.max_states},
        {"max_memory_bytes", r.max_memory_bytes},
        {"exploration_s", r.exploration_s},
        {"states_per_s", rate(r)},
        {"memory_bytes", r.memory_bytes},
        {"bytes_per_state", r.bytes_per_state},
        {"bytes_per_marking", r.bytes_per_marking}}},
      {"deadlocks", {{"count", r.deadlock_count}, {"examples", std::move(deadlocks)}}},
      {"bounds",
       {{"bounded", to_string(r.bounded)}, {"safe", to_string(r.safe)}, {"places", std::move(places)}}},
      {"coverability", std::move(coverability)},
      {"structure", {{"max_size", r.max_structural_size}, {"skipped", r.structure_skipped}}},
      {"double_started", std::move(doubles)},
      {"growth", std::move(growth)},
      {"dead_transitions", ids_json(net, r.dead_transitions, false)},
      {"guard_false", ids_json(net, r.guard_false, false)},
      {"never_marked_places", ids_json(net, r.never_marked, true)},
      {"outcome",
       {{"verdict", to_string(r.outcome)},
        {"outcome_states", r.outcome_states},
        {"stuck_count", r.stuck_count},
        {"stuck", std::move(stuck)}}},
      {"invariants", std::move(invariants)},
      {"assumed_facts", r.assumed_facts},
      {"ok", r.ok()}};
  // Names come from net files: a byte sequence that is not UTF-8 is replaced, not thrown on.
  return out.dump(-1, ' ', false, Json::error_handler_t::replace) + '\n';
}

}  // namespace tripodal::analysis
