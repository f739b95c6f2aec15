#include "tripodal/analysis/analyzer.hpp"

#include <algorithm>
#include <cctype>
#include <deque>
#include <set>

#include "compiled_net.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/registry.hpp"

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
  return complete() && deadlock_count == 0 && bounded == Verdict::pass && double_started.empty() &&
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
      std::vector<std::string> names;
      for (const auto& d : net.parameters) names.push_back(d.name);
      const auto close = closest_name(name, names);
      problems.error(net.where, "--param '" + item + "': unknown parameter '" + name +
                                    "' (declared: " + (declared.empty() ? std::string("none") : declared) +
                                    ")" + (close ? "; did you mean '" + *close + "'?" : std::string()));
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

// The first state, in BFS order (so with a shortest path), where place p holds at least `k`.
// Each marking costs O(places) to unpack: the scan stops after a budget of place reads (a huge
// net with such a place is still reported, without the path).
std::optional<StateId> first_state_with(const StateSpace& space, PlaceIndex p, Tokens k, std::size_t places) {
  constexpr std::size_t kBudget = 400'000'000;
  const std::size_t states =
      std::min<std::size_t>(space.states(), kBudget / std::max<std::size_t>(places, 1));
  for (StateId s = 0; s < states; ++s) {
    if (space.marking(s)[p] >= k) return s;
  }
  return std::nullopt;
}

void apply(const detail::CompiledNet& c, TransitionIndex t, Marking& m) {
  for (std::uint32_t i = c.change_begin[t]; i < c.change_begin[t + 1]; ++i) {
    const detail::Change& d = c.changes[i];
    m[d.place] = m[d.place] - d.consumed + d.produced;
  }
}

// The supervisor ends a net at an outcome: nothing fires after it.
bool marks_outcome(const detail::CompiledNet& c, const Marking& m) {
  for (PlaceIndex p = 0; p < m.size(); ++p) {
    if (m[p] != 0 && c.is_outcome[p] != 0) return true;
  }
  return false;
}

bool may_fire(const detail::CompiledNet& c, const Marking& m, TransitionIndex t) {
  bool found = false;
  c.successors(m.data(), [&](TransitionIndex u) { found = found || u == t; });
  return found;
}

// A pumping cycle on the path to the deepest stored state: markings m_i, m_j (i < j) with
// m_j >= m_i and m_j != m_i. Every long enough path of an unbounded net has one (Dickson's lemma).
// The cycle is then replayed from m_j under the analysis semantics: it confirms the growth when
// it can fire again and again, each round growing the place (priorities and inhibitor arcs can
// stop a cycle that a marking with more tokens would otherwise repeat).
std::optional<GrowthWitness> find_growth(const PetriNet& net, const StateSpace& space,
                                         const AnalysisOptions& options) {
  if (space.states() == 0) return std::nullopt;
  constexpr std::size_t kMaxPath = 4096;  // ancestors compared: the search stays linear in the path
  constexpr std::size_t kWindow = 256;
  constexpr std::size_t kRounds = 3;
  const detail::CompiledNet c(net, options.parameters, {.semantics = options.semantics});
  std::vector<TransitionIndex> path = space.path_to(static_cast<StateId>(space.states() - 1));
  if (path.size() > kMaxPath) path.resize(kMaxPath);
  std::vector<Marking> m{space.marking(0)};
  for (const TransitionIndex t : path) {
    m.push_back(m.back());
    apply(c, t, m.back());
  }
  for (std::size_t j = 1; j < m.size(); ++j) {
    for (std::size_t i = j; i-- > 0 && j - i <= kWindow;) {
      bool covers = true;
      std::optional<PlaceIndex> grown;
      for (PlaceIndex p = 0; p < m[j].size() && covers; ++p) {
        covers = m[j][p] >= m[i][p];
        if (covers && m[j][p] > m[i][p] && !grown) grown = p;
      }
      if (!covers || !grown) continue;
      GrowthWitness g;
      g.place = *grown;
      g.prefix.assign(path.begin(), path.begin() + static_cast<std::ptrdiff_t>(i));
      g.pump.assign(path.begin() + static_cast<std::ptrdiff_t>(i),
                    path.begin() + static_cast<std::ptrdiff_t>(j));
      g.before = m[i][*grown];
      Marking cur = m[j];
      g.after = cur[*grown];
      for (std::size_t round = 0; round < kRounds; ++round) {
        const Tokens start = cur[*grown];
        bool fired = true;
        for (const TransitionIndex t : g.pump) {
          if (!may_fire(c, cur, t) || (options.stop_at_outcome && marks_outcome(c, cur))) {
            fired = false;
            break;
          }
          apply(c, t, cur);
        }
        if (!fired || cur[*grown] <= start) break;
        g.rounds = round + 1;
        g.after = cur[*grown];
      }
      return g;
    }
  }
  return std::nullopt;
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

  // A behavior or process bound to a place with two tokens is started twice.
  for (PlaceIndex p = 0; p < r.places; ++p) {
    const Place& place = net.place(p);
    if ((!place.behavior && !place.process) || r.bounds[p].max_seen < 2) continue;
    const auto s = first_state_with(space, p, 2, r.places);
    r.double_started.push_back({p, s ? witness_of(space, *s) : Witness{}});
  }
  // A search cut short on a net that may be unbounded: look for the cycle that fills it.
  const bool may_grow =
      r.stop == StopReason::token_overflow ||
      (!complete && r.coverability_ran &&
       (!r.coverability.complete || std::any_of(r.bounds.begin(), r.bounds.end(),
                                                [](const PlaceBound& b) { return b.may_be_unbounded; })));
  if (may_grow) {
    r.growth = find_growth(net, space, options);
    if (r.growth && r.growth->confirmed()) {
      r.bounded = Verdict::fail;
      r.safe = Verdict::fail;
      r.bounds[r.growth->place].kind = BoundKind::unbounded;
    }
  }
  {
    const auto guards = detail::classify_guards(net, detail::bind_parameters(net, options.parameters));
    std::set<std::string> facts;
    for (TransitionIndex t = 0; t < r.transitions; ++t) {
      if (guards[t] == detail::GuardState::never) r.guard_false.push_back(t);
      if (guards[t] != detail::GuardState::maybe) continue;
      for (const auto& id : net.transition(t).guard->identifiers()) {
        if (net.find_fact(id) != nullptr) facts.insert(id);
      }
    }
    r.assumed_facts.assign(facts.begin(), facts.end());
  }

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

std::string binding_of(const Place& p) {
  if (p.behavior) return "behavior '" + p.behavior->behavior + "'";
  if (p.process) return "process '" + p.process->process + "'";
  return "place";
}

std::string growth_text(const PetriNet& net, const GrowthWitness& g) {
  return "place '" + net.place(g.place).id + "' grows without end: " +
         (g.prefix.empty() ? std::string("from the initial marking") : "after " + path_ids(net, g.prefix)) +
         ", the cycle " + path_ids(net, g.pump) + " can fire again and again, adding tokens each time (" +
         std::to_string(g.before) + " -> " + std::to_string(g.after) + " after " +
         std::to_string(g.rounds + 1) + " rounds)";
}

struct OnceResult {
  CheckResult result = CheckResult::passed;
  std::vector<std::string> assumed_facts;
  std::vector<std::uint8_t> fired;  // per transition
};

OnceResult check_once(const PetriNet& net, Diagnostics& diagnostics, const BehaviourCheckOptions& options,
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
  OnceResult out;
  out.assumed_facts = r.assumed_facts;
  out.fired.assign(r.transitions, 1);
  for (const TransitionIndex t : r.dead_transitions) out.fired[t] = 0;
  bool failed = false;
  // Found in the explored part: errors even when the exploration stopped short.
  for (const DoubleStart& d : r.double_started) {
    const Place& place = net.place(d.place);
    const std::string where = d.witness.marking.empty()
                                  ? "up to " + std::to_string(r.bounds[d.place].max_seen) +
                                        " tokens (the net is too large to search for the path)"
                                  : std::to_string(d.witness.marking[d.place]) + " tokens in marking " +
                                        marking_ids(net, d.witness.marking) + ", reached by " +
                                        path_ids(net, d.witness.path);
    diagnostics.error(place.where, prefix + binding_of(place) + " is started twice: place '" + place.id +
                                       "' holds " + where);
    failed = true;
  }
  if (r.growth && r.growth->confirmed()) {
    diagnostics.error(net.place(r.growth->place).where, prefix + "unbounded: " + growth_text(net, *r.growth));
    failed = true;
  }
  if (!r.complete()) {
    if (r.growth && !r.growth->confirmed()) {
      diagnostics.note(net.place(r.growth->place).where,
                       prefix + "place '" + net.place(r.growth->place).id + "' may grow without end: " +
                           (r.growth->prefix.empty() ? std::string("from the initial marking")
                                                     : "after " + path_ids(net, r.growth->prefix)) +
                           ", the cycle " + path_ids(net, r.growth->pump) + " adds tokens to it");
    }
    if (!failed) {
      diagnostics.note(net.where, prefix + "behaviour not checked: " + incomplete_reason(r) +
                                      " (or run tripodal-net analyze for the full analysis)");
    }
    out.result = failed ? CheckResult::failed : CheckResult::not_decided;
    out.fired.assign(r.transitions, 1);  // not known: no warning
    return out;
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
  failed = failed || r.deadlock_count != 0 || r.outcome == Verdict::fail;
  out.result = failed ? CheckResult::failed : CheckResult::passed;
  return out;
}

}  // namespace

std::string assumption_text(const std::vector<std::string>& facts) {
  if (facts.empty()) return {};
  std::string out = facts.size() == 1 ? "the assumption that fact " : "the assumption that facts ";
  for (std::size_t i = 0; i < facts.size(); ++i) out += (i == 0 ? "" : ", ") + facts[i];
  return out + " can take any value";
}

bool check_behaviour(const PetriNet& net, Diagnostics& diagnostics, const BehaviourCheckOptions& options) {
  return check_behaviour_detailed(net, diagnostics, options).checked;
}

BehaviourCheckResult check_behaviour_detailed(const PetriNet& net, Diagnostics& diagnostics,
                                              const BehaviourCheckOptions& options) {
  BehaviourCheckResult result;
  bool has_outcome = false;
  for (const Place& p : net.places()) has_outcome = has_outcome || p.outcome != Outcome::none;
  bool passed = true;
  if (options.process_net && options.semantics == Semantics::engine && net.level == NetLevel::low &&
      !has_outcome) {
    diagnostics.error(net.where,
                      "net '" + net.id +
                          "' has no outcome place: the process supervisor ends a process "
                          "when a place with outcome=\"success\" or outcome=\"fault\" is marked, so this one "
                          "could never finish (mark its end places with an outcome)");
    passed = false;
  }
  const std::vector<ParameterValues> sets = options.parameter_sets.empty()
                                                ? std::vector<ParameterValues>{ParameterValues{}}
                                                : options.parameter_sets;
  std::set<std::string> facts;
  std::vector<std::uint8_t> fired_somewhere(net.transitions().size(), 0);
  bool all_decided = true;
  for (const ParameterValues& given : sets) {
    // Parameters without a default and not given are checked with every combination of the
    // values their guards name (the process is meant to run with one of them).
    std::vector<const VariableDecl*> open;
    std::vector<std::vector<Value>> values;
    std::size_t combinations = 1;
    bool too_many = false;
    for (const VariableDecl& p : net.parameters) {
      if (p.default_value || given.count(p.name) != 0) continue;
      open.push_back(&p);
      values.push_back(candidate_values(net, p));
      combinations *= values.back().size();
      if (combinations > kCheckParameterCombinations) {
        diagnostics.note(net.where,
                         "behaviour not checked: more than " + std::to_string(kCheckParameterCombinations) +
                             " combinations of the values the guards give parameters without defaults "
                             "(run tripodal-net analyze with --param NAME=VALUE)");
        too_many = true;
        break;
      }
    }
    if (too_many) {
      all_decided = false;
      continue;
    }
    std::string given_prefix;
    if (!options.parameter_sets.empty()) {
      for (const auto& [k, v] : given)
        given_prefix += (given_prefix.empty() ? "with " : ", ") + k + "=" + tripodal::to_string(v);
    }
    std::vector<std::size_t> pick(open.size(), 0);
    for (std::size_t c = 0; c < combinations; ++c) {
      ParameterValues parameters = given;
      std::string prefix = given_prefix;
      for (std::size_t i = 0; i < open.size(); ++i) {
        parameters[open[i]->name] = values[i][pick[i]];
        prefix +=
            (prefix.empty() ? "with " : ", ") + open[i]->name + "=" + tripodal::to_string(values[i][pick[i]]);
      }
      if (!prefix.empty()) prefix += ": ";
      const OnceResult once = check_once(net, diagnostics, options, parameters, prefix);
      ++result.parameter_sets;
      passed = once.result == CheckResult::passed && passed;
      all_decided = all_decided && once.result != CheckResult::not_decided;
      facts.insert(once.assumed_facts.begin(), once.assumed_facts.end());
      for (std::size_t t = 0; t < once.fired.size(); ++t) fired_somewhere[t] |= once.fired[t];
      for (std::size_t i = 0; i < open.size() && ++pick[i] == values[i].size(); ++i) pick[i] = 0;
    }
  }
  // A transition that fires for no parameter set checked is a mistake (a guard that can never
  // hold, a branch always overtaken, an input never marked), unless the search was cut. Not for
  // the sets a robot gives: a robot's parameters leave out the branches of other robots.
  if (all_decided && options.parameter_sets.empty()) {
    for (TransitionIndex t = 0; t < fired_somewhere.size(); ++t) {
      if (fired_somewhere[t] != 0) continue;
      const Transition& tr = net.transition(t);
      diagnostics.warning(tr.where, "transition '" + tr.id + "' never fires" +
                                        (result.parameter_sets > 1 ? " for any parameter set checked" : "") +
                                        (tr.guard ? " (guard '" + tr.guard->text() + "')" : std::string()));
    }
  }
  result.checked = passed && all_decided;
  result.assumed_facts.assign(facts.begin(), facts.end());
  return result;
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
