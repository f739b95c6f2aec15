#include "tripodal/core/net_history.hpp"

namespace tripodal {

void HistoryRecorder::on_firing(const Firing& firing) {
  firings_.push_back(RecordedFiring{firing.time, firing.transition, std::string(firing.transition_id),
                                    std::string(firing.event),
                                    std::vector<PlaceChange>(firing.changes.begin(), firing.changes.end()),
                                    Marking(firing.marking_after.begin(), firing.marking_after.end())});
}

std::vector<std::string> HistoryRecorder::transition_ids() const {
  std::vector<std::string> out;
  out.reserve(firings_.size());
  for (const auto& f : firings_) out.push_back(f.transition_id);
  return out;
}

std::vector<TransitionIndex> HistoryRecorder::sequence() const {
  std::vector<TransitionIndex> out;
  out.reserve(firings_.size());
  for (const auto& f : firings_) out.push_back(f.transition);
  return out;
}

}  // namespace tripodal
