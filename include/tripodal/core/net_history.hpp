// A recording engine observer: keeps every firing (time, transition, event, marking change and
// marking after) for tests, the simulator's trace and post-mortem inspection of a process run.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "tripodal/core/engine.hpp"

namespace tripodal {

struct RecordedFiring {
  Time time{};
  TransitionIndex transition = 0;
  std::string transition_id;
  std::string event;  ///< empty when the transition has no event
  std::vector<PlaceChange> changes;
  Marking marking_after;
};

/// Records the firings of the engines it observes. Allocates per firing: for tests and tools,
/// not for a control loop.
class HistoryRecorder final : public EngineObserver {
 public:
  [[nodiscard]] const std::vector<RecordedFiring>& firings() const noexcept { return firings_; }
  [[nodiscard]] std::size_t size() const noexcept { return firings_.size(); }
  /// The fired transitions' ids in firing order.
  [[nodiscard]] std::vector<std::string> transition_ids() const;
  /// The fired transitions' indices in firing order.
  [[nodiscard]] std::vector<TransitionIndex> sequence() const;
  void clear() noexcept { firings_.clear(); }

 protected:
  void on_firing(const Firing& firing) override;

 private:
  std::vector<RecordedFiring> firings_;
};

}  // namespace tripodal
