// Plays a recorded trace back into the framework: a simulated clock drives advance_to(t, sink), which
// hands every record stamped at or before t to a TraceSink (the lead connects sinks to resources'
// publish()). Default pacing is as fast as the computation allows; real-time pacing sleeps on an
// injected clock.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <optional>

#include "tripodal/core/clock.hpp"
#include "tripodal/trace/trace_reader.hpp"

namespace tripodal::trace {

/// Receives replayed records, one callback per record kind; the defaults ignore the record.
class TraceSink {
 public:
  virtual ~TraceSink() = default;
  virtual void on_laser(const ChannelInfo& /*channel*/, const LaserScan& /*scan*/) {}
  virtual void on_odometry(const ChannelInfo& /*channel*/, const OdometryReading& /*reading*/) {}
  virtual void on_sonar(const ChannelInfo& /*channel*/, const SonarReading& /*reading*/) {}
  virtual void on_infrared(const ChannelInfo& /*channel*/, const InfraredReading& /*reading*/) {}
  virtual void on_bumper(const ChannelInfo& /*channel*/, const BumperReading& /*reading*/) {}
  virtual void on_battery(const ChannelInfo& /*channel*/, const BatteryReading& /*reading*/) {}
  virtual void on_gyro(const ChannelInfo& /*channel*/, const GyroReading& /*reading*/) {}
  virtual void on_command(const ChannelInfo& /*channel*/, const CommandRecord& /*command*/) {}
  virtual void on_event(const ChannelInfo& /*channel*/, const EventRecord& /*event*/) {}
};

/// Hands `record` to the callback of `sink` that matches its kind.
void deliver(const ChannelInfo& channel, const RecordData& record, TraceSink& sink);

enum class ReplayPacing {
  kAsFastAsPossible,  ///< deliver as soon as asked (tests, benchmarks, batch evaluation)
  kRealTime,          ///< play(): wait on the clock so that records come out at `speed` x their spacing
};

struct TraceReplayOptions {
  ReplayPacing pacing = ReplayPacing::kAsFastAsPossible;
  double speed = 1.0;  ///< kRealTime: 2.0 plays twice as fast as recorded; must be > 0
  /// kRealTime: the clock play() paces against, and how to wait on it (e.g. sleep_for on a
  /// SteadyClock, or SimClock::advance in tests). Both are required for kRealTime.
  const Clock* clock = nullptr;
  std::function<void(Duration)> sleep;
};

/// Replays one trace in file order (which the importer and writers keep in time order).
class TraceReplay final {
 public:
  /// Reads the first record to know the start time. Throws std::invalid_argument on inconsistent
  /// options and what TraceReader throws.
  explicit TraceReplay(std::unique_ptr<TraceReader> reader, TraceReplayOptions options = {});

  /// Delivers, in file order, every not yet delivered record stamped at or before `t`, and returns
  /// how many. A record stamped earlier than one already delivered is delivered at the next call.
  /// Throws TraceFormatError when the trace turns out corrupt (records before it were delivered).
  std::size_t advance_to(Time t, TraceSink& sink);

  /// Delivers every remaining record; with kRealTime pacing, waits on the clock between records so
  /// that (stamp - start_time) / speed of trace time has passed on the clock. Returns the count.
  std::size_t play(TraceSink& sink);

  [[nodiscard]] bool finished() const noexcept { return !pending_; }
  /// Stamp of the next record to deliver, if any.
  [[nodiscard]] std::optional<Time> next_stamp() const noexcept;
  /// Stamp of the first record of the trace (0 for an empty trace).
  [[nodiscard]] Time start_time() const noexcept { return start_; }
  [[nodiscard]] std::uint64_t delivered() const noexcept { return delivered_; }
  /// Records whose stamp was earlier than the one delivered before them.
  [[nodiscard]] std::uint64_t out_of_order() const noexcept { return out_of_order_; }
  [[nodiscard]] const TraceReader& reader() const noexcept { return *reader_; }

 private:
  void deliver_pending(TraceSink& sink);
  void fetch();

  std::unique_ptr<TraceReader> reader_;
  TraceReplayOptions options_;
  TraceRecord record_;
  bool pending_ = false;
  Time start_{};
  Time last_{};
  std::uint64_t delivered_ = 0;
  std::uint64_t out_of_order_ = 0;
};

}  // namespace tripodal::trace
