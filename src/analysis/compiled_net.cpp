#include "compiled_net.hpp"

#include <algorithm>
#include <string_view>
#include <unordered_map>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/registry.hpp"

namespace tripodal::analysis::detail {

std::vector<Value> bind_parameters(const PetriNet& net, const ParameterValues& given) {
  Diagnostics problems;
  const std::string net_name = net.id.empty() ? std::string("the net") : "net '" + net.id + "'";
  std::vector<Value> values(net.parameters.size());
  for (std::size_t i = 0; i < net.parameters.size(); ++i) {
    const VariableDecl& decl = net.parameters[i];
    const auto it = given.find(decl.name);
    if (it != given.end()) {
      if (type_of(it->second) != decl.type) {
        problems.error(net.where, "parameter '" + decl.name + "' of " + net_name + " must be a " +
                                      std::string(to_string(decl.type)) + ", got " + tripodal::to_string(it->second));
      }
      values[i] = it->second;
    } else if (decl.default_value) {
      values[i] = *decl.default_value;
    } else {
      problems.error(net.where, "missing required parameter '" + decl.name + "' (" +
                                    std::string(to_string(decl.type)) + ") of " + net_name +
                                    ": give it with --param " + decl.name + "=VALUE");
    }
  }
  for (const auto& [name, value] : given) {
    if (net.find_parameter(name) == nullptr) {
      std::string declared;
      for (const auto& d : net.parameters) declared += (declared.empty() ? "" : ", ") + d.name;
      std::vector<std::string> names;
      for (const auto& d : net.parameters) names.push_back(d.name);
      const auto close = closest_name(name, names);
      problems.error(net.where, "unknown parameter '" + name + "' for " + net_name +
                                    " (declared: " + (declared.empty() ? std::string("none") : declared) +
                                    ")" + (close ? "; did you mean '" + *close + "'?" : std::string()));
    }
  }
  for (const Transition& tr : net.transitions()) {
    if (!tr.guard) continue;
    for (const std::string& name : tr.guard->identifiers()) {
      if (net.find_parameter(name) == nullptr && net.find_fact(name) == nullptr) {
        problems.error(tr.where, "guard '" + tr.guard->text() + "' of transition '" + tr.id + "' reads '" + name +
                                     "', which is neither a parameter nor a fact of " + net_name);
      }
    }
  }
  if (problems.has_errors()) throw ConfigError(std::move(problems));
  return values;
}

std::vector<GuardState> classify_guards(const PetriNet& net, const std::vector<Value>& parameter_values) {
  std::vector<GuardState> out(net.transitions().size(), GuardState::always);
  std::vector<const Value*> slots;
  for (TransitionIndex t = 0; t < out.size(); ++t) {
    const Transition& tr = net.transition(t);
    if (!tr.guard) continue;
    const auto& ids = tr.guard->identifiers();
    slots.assign(ids.size(), nullptr);
    for (std::size_t s = 0; s < ids.size(); ++s) {
      for (std::size_t i = 0; i < net.parameters.size() && i < parameter_values.size(); ++i) {
        if (net.parameters[i].name == ids[s]) slots[s] = &parameter_values[i];
      }
    }
    switch (tr.guard->partial_evaluate(slots)) {
      case Guard::Truth::no:
        out[t] = GuardState::never;
        break;
      case Guard::Truth::yes:
        out[t] = GuardState::always;
        break;
      case Guard::Truth::unknown:
        out[t] = GuardState::maybe;
        break;
    }
  }
  return out;
}

CompiledNet::CompiledNet(const PetriNet& net, const ParameterValues& parameters, CompileOptions options)
    : places(net.places().size()), transitions(net.transitions().size()), semantics(options.semantics) {
  const std::vector<Value> values = bind_parameters(net, parameters);
  const auto& pl = net.places();
  kind.resize(transitions);
  guard.resize(transitions);
  decisive.assign(transitions, 0);
  check_begin.assign(1, 0);
  change_begin.assign(1, 0);
  is_outcome.assign(places, 0);
  for (PlaceIndex p = 0; p < places; ++p) is_outcome[p] = pl[p].outcome != Outcome::none ? 1 : 0;
  std::vector<Change> scratch;
  guard = classify_guards(net, values);

  for (TransitionIndex t = 0; t < transitions; ++t) {
    const Transition& tr = net.transition(t);
    kind[t] = !tr.event.empty() ? Kind::event : (tr.delay.count() > 0 ? Kind::delayed : Kind::immediate);
    // Only the places whose count a firing changes matter to the search.
    scratch.clear();
    tripodal::detail::fold_transition(net, tr, {.capacities_and_inhibitors = !options.monotone}, checks, scratch);
    for (const Change& d : scratch) {
      if (d.consumed != d.produced) changes.push_back(d);
    }
    check_begin.push_back(static_cast<std::uint32_t>(checks.size()));
    change_begin.push_back(static_cast<std::uint32_t>(changes.size()));
  }

  // Conflict order as in the engine.
  const std::vector<TransitionIndex> order = tripodal::detail::conflict_order(net);
  std::unordered_map<std::string_view, std::size_t> event_index;
  std::vector<std::vector<TransitionIndex>> by_event;
  for (const TransitionIndex t : order) {
    const Transition& tr = net.transition(t);
    if (kind[t] != Kind::event) {
      urgent_order.push_back(t);
      // An enabled immediate transition with a certain guard is always ready: it or something
      // ranked above it fires, nothing below it.
      if (kind[t] == Kind::immediate && guard[t] == GuardState::always) decisive[t] = 1;
      continue;
    }
    const auto [it, added] = event_index.try_emplace(tr.event, by_event.size());
    if (added) {
      by_event.push_back({t});
    } else {
      by_event[it->second].push_back(t);
    }
    // A listener without delay and with a certain guard takes its event whenever it is enabled.
    if (tr.delay.count() == 0 && guard[t] == GuardState::always) decisive[t] = 1;
  }
  event_begin.assign(1, 0);
  for (const auto& l : by_event) {
    listeners.insert(listeners.end(), l.begin(), l.end());
    event_begin.push_back(static_cast<std::uint32_t>(listeners.size()));
  }

  rank.assign(transitions, 0);
  group.assign(transitions, kNoGroup);
  if (semantics == Semantics::interleaving) {
    for (TransitionIndex t = 0; t < transitions; ++t) rank[t] = static_cast<std::uint32_t>(t);
  } else {
    std::uint32_t next = 0;
    for (const TransitionIndex t : urgent_order) rank[t] = next++;
    for (std::size_t e = 0; e + 1 < event_begin.size(); ++e) {
      for (std::uint32_t i = event_begin[e]; i < event_begin[e + 1]; ++i) {
        rank[listeners[i]] = next++;
        group[listeners[i]] = static_cast<std::uint32_t>(e);
      }
    }
  }
  std::vector<std::uint32_t> watched(transitions, 0xFFFFFFFFU);
  watch_begin.assign(places + 1, 0);
  for (TransitionIndex t = 0; t < transitions; ++t) {
    if (guard[t] == GuardState::never) continue;
    for (std::uint32_t i = check_begin[t]; i < check_begin[t + 1]; ++i) {
      if (checks[i].lo > 0) {
        watched[t] = checks[i].place;
        ++watch_begin[checks[i].place + 1];
        break;
      }
    }
    if (watched[t] == 0xFFFFFFFFU) unwatched.push_back(t);
  }
  for (std::size_t p = 0; p < places; ++p) watch_begin[p + 1] += watch_begin[p];
  watchers.resize(watch_begin[places]);
  std::vector<std::uint32_t> fill(watch_begin.begin(), watch_begin.end() - 1);
  for (TransitionIndex t = 0; t < transitions; ++t) {
    if (watched[t] != 0xFFFFFFFFU) watchers[fill[watched[t]]++] = t;
  }
}

}  // namespace tripodal::analysis::detail
