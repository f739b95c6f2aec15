// The Petri-net execution engine of the sequencing layer: runs a configuration net (a process's
// low-level net or a task's high-level net) against posted events, facts and time, and tells the
// process supervisor which behaviors are active and which outcome the net reached.
//
// Semantics (docs/engine.md): a transition is enabled when its input and read places hold at
// least the arc weights, its inhibitor places fewer, firing keeps every output place within its
// capacity, and its guard holds. Immediate transitions fire as soon as enabled, delayed ones once
// continuously enabled for their delay, event transitions only when their event is posted.
// Conflicts: higher priority first, then declaration order. Deterministic.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/petri_net.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/core/value.hpp"

namespace tripodal {

/// Process parameter values by name, fixed for the lifetime of an Engine.
using ParameterValues = std::map<std::string, Value, std::less<>>;

/// Index of an event name among the events the net's transitions wait for.
using EventId = std::uint32_t;
/// Index of a declared fact (PetriNet::facts).
using FactId = std::uint32_t;

struct EngineOptions {
  /// Livelock budget: the most transitions one step may fire at one instant of time. A net
  /// whose immediate transitions cycle would fire forever; the step stops after this many
  /// firings with StepStatus::livelock.
  std::size_t max_firings_per_instant = 100'000;
  /// The engine's time before the first step; transitions enabled by the initial marking count
  /// their delay from here.
  Time start_time{};
};

/// Tokens taken from and put into one place by one firing.
struct PlaceChange {
  PlaceIndex place = 0;
  Tokens consumed = 0;
  Tokens produced = 0;
};

/// One firing as observers see it. Views are valid during the observer call only.
struct Firing {
  Time time{};
  TransitionIndex transition = 0;
  std::string_view transition_id;
  std::string_view event;                ///< the event it consumed; empty if none
  std::span<const PlaceChange> changes;  ///< the places its normal arcs touch, by place index
  std::span<const Tokens> marking_after;
};

/// Sees every firing of the engines it is added to. Called synchronously from step(), after the
/// marking has changed; must not call back into the engine's non-const methods.
class EngineObserver {
 public:
  virtual ~EngineObserver() = default;
  EngineObserver() = default;
  EngineObserver(const EngineObserver&) = default;
  EngineObserver& operator=(const EngineObserver&) = default;

  void notify(const Firing& firing) { on_firing(firing); }

 protected:
  virtual void on_firing(const Firing& firing) = 0;
};

enum class StepStatus {
  ok,
  livelock,         ///< more than max_firings_per_instant firings at one instant; see StepResult
  time_regressed,   ///< step(now) with now earlier than the engine's time; nothing was done
};

/// What one step did. Owned by the engine and reused by the next step (no allocation in steady
/// state); copy what you need to keep.
struct StepResult {
  StepStatus status = StepStatus::ok;
  std::size_t firings = 0;
  /// Events no enabled transition was waiting for when they were processed (and, after a
  /// livelock, the events the step did not reach), in posting order. They are dropped.
  std::vector<std::string> unconsumed_events;
  /// Places binding a behavior or referring to a process that became marked / unmarked during
  /// the step (relative to the end of the previous step), ascending place index.
  std::vector<PlaceIndex> activated;
  std::vector<PlaceIndex> deactivated;
  /// On livelock: the transitions repeating in the tail of the firing sequence, in firing order.
  std::vector<TransitionIndex> loop;
  /// On error: a message naming the transitions in the loop (or the time problem).
  std::string error;

  [[nodiscard]] bool ok() const noexcept { return status == StepStatus::ok; }
};

/// The outcome the net reached, for the process supervisor.
struct OutcomeState {
  Outcome outcome = Outcome::none;
  PlaceIndex place = 0;         ///< the outcome place, when outcome != none
  std::string_view place_id;
  std::string_view message;     ///< fault message of the place (empty for success)
};

/// Executes one net instance. Construction compiles the net into flat arrays; step() is
/// allocation-free in steady state and its firing cost does not depend on the net's size.
/// Not thread-safe: one thread steps an engine.
class Engine final {
 public:
  /// Compiles `net` with `parameters` (declared parameters only; defaults applied). Throws
  /// ConfigError listing every problem: a missing required parameter, a parameter of the wrong
  /// type or not declared, a guard reading an undeclared name, or comparing a declared name with
  /// a value of another type. The net is copied.
  Engine(const PetriNet& net, const ParameterValues& parameters = {}, EngineOptions options = {});
  ~Engine();
  Engine(Engine&&) noexcept;
  Engine& operator=(Engine&&) noexcept;
  Engine(const Engine&) = delete;
  Engine& operator=(const Engine&) = delete;

  /// Advances the engine's time to `now` and fires, in order: delayed transitions that fall due
  /// up to `now` (each at its own deadline, with what they enable), then the posted events one
  /// after another (each consumed by at most one transition, then the net settles). Returns when
  /// nothing more can fire at `now`. `now` must not be earlier than now().
  const StepResult& step(Time now);
  const StepResult& step(Time now, std::span<const EventId> events);
  const StepResult& step(Time now, std::span<const std::string_view> events);
  const StepResult& step(Time now, std::initializer_list<std::string_view> events);

  /// The id of a event some transition waits for; nullopt for a name no transition uses.
  [[nodiscard]] std::optional<EventId> event_id(std::string_view name) const noexcept;
  [[nodiscard]] std::string_view event_name(EventId id) const;
  [[nodiscard]] std::size_t event_count() const noexcept;

  /// Sets a declared fact (throws std::invalid_argument for an unknown fact or a value of the
  /// wrong type). Transitions whose guards read it are re-examined at now(); nothing fires until
  /// the next step.
  void set_fact(std::string_view name, Value value);
  void set_fact(FactId fact, Value value);
  /// Makes the fact unknown again: guards reading it are false.
  void clear_fact(FactId fact);
  [[nodiscard]] std::optional<FactId> fact_id(std::string_view name) const noexcept;
  [[nodiscard]] const Value* fact(FactId fact) const;
  [[nodiscard]] const Value& parameter(std::string_view name) const;

  [[nodiscard]] Time now() const noexcept;
  [[nodiscard]] std::span<const Tokens> marking() const noexcept;
  [[nodiscard]] Tokens tokens(PlaceIndex place) const;
  /// Enabled by marking and guard (a delayed transition may still be waiting for its delay, an
  /// event transition for its event).
  [[nodiscard]] bool is_enabled(TransitionIndex t) const;
  /// The earliest time a delayed transition (without event) is due; nullopt when none is timing.
  [[nodiscard]] std::optional<Time> next_deadline() const noexcept;

  /// The reached outcome: a marked fault place wins over a marked success place, then the lowest
  /// place index. Outcome::none when no outcome place is marked.
  [[nodiscard]] OutcomeState outcome() const noexcept;
  /// Marked places that bind a behavior or refer to a process, ascending.
  [[nodiscard]] std::vector<PlaceIndex> active_bindings() const;

  /// Observers are not owned; remove one before destroying it.
  void add_observer(EngineObserver& observer);
  void remove_observer(const EngineObserver& observer) noexcept;

  /// Back to the initial marking with facts at their defaults, at `start`.
  void reset(Time start);

  [[nodiscard]] const PetriNet& net() const noexcept;
  [[nodiscard]] const EngineOptions& options() const noexcept;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

[[nodiscard]] std::string_view to_string(StepStatus s) noexcept;

}  // namespace tripodal
