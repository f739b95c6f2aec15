// Seeded random nets and scenarios: the incremental engine must fire exactly the sequence a naive
// reference engine (re-examining every transition after every firing) fires, be deterministic,
// and respect the net's invariants at every firing.
#include <spdlog/spdlog.h>

#include <catch2/catch.hpp>

#include <algorithm>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "engine_test_nets.hpp"
#include "tripodal/core/engine.hpp"
#include "tripodal/core/net_history.hpp"

using namespace tripodal;

namespace {

struct Fired {
  Time time{};
  TransitionIndex transition = 0;
  std::string event;
  bool operator==(const Fired&) const = default;
};

/// The semantics of docs/engine.md written as directly as possible, without any incremental state.
class ReferenceEngine {
 public:
  ReferenceEngine(const PetriNet& net, ParameterValues parameters, std::size_t budget)
      : net_(net), parameters_(std::move(parameters)), budget_(budget), marking_(net.initial_marking()) {
    for (const auto& f : net.facts) {
      if (f.default_value) facts_[f.name] = *f.default_value;
    }
    for (const auto& p : net.parameters) {
      if (!parameters_.count(p.name) && p.default_value) parameters_[p.name] = *p.default_value;
    }
    enabled_.assign(net.transitions().size(), false);
    since_.assign(net.transitions().size(), Time{});
    refresh(std::nullopt);
  }

  void set_fact(const std::string& name, const Value& v) {
    facts_[name] = v;
    refresh(std::nullopt);
  }

  // Returns false on livelock.
  bool step(Time now, const std::vector<std::string>& events, std::vector<std::string>& unconsumed) {
    count_ = 0;
    for (;;) {
      std::optional<Time> due;
      for (TransitionIndex t = 0; t < net_.transitions().size(); ++t) {
        const Transition& tr = net_.transition(t);
        if (!tr.event.empty() || tr.delay.count() == 0 || !enabled_[t]) continue;
        const Time d = since_[t] + tr.delay;
        if (d <= now && (!due || d < *due)) due = d;
      }
      if (!due) break;
      if (*due > cur_) {
        cur_ = *due;
        count_ = 0;
      }
      if (!settle()) return livelock(events, 0, unconsumed);
    }
    if (now > cur_) {
      cur_ = now;
      count_ = 0;
    }
    if (!settle()) return livelock(events, 0, unconsumed);
    for (std::size_t i = 0; i < events.size(); ++i) {
      std::optional<TransitionIndex> best;
      for (TransitionIndex t = 0; t < net_.transitions().size(); ++t) {
        const Transition& tr = net_.transition(t);
        if (tr.event != events[i] || !enabled_[t] || since_[t] + tr.delay > cur_) continue;
        if (!best || tr.priority > net_.transition(*best).priority) best = t;
      }
      if (!best) {
        unconsumed.push_back(events[i]);
        continue;
      }
      if (!fire(*best, events[i]) || !settle()) return livelock(events, i + 1, unconsumed);
    }
    return true;
  }

  [[nodiscard]] const std::vector<Fired>& fired() const { return fired_; }
  [[nodiscard]] const Marking& marking() const { return marking_; }

 private:
  bool livelock(const std::vector<std::string>& events, std::size_t from, std::vector<std::string>& unconsumed) {
    for (std::size_t i = from; i < events.size(); ++i) unconsumed.push_back(events[i]);
    return false;
  }

  [[nodiscard]] bool enabled_now(TransitionIndex t) const {
    const Transition& tr = net_.transition(t);
    std::map<PlaceIndex, long> consumed;
    std::map<PlaceIndex, long> produced;
    for (const auto& a : tr.inputs) consumed[a.place] += a.weight;
    for (const auto& a : tr.outputs) produced[a.place] += a.weight;
    for (const auto& [p, w] : consumed) {
      if (marking_[p] < w) return false;
    }
    for (const auto& a : tr.reads) {
      if (marking_[a.place] < a.weight) return false;
    }
    for (const auto& a : tr.inhibitors) {
      if (marking_[a.place] >= a.weight) return false;
    }
    for (PlaceIndex p = 0; p < marking_.size(); ++p) {
      const auto& cap = net_.place(p).capacity;
      if (cap && static_cast<long>(marking_[p]) - consumed[p] + produced[p] > static_cast<long>(*cap)) return false;
    }
    if (!tr.guard) return true;
    std::vector<const Value*> slots;
    for (const auto& name : tr.guard->identifiers()) {
      const auto p = parameters_.find(name);
      const auto f = facts_.find(name);
      slots.push_back(p != parameters_.end() ? &p->second : f != facts_.end() ? &f->second : nullptr);
    }
    return tr.guard->evaluate(slots);
  }

  void refresh(std::optional<TransitionIndex> just_fired) {
    for (TransitionIndex t = 0; t < net_.transitions().size(); ++t) {
      const bool e = enabled_now(t);
      if (just_fired == t) enabled_[t] = false;
      if (e && !enabled_[t]) since_[t] = cur_;
      enabled_[t] = e;
    }
  }

  bool fire(TransitionIndex t, const std::string& event) {
    if (count_ == budget_) return false;
    ++count_;
    const Transition& tr = net_.transition(t);
    for (const auto& a : tr.inputs) marking_[a.place] -= a.weight;
    for (const auto& a : tr.outputs) marking_[a.place] += a.weight;
    fired_.push_back(Fired{cur_, t, event});
    refresh(t);
    return true;
  }

  bool settle() {
    for (;;) {
      std::optional<TransitionIndex> best;
      for (TransitionIndex t = 0; t < net_.transitions().size(); ++t) {
        const Transition& tr = net_.transition(t);
        if (!tr.event.empty() || !enabled_[t] || since_[t] + tr.delay > cur_) continue;
        if (!best || tr.priority > net_.transition(*best).priority) best = t;
      }
      if (!best) return true;
      if (!fire(*best, {})) return false;
    }
  }

  const PetriNet& net_;
  ParameterValues parameters_;
  std::map<std::string, Value> facts_;
  std::size_t budget_;
  Marking marking_;
  std::vector<bool> enabled_;
  std::vector<Time> since_;
  Time cur_{};
  std::size_t count_ = 0;
  std::vector<Fired> fired_;
};

/// Checks every firing against the net's rules, from the marking after and the changes.
class InvariantChecker final : public EngineObserver {
 public:
  InvariantChecker(const PetriNet& net, bool conservative) : net_(net), conservative_(conservative) {
    const Marking m = net.initial_marking();
    for (const Tokens k : m) total_ += k;
  }
  std::vector<Fired> fired;
  std::size_t violations = 0;

 protected:
  void on_firing(const Firing& f) override {
    fired.push_back(Fired{f.time, f.transition, std::string(f.event)});
    const Transition& tr = net_.transition(f.transition);
    Marking before(f.marking_after.begin(), f.marking_after.end());
    for (const PlaceChange& c : f.changes) before[c.place] = before[c.place] - c.produced + c.consumed;
    std::uint64_t total = 0;
    for (PlaceIndex p = 0; p < f.marking_after.size(); ++p) {
      const Tokens after = f.marking_after[p];
      total += after;
      if (after > 1'000'000) ++violations;  // a wrapped (negative) count
      if (net_.place(p).capacity && after > *net_.place(p).capacity) ++violations;
    }
    for (const auto& a : tr.inhibitors) {
      if (before[a.place] >= a.weight) ++violations;
    }
    for (const auto& a : tr.reads) {
      if (before[a.place] < a.weight) ++violations;
    }
    for (const auto& a : tr.inputs) {
      if (before[a.place] < a.weight) ++violations;
    }
    if (!tr.event.empty() && f.event != tr.event) ++violations;
    if (conservative_ && total != total_) ++violations;
  }

 private:
  const PetriNet& net_;
  bool conservative_;
  std::uint64_t total_ = 0;
};

struct Scenario {
  PetriNet net;
  ParameterValues parameters;
  bool conservative = false;
};

const std::vector<std::string> kEvents{"e0", "e1", "e2"};

Scenario random_net(std::mt19937& rng, bool conservative) {
  auto uniform = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  auto chance = [&](double p) { return std::bernoulli_distribution(p)(rng); };
  Scenario s;
  s.conservative = conservative;
  PetriNet& net = s.net;
  net.id = "random";
  net.parameters.push_back(VariableDecl{"mode", ValueType::string, Value{std::string("a")}, "", {}});
  net.facts.push_back(VariableDecl{"flag", ValueType::boolean, Value{false}, "", {}});
  net.facts.push_back(VariableDecl{"level", ValueType::number, std::nullopt, "", {}});
  if (chance(0.5)) s.parameters["mode"] = Value{std::string(chance(0.5) ? "a" : "b")};

  const int places = uniform(2, 10);
  const int transitions = uniform(1, 14);
  for (int p = 0; p < places; ++p) {
    Place pl = test::make_place(test::numbered('P', static_cast<std::size_t>(p)),
                                static_cast<Tokens>(uniform(0, 2)));
    if (!conservative && chance(0.3)) pl.capacity = std::max<Tokens>(pl.initial_tokens, static_cast<Tokens>(uniform(1, 4)));
    net.add_place(std::move(pl));
  }
  const char* guards[] = {"flag", "!flag", "level > 1", "mode == 'a'", "mode == 'b' || flag"};
  for (int t = 0; t < transitions; ++t) {
    Transition tr = test::make_transition(test::numbered('T', static_cast<std::size_t>(t)));
    tr.priority = uniform(-1, 1);
    const int kind = uniform(0, 9);
    if (kind < 4) tr.event = kEvents[static_cast<std::size_t>(uniform(0, 2))];
    if (kind >= 4 && kind < 7) tr.delay = from_seconds(0.25 * uniform(1, 6));
    if (kind == 3 && chance(0.5)) tr.delay = from_seconds(0.25 * uniform(1, 3));  // event after a delay
    if (chance(0.2)) tr.guard = Guard::parse(guards[uniform(0, 4)]);
    net.add_transition(std::move(tr));
  }
  auto place_id = [&] { return test::numbered('P', static_cast<std::size_t>(uniform(0, places - 1))); };
  for (int t = 0; t < transitions; ++t) {
    const std::string id = test::numbered('T', static_cast<std::size_t>(t));
    if (conservative) {
      // one token in, one token out: the total number of tokens never changes
      net.add_arc(place_id(), id);
      net.add_arc(id, place_id());
    } else {
      for (int i = uniform(1, 2); i > 0; --i) net.add_arc(place_id(), id, static_cast<Tokens>(uniform(1, 2)));
      for (int i = uniform(0, 2); i > 0; --i) net.add_arc(id, place_id(), static_cast<Tokens>(uniform(1, 2)));
    }
    if (chance(0.25)) net.add_arc(place_id(), id, static_cast<Tokens>(uniform(1, 2)), ArcKind::read);
    if (chance(0.25)) net.add_arc(place_id(), id, static_cast<Tokens>(uniform(1, 3)), ArcKind::inhibitor);
  }
  return s;
}

struct Action {
  Time time{};
  std::vector<std::string> events;
  std::optional<std::pair<std::string, Value>> fact;
};

std::vector<Action> random_actions(std::mt19937& rng) {
  auto uniform = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  std::vector<Action> actions;
  Time t{};
  for (int i = uniform(5, 40); i > 0; --i) {
    t += from_seconds(0.125 * uniform(0, 8));  // on the delays' grid: deadlines and steps coincide
    Action a;
    a.time = t;
    for (int e = uniform(0, 3); e > 0; --e) {
      a.events.push_back(uniform(0, 9) == 0 ? std::string("unknown") : kEvents[static_cast<std::size_t>(uniform(0, 2))]);
    }
    if (uniform(0, 4) == 0) {
      if (uniform(0, 1) == 0) {
        a.fact = std::make_pair(std::string("flag"), Value{uniform(0, 1) == 1});
      } else {
        a.fact = std::make_pair(std::string("level"), Value{static_cast<double>(uniform(0, 3))});
      }
    }
    actions.push_back(std::move(a));
  }
  return actions;
}

struct RunResult {
  std::vector<Fired> fired;
  std::vector<std::vector<std::string>> unconsumed;
  std::vector<StepStatus> status;
  Marking final_marking;
  std::size_t violations = 0;
};

constexpr std::size_t kBudget = 64;

/// Silences the engine's log (livelocks are logged as errors) while random scenarios run.
class QuietEngineLog {
 public:
  QuietEngineLog() {
    const Engine make_logger(test::ring_net(1, Duration{1}));
    logger_ = spdlog::get("tripodal.engine");
    level_ = logger_->level();
    logger_->set_level(spdlog::level::off);
  }
  ~QuietEngineLog() { logger_->set_level(level_); }
  QuietEngineLog(const QuietEngineLog&) = delete;
  QuietEngineLog& operator=(const QuietEngineLog&) = delete;

 private:
  std::shared_ptr<spdlog::logger> logger_;
  spdlog::level::level_enum level_ = spdlog::level::info;
};

RunResult run_engine(const Scenario& s, const std::vector<Action>& actions) {
  EngineOptions options;
  options.max_firings_per_instant = kBudget;
  Engine engine(s.net, s.parameters, options);
  InvariantChecker checker(s.net, s.conservative);
  engine.add_observer(checker);
  RunResult r;
  for (const Action& a : actions) {
    if (a.fact) {
      const StepResult& before = engine.step(a.time);
      if (!before.ok()) {
        r.unconsumed.push_back(a.events);  // the reference reports the events it did not reach
        r.status.push_back(before.status);
        break;
      }
      engine.set_fact(a.fact->first, a.fact->second);
    }
    std::vector<std::string_view> events(a.events.begin(), a.events.end());
    const StepResult& step = engine.step(a.time, std::span<const std::string_view>(events));
    r.unconsumed.push_back(step.unconsumed_events);
    r.status.push_back(step.status);
    if (!step.ok()) break;
  }
  r.fired = checker.fired;
  r.final_marking.assign(engine.marking().begin(), engine.marking().end());
  r.violations = checker.violations;
  return r;
}

RunResult run_reference(const Scenario& s, const std::vector<Action>& actions) {
  ReferenceEngine ref(s.net, s.parameters, kBudget);
  RunResult r;
  for (const Action& a : actions) {
    std::vector<std::string> unconsumed;
    bool ok = true;
    if (a.fact) {
      ok = ref.step(a.time, {}, unconsumed);
      if (ok) ref.set_fact(a.fact->first, a.fact->second);
    }
    if (ok) {
      ok = ref.step(a.time, a.events, unconsumed);
    } else {
      unconsumed = a.events;
    }
    r.unconsumed.push_back(unconsumed);
    r.status.push_back(ok ? StepStatus::ok : StepStatus::livelock);
    if (!ok) break;
  }
  r.fired = ref.fired();
  r.final_marking = ref.marking();
  return r;
}

}  // namespace

TEST_CASE("random nets: the engine fires exactly what the naive reference engine fires") {
  const QuietEngineLog quiet;
  std::size_t total_firings = 0;
  std::size_t livelocks = 0;
  for (std::uint32_t seed = 1; seed <= 2000; ++seed) {
    std::mt19937 rng(seed);
    const bool conservative = seed % 3 == 0;
    const Scenario s = random_net(rng, conservative);
    const std::vector<Action> actions = random_actions(rng);
    const RunResult engine = run_engine(s, actions);
    const RunResult reference = run_reference(s, actions);
    INFO("seed " << seed);
    REQUIRE(engine.violations == 0);
    REQUIRE(engine.fired.size() == reference.fired.size());
    REQUIRE(engine.fired == reference.fired);
    REQUIRE(engine.status == reference.status);
    REQUIRE(engine.unconsumed == reference.unconsumed);
    if (engine.status.back() == StepStatus::ok) REQUIRE(engine.final_marking == reference.final_marking);
    total_firings += engine.fired.size();
    if (engine.status.back() == StepStatus::livelock) ++livelocks;
  }
  // The generator must exercise the engine, not produce dead nets.
  CHECK(total_firings > 20000);
  CHECK(livelocks > 50);  // the livelock path is compared too
  CHECK(livelocks < 1000);  // most scenarios run to their end
}

TEST_CASE("random nets: two engines given the same inputs fire the same sequence") {
  const QuietEngineLog quiet;
  for (std::uint32_t seed = 1000; seed < 1200; ++seed) {
    std::mt19937 rng(seed);
    const Scenario s = random_net(rng, seed % 2 == 0);
    const std::vector<Action> actions = random_actions(rng);
    const RunResult a = run_engine(s, actions);
    const RunResult b = run_engine(s, actions);
    INFO("seed " << seed);
    REQUIRE(a.fired == b.fired);
    REQUIRE(a.unconsumed == b.unconsumed);
    REQUIRE(a.final_marking == b.final_marking);
  }
}

TEST_CASE("random conservative nets keep their token count") {
  const QuietEngineLog quiet;
  for (std::uint32_t seed = 5000; seed < 5200; ++seed) {
    std::mt19937 rng(seed);
    const Scenario s = random_net(rng, true);
    const RunResult r = run_engine(s, random_actions(rng));
    INFO("seed " << seed);
    REQUIRE(r.violations == 0);
    std::uint64_t before = 0;
    std::uint64_t after = 0;
    for (const Tokens k : s.net.initial_marking()) before += k;
    for (const Tokens k : r.final_marking) after += k;
    REQUIRE(before == after);
  }
}
