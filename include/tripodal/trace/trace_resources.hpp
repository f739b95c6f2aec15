// TraceResources: the resources a replayed trace publishes into — one per sensor channel, named as
// its channel — and the sink that hands each replayed reading to its resource. Both test kits
// replay through it: the behavior harness and the trace hardware a whole robot runs on (testing/).
#pragma once

#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "tripodal/core/time.hpp"
#include "tripodal/resources/resource.hpp"
#include "tripodal/trace/trace_replay.hpp"

namespace tripodal::trace {

/// What a first pass over a trace finds, without keeping any record.
struct TraceSummary {
  std::vector<ChannelInfo> channels;
  bool empty = true;
  Time first{};  ///< stamp of the first record (0 for an empty trace)
  Time last{};   ///< the latest stamp of a whole record
  /// Empty, or the reader's warning for a trace cut inside a record: it replays up to `last`.
  std::string warning;
};

/// Reads `trace` once to its end. Throws TraceIoError / TraceFormatError (with the byte offset).
[[nodiscard]] TraceSummary summarize_trace(const std::filesystem::path& trace);

/// The channel called `name` of kind `kind`; nullptr when the trace has none.
[[nodiscard]] const ChannelInfo* find_channel(const std::vector<ChannelInfo>& channels, std::string_view name,
                                              ChannelKind kind) noexcept;

/// Owns one resource per sensor channel and publishes replayed readings into them. Command and
/// event records are not readings: a subclass may override on_command/on_event to keep them.
class TraceResources : public TraceSink {
 public:
  /// A resource (max_age `max_age`, 0: never stale) for every sensor channel of `channels` whose
  /// name is not in `skip` (channels the consumer computes itself, e.g. the controller's odometry).
  TraceResources(const std::vector<ChannelInfo>& channels, Duration max_age, const std::vector<std::string>& skip = {});

  /// Adds every resource to `table` (in channel order).
  void add_to(ResourceTable& table);
  [[nodiscard]] std::size_t size() const noexcept { return owned_.size(); }

  void on_laser(const ChannelInfo& c, const LaserScan& r) final { publish(c, r); }
  void on_odometry(const ChannelInfo& c, const OdometryReading& r) final { publish(c, r); }
  void on_sonar(const ChannelInfo& c, const SonarReading& r) final { publish(c, r); }
  void on_infrared(const ChannelInfo& c, const InfraredReading& r) final { publish(c, r); }
  void on_bumper(const ChannelInfo& c, const BumperReading& r) final { publish(c, r); }
  void on_battery(const ChannelInfo& c, const BatteryReading& r) final { publish(c, r); }
  void on_gyro(const ChannelInfo& c, const GyroReading& r) final { publish(c, r); }

 private:
  template <class Reading>
  void publish(const ChannelInfo& c, const Reading& r) {
    if (c.id < by_channel_.size() && by_channel_[c.id] != nullptr) static_cast<TypedResource<Reading>*>(by_channel_[c.id])->publish(r);
  }
  std::vector<std::unique_ptr<CResource>> owned_;
  std::vector<CResource*> by_channel_;  // indexed by channel id; nullptr: not replayed
};

}  // namespace tripodal::trace
