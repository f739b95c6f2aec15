#include "tripodal/analysis/analyzer.hpp"

#include <algorithm>
#include <cctype>
#include <deque>

#include "tripodal/core/diagnostic.hpp"

namespace tripodal::analysis {

std::string_view to_string(Verdict v) noexcept {
  switch (v) {
    case Verdict::pass: return "pass";
    case Verdict::fail: return "fail";
    case Verdict::unknown: return "unknown";
    case Verdict::not_applicable: return "not_applicable";
  }
  return "?";
}

bool AnalysisReport::ok() const noexcept {
  return complete() && deadlock_count == 0 && bounded == Verdict::pass &&
         (outcome == Verdict::pass || outcome == Verdict::not_applicable);
}

ParameterValues parse_parameter_assignments(const PetriNet& net, const std::vector<std::string>& kv) {
  Diagnostics problems;
  ParameterValues values;
  for (const std::string& item : kv) {
    const auto eq = item.find('=');
    if (eq == std::string::npos || eq == 0) {
      problems.error(net.where, "--param '" + item + "': expected NAME=VALUE");
      continue;
    }
    const std::string name = item.substr(0, eq);
    const std::string text = item.substr(eq + 1);
    const VariableDecl* decl = net.find_parameter(name);
    if (decl == nullptr) {
      std::string declared;
      for (const auto& d : net.parameters) declared += (declared.empty() ? "" : ", ") + d.name;
      problems.error(net.where, "--param '" + item + "': unknown parameter '" + name + "' (declared: " +
                                    (declared.empty() ? std::string("none") : declared) + ")");
      continue;
    }
    auto value = parse_value(decl->type, text);
    if (!value) {
      problems.error(net.where, "--param '" + item + "': expected a " + std::string(to_string(decl->type)) +
                                    " for parameter '" + name + "'");
      continue;
    }
    values[name] = std::move(*value);
  }
  if (problems.has_errors()) throw ConfigError(std::move(problems));
  return values;
}

namespace {

Witness witness_of(const StateSpace& space, StateId s) {
  return Witness{s, space.marking(s), space.path_to(s)};
}

// States from which an outcome state can be reached: backward breadth-first search over the
// reversed edges (built by counting sort from the forward lists).
std::vector<std::uint8_t> can_reach_outcome(const StateSpace& space) {
  const std::size_t n = space.states();
  std::vector<std::uint64_t> begin(n + 1, 0);
  for (StateId s = 0; s < space.expanded(); ++s) {
    for (const StateId t : space.successors(s)) ++begin[t + 1];
  }
  for (std::size_t i = 0; i < n; ++i) begin[i + 1] += begin[i];
  std::vector<StateId> preds(begin[n]);
  std::vector<std::uint64_t> fill(begin.begin(), begin.end() - 1);
  for (StateId s = 0; s < space.expanded(); ++s) {
    for (const StateId t : space.successors(s)) preds[fill[t]++] = s;
  }
  std::vector<std::uint8_t> good(n, 0);
  std::deque<StateId> queue;
  for (const StateId s : space.outcome_states()) {
    good[s] = 1;
    queue.push_back(s);
  }
  while (!queue.empty()) {
    const StateId s = queue.front();
    queue.pop_front();
    for (std::uint64_t i = begin[s]; i < begin[s + 1]; ++i) {
      if (good[preds[i]] == 0) {
        good[preds[i]] = 1;
        queue.push_back(preds[i]);
      }
    }
  }
  return good;
}

}  // namespace

AnalysisReport analyze(const PetriNet& net, const AnalysisOptions& options) {
  AnalysisReport r;
  r.net_id = net.id;
  r.places = net.places().size();
  r.transitions = net.transitions().size();
  r.semantics = options.semantics;
  r.parameters = options.parameters;
  r.max_states = options.max_states;
  r.max_memory_bytes = options.max_memory_bytes;
  r.max_structural_size = options.max_structural_size;
  r.structure_skipped = r.places + r.transitions > options.max_structural_size;

  // Structure first: invariants give place bounds that size the packed fields.
  std::vector<std::optional<Tokens>> known(r.places);
  if (options.invariants && !r.structure_skipped) {
    r.invariants_computed = true;
    r.p_invariants = place_invariants(net, {.max_rows = options.max_invariant_rows});
    r.t_invariants = transition_invariants(net, {.max_rows = options.max_invariant_rows});
    known = structural_bounds(net, r.p_invariants);
  }
  for (PlaceIndex p = 0; p < r.places; ++p) {
    const auto& cap = net.place(p).capacity;
    if (cap && (!known[p] || *cap < *known[p])) known[p] = *cap;
  }
  r.bounds.resize(r.places);
  for (PlaceIndex p = 0; p < r.places; ++p) r.bounds[p].structural = known[p];
  const bool structurally_bounded = std::all_of(known.begin(), known.end(), [](const auto& b) { return b.has_value(); });

  // Karp–Miller only where the structure does not already bound every place.
  if (!structurally_bounded && !r.structure_skipped) {
    r.coverability_ran = true;
    r.coverability = karp_miller(net, {.parameters = options.parameters, .max_nodes = options.max_coverability_nodes});
    if (r.coverability.complete) {
      for (PlaceIndex p = 0; p < r.places; ++p) {
        const auto& b = r.coverability.bounds[p];
        if (!b) {
          r.bounds[p].may_be_unbounded = true;
        } else if (!known[p] || *b < *known[p]) {
          known[p] = *b;
        }
      }
    }
  }

  bool has_outcome = false;
  for (const Place& p : net.places()) has_outcome = has_outcome || p.outcome != Outcome::none;

  ExploreOptions eo;
  eo.semantics = options.semantics;
  eo.parameters = options.parameters;
  eo.stop_at_outcome = options.stop_at_outcome;
  eo.keep_edges = has_outcome;
  eo.max_states = options.max_states;
  eo.max_memory_bytes = options.max_memory_bytes;
  eo.place_bounds = known;
  SteadyClock steady;
  const Clock& clock = options.clock != nullptr ? *options.clock : steady;
  const Time start = clock.now();
  const StateSpace space = explore(net, eo);
  r.exploration_s = to_seconds(Time{clock.now() - start});

  r.states = space.states();
  r.edges = space.edges();
  r.expanded = space.expanded();
  r.stop = space.stop_reason();
  r.memory_bytes = space.memory_bytes();
  r.bytes_per_state = space.bytes_per_state();
  r.bytes_per_marking = space.bytes_per_marking();

  r.deadlock_count = space.deadlocks().size();
  for (std::size_t i = 0; i < space.deadlocks().size() && i < options.max_examples; ++i) {
    r.deadlocks.push_back(witness_of(space, space.deadlocks()[i]));
  }

  // Bounds and safeness.
  const bool complete = space.complete();
  const bool km_proves_unbounded = r.coverability_ran && r.coverability.complete && r.coverability.exact &&
                                   options.semantics == Semantics::interleaving && !r.coverability.bounded();
  bool all_bounded = true;
  bool all_safe = true;
  bool some_unsafe = false;
  for (PlaceIndex p = 0; p < r.places; ++p) {
    PlaceBound& b = r.bounds[p];
    b.max_seen = p < space.max_tokens().size() ? space.max_tokens()[p] : 0;
    if (complete) {
      b.kind = BoundKind::exact;
    } else if (km_proves_unbounded && !r.coverability.bounds[p]) {
      b.kind = BoundKind::unbounded;
    } else {
      b.kind = BoundKind::at_least;
    }
    const bool bounded = complete || known[p].has_value();
    all_bounded = all_bounded && bounded;
    const Tokens limit = complete ? b.max_seen : (known[p] ? *known[p] : kOmega);
    all_safe = all_safe && limit <= 1;
    some_unsafe = some_unsafe || b.max_seen > 1;
  }
  r.bounded = all_bounded ? Verdict::pass : (km_proves_unbounded ? Verdict::fail : Verdict::unknown);
  r.safe = some_unsafe || r.bounded == Verdict::fail ? Verdict::fail : (all_safe ? Verdict::pass : Verdict::unknown);

  for (TransitionIndex t = 0; t < r.transitions; ++t) {
    if (space.fired()[t] == 0) r.dead_transitions.push_back(t);
  }
  for (PlaceIndex p = 0; p < r.places; ++p) {
    if (r.bounds[p].max_seen == 0) r.never_marked.push_back(p);
  }

  // Outcome check.
  r.outcome_states = space.outcome_states().size();
  if (has_outcome) {
    // The reversed edges cost 8 bytes per state and 4 per edge beyond the store.
    const std::size_t reverse_bytes = (space.states() + 1) * 8 + space.edges() * 4 + space.states();
    if (!complete || space.memory_bytes() + reverse_bytes > options.max_memory_bytes) {
      r.outcome = Verdict::unknown;
    } else {
      const auto good = can_reach_outcome(space);
      for (StateId s = 0; s < good.size(); ++s) {
        if (good[s] != 0) continue;
        ++r.stuck_count;
        if (r.stuck.size() < options.max_examples) r.stuck.push_back(witness_of(space, s));
      }
      r.outcome = r.stuck_count == 0 ? Verdict::pass : Verdict::fail;
    }
  }
  return r;
}

}  // namespace tripodal::analysis

namespace tripodal::analysis {

namespace {

std::string marking_ids(const PetriNet& net, const Marking& m) {
  std::string out;
  for (PlaceIndex p = 0; p < m.size(); ++p) {
    if (m[p] == 0) continue;
    out += (out.empty() ? "" : " ") + net.place(p).id + (m[p] > 1 ? "*" + std::to_string(m[p]) : "");
  }
  return out.empty() ? "(empty)" : out;
}

std::string path_ids(const PetriNet& net, const std::vector<TransitionIndex>& path) {
  if (path.empty()) return "the initial marking";
  std::string out;
  for (const TransitionIndex t : path) {
    const Transition& tr = net.transition(t);
    out += (out.empty() ? "" : " -> ") + tr.id + (tr.event.empty() ? "" : " [" + tr.event + "]");
  }
  return out;
}

// The values a parameter without a default is checked with: the literals its guards compare it
// with (for a number also one below and one above, for the ordered comparisons), both truth
// values for a boolean. A parameter no guard reads changes nothing the analysis sees: one
// placeholder value stands for all.
std::vector<Value> candidate_values(const PetriNet& net, const VariableDecl& p) {
  std::vector<Value> out;
  auto add = [&](Value v) {
    if (type_of(v) == p.type && std::find(out.begin(), out.end(), v) == out.end()) out.push_back(std::move(v));
  };
  if (p.type == ValueType::boolean) return {Value{false}, Value{true}};
  for (const Transition& t : net.transitions()) {
    if (!t.guard) continue;
    const auto& ids = t.guard->identifiers();
    for (std::size_t slot = 0; slot < ids.size(); ++slot) {
      if (ids[slot] != p.name) continue;
      for (Value& v : t.guard->compared_literals(slot)) {
        if (const double* x = std::get_if<double>(&v)) {
          add(Value{*x - 1.0});
          add(Value{*x + 1.0});
        }
        add(std::move(v));
      }
    }
  }
  if (out.empty()) out.push_back(p.type == ValueType::number ? Value{0.0} : Value{std::string{}});
  return out;
}

enum class CheckResult { passed, failed, not_decided };

}  // namespace

std::string incomplete_reason(const AnalysisReport& r) {
  const std::string after = " after " + std::to_string(r.states) + " states";
  switch (r.stop) {
    case StopReason::complete: return "the exploration is complete";
    case StopReason::max_states:
      return "more than " + std::to_string(r.max_states) + " reachable states: the exploration stopped at the limit of " +
             std::to_string(r.max_states) + " states; raise it with --max-states N";
    case StopReason::max_memory:
      return "the state store would exceed the memory limit of " + std::to_string(r.max_memory_bytes >> 20) +
             " MiB" + after + "; raise it with --max-memory-mb N";
    case StopReason::token_overflow:
      return "a place would hold more than 4294967295 tokens" + after + " (the net is probably unbounded)";
  }
  return "?";
}

namespace {

CheckResult check_once(const PetriNet& net, Diagnostics& diagnostics, const BehaviourCheckOptions& options,
                       const ParameterValues& parameters, const std::string& prefix) {
  AnalysisOptions o;
  o.semantics = options.semantics;
  o.parameters = parameters;
  o.max_states = options.max_states;
  o.max_memory_bytes = options.max_memory_bytes;
  o.max_examples = 3;
  o.invariants = false;
  o.max_coverability_nodes = options.max_states;
  const AnalysisReport r = analyze(net, o);
  if (!r.complete()) {
    diagnostics.note(net.where, prefix + "behaviour not checked: " + incomplete_reason(r) +
                                    " (or run tripodal-net analyze for the full analysis)");
    return CheckResult::not_decided;
  }
  for (const Witness& w : r.deadlocks) {
    diagnostics.error(net.where, prefix + "deadlock: nothing can fire in marking " + marking_ids(net, w.marking) +
                                     ", reached by " + path_ids(net, w.path));
  }
  if (r.deadlock_count > r.deadlocks.size()) {
    diagnostics.error(net.where, prefix + std::to_string(r.deadlock_count - r.deadlocks.size()) + " more deadlocks");
  }
  if (r.outcome == Verdict::fail) {
    for (const Witness& w : r.stuck) {
      diagnostics.error(net.where, prefix + "no outcome place can be reached from marking " +
                                       marking_ids(net, w.marking) + ", reached by " + path_ids(net, w.path));
    }
    if (r.stuck_count > r.stuck.size()) {
      diagnostics.error(net.where, prefix + std::to_string(r.stuck_count - r.stuck.size()) +
                                       " more markings from which no outcome can be reached");
    }
  }
  return r.deadlock_count == 0 && r.outcome != Verdict::fail ? CheckResult::passed : CheckResult::failed;
}

}  // namespace

bool check_behaviour(const PetriNet& net, Diagnostics& diagnostics, const BehaviourCheckOptions& options) {
  // Parameters without a default are checked with every combination of the values their guards
  // name (the process is meant to run with one of them).
  std::vector<const VariableDecl*> open;
  std::vector<std::vector<Value>> values;
  std::size_t combinations = 1;
  for (const VariableDecl& p : net.parameters) {
    if (p.default_value) continue;
    open.push_back(&p);
    values.push_back(candidate_values(net, p));
    combinations *= values.back().size();
    if (combinations > kCheckParameterCombinations) {
      diagnostics.note(net.where, "behaviour not checked: more than " + std::to_string(kCheckParameterCombinations) +
                                      " combinations of the values the guards give parameters without defaults "
                                      "(run tripodal-net analyze with --param NAME=VALUE)");
      return false;
    }
  }
  bool passed = true;
  std::vector<std::size_t> pick(open.size(), 0);
  for (std::size_t c = 0; c < combinations; ++c) {
    ParameterValues parameters;
    std::string prefix;
    for (std::size_t i = 0; i < open.size(); ++i) {
      parameters[open[i]->name] = values[i][pick[i]];
      prefix += (prefix.empty() ? "with " : ", ") + open[i]->name + "=" + tripodal::to_string(values[i][pick[i]]);
    }
    if (!prefix.empty()) prefix += ": ";
    passed = check_once(net, diagnostics, options, parameters, prefix) == CheckResult::passed && passed;
    for (std::size_t i = 0; i < open.size() && ++pick[i] == values[i].size(); ++i) pick[i] = 0;
  }
  return passed;
}

Semantics default_semantics_for(std::string_view file_name, std::string_view head) {
  auto ends_with_pnml = [](std::string_view s) {
    if (s.size() < 5) return false;
    std::string tail(s.substr(s.size() - 5));
    for (char& c : tail) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    return tail == ".pnml";
  };
  if (ends_with_pnml(file_name) || head.find("<pnml") != std::string_view::npos) return Semantics::interleaving;
  return Semantics::engine;
}

}  // namespace tripodal::analysis
