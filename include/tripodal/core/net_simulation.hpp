// Simulation of a configuration net against a timed event script, without a robot: the engine
// steps at the script's times and at its own delay deadlines. Backs `tripodal-net simulate` and
// lets an author see how a net reacts to a scenario before it runs on a robot.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tripodal/core/engine.hpp"
#include "tripodal/core/event_script.hpp"

namespace tripodal {

struct SimulationOptions {
  Time end_time = time_from_seconds(3600.0);  ///< stop here at the latest
  bool stop_at_outcome = true;           ///< stop once an outcome place is marked
  /// false: a script event no transition of the net waits for is an error (likely a typo).
  bool allow_unknown_events = false;
  EngineOptions engine;
};

/// One line of a simulation trace.
struct TraceEntry {
  enum class Kind { firing, fact_set, event_dropped, error };
  Kind kind = Kind::firing;
  Time time{};
  TransitionIndex transition = 0;  ///< firing
  std::string name;                ///< transition id, fact name or event name
  std::string detail;              ///< firing: description; fact_set: value; error: message
  std::string event;               ///< firing: the event it consumed
  /// firing: the marked places after it, ascending (a trace of a large net keeps only these).
  std::vector<std::pair<PlaceIndex, Tokens>> marked_after;
};

struct SimulationResult {
  std::vector<TraceEntry> trace;
  StepStatus status = StepStatus::ok;  ///< livelock ends the simulation
  std::string error;
  Time end_time{};  ///< the engine's time when the simulation stopped
  Outcome outcome = Outcome::none;
  std::string outcome_place;
  std::string fault_message;
  Marking final_marking;

  /// The trace, one line per entry ("   0.500 s  fire t3 [localizer.lost] ...  marking: P1 P4"),
  /// then the outcome line. Place ids come from `net`.
  [[nodiscard]] std::string str(const PetriNet& net) const;
};

/// Runs one net instance through scripts. Each run starts from the initial marking at time 0.
class NetSimulation final {
 public:
  /// Throws ConfigError as Engine does (parameters, guards).
  NetSimulation(const PetriNet& net, const ParameterValues& parameters, SimulationOptions options = {});

  /// Checks the script against the net: unknown facts, values not of the fact's type, and
  /// (unless allowed) events of no transition. Throws ConfigError listing each with its line:col.
  void validate(const EventScript& script) const;
  /// Validates, then runs until options().end_time, an outcome (if stop_at_outcome) or a livelock.
  SimulationResult run(const EventScript& script);

  [[nodiscard]] const SimulationOptions& options() const noexcept { return options_; }
  [[nodiscard]] const Engine& engine() const noexcept { return engine_; }

 private:
  SimulationOptions options_;
  Engine engine_;
};

/// "P1 P4:2" — the marked places (count when above one), or "(empty)".
[[nodiscard]] std::string format_marking(const PetriNet& net, std::span<const Tokens> marking);

}  // namespace tripodal
