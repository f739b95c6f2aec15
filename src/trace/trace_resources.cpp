#include "tripodal/trace/trace_resources.hpp"

#include <algorithm>

#include "tripodal/trace/trace_reader.hpp"

namespace tripodal::trace {

TraceSummary summarize_trace(const std::filesystem::path& trace) {
  TraceSummary s;
  TraceReader reader(trace);
  TraceRecord rec;
  while (reader.next(rec)) {
    const Time t = stamp_of(rec.data);
    if (s.empty) s.first = t;
    s.last = s.empty ? t : std::max(s.last, t);
    s.empty = false;
  }
  s.channels = reader.channels();
  if (reader.state() == ReadState::kTruncated) s.warning = reader.warning();
  return s;
}

const ChannelInfo* find_channel(const std::vector<ChannelInfo>& channels, std::string_view name, ChannelKind kind) noexcept {
  const auto it = std::find_if(channels.begin(), channels.end(), [&](const ChannelInfo& c) { return c.name == name && c.kind == kind; });
  return it == channels.end() ? nullptr : &*it;
}

TraceResources::TraceResources(const std::vector<ChannelInfo>& channels, Duration max_age, const std::vector<std::string>& skip) {
  for (const ChannelInfo& c : channels) {
    if (std::find(skip.begin(), skip.end(), c.name) != skip.end()) continue;
    std::unique_ptr<CResource> r;
    switch (c.kind) {
      case ChannelKind::kLaser: r = std::make_unique<LaserResource>(c.name, max_age); break;
      case ChannelKind::kOdometry: r = std::make_unique<OdometryResource>(c.name, max_age); break;
      case ChannelKind::kSonar: r = std::make_unique<SonarResource>(c.name, max_age); break;
      case ChannelKind::kInfrared: r = std::make_unique<InfraredResource>(c.name, max_age); break;
      case ChannelKind::kBumper: r = std::make_unique<BumperResource>(c.name, max_age); break;
      case ChannelKind::kBattery: r = std::make_unique<BatteryResource>(c.name, max_age); break;
      case ChannelKind::kGyro: r = std::make_unique<GyroResource>(c.name, max_age); break;
      case ChannelKind::kCommand:
      case ChannelKind::kEvent: break;
    }
    if (!r) continue;
    if (by_channel_.size() <= c.id) by_channel_.resize(c.id + 1u, nullptr);
    by_channel_[c.id] = r.get();
    owned_.push_back(std::move(r));
  }
}

void TraceResources::add_to(ResourceTable& table) {
  for (const auto& r : owned_) table.add(*r);
}

}  // namespace tripodal::trace
