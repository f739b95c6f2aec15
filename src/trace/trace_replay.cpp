#include "tripodal/trace/trace_replay.hpp"

#include <stdexcept>

namespace tripodal::trace {

void deliver(const ChannelInfo& channel, const RecordData& record, TraceSink& sink) {
  std::visit(
      [&](const auto& r) {
        using T = std::decay_t<decltype(r)>;
        if constexpr (std::is_same_v<T, LaserScan>) sink.on_laser(channel, r);
        else if constexpr (std::is_same_v<T, OdometryReading>) sink.on_odometry(channel, r);
        else if constexpr (std::is_same_v<T, SonarReading>) sink.on_sonar(channel, r);
        else if constexpr (std::is_same_v<T, InfraredReading>) sink.on_infrared(channel, r);
        else if constexpr (std::is_same_v<T, BumperReading>) sink.on_bumper(channel, r);
        else if constexpr (std::is_same_v<T, BatteryReading>) sink.on_battery(channel, r);
        else if constexpr (std::is_same_v<T, GyroReading>) sink.on_gyro(channel, r);
        else if constexpr (std::is_same_v<T, CommandRecord>) sink.on_command(channel, r);
        else sink.on_event(channel, r);
      },
      record);
}

TraceReplay::TraceReplay(std::unique_ptr<TraceReader> reader, TraceReplayOptions options)
    : reader_(std::move(reader)), options_(std::move(options)) {
  if (!reader_) throw std::invalid_argument("TraceReplay: no reader");
  if (options_.pacing == ReplayPacing::kRealTime) {
    if (options_.clock == nullptr || !options_.sleep) {
      throw std::invalid_argument("TraceReplay: real-time pacing needs a clock and a sleep function");
    }
    if (!(options_.speed > 0.0)) {
      throw std::invalid_argument("TraceReplay: speed must be > 0, got " + std::to_string(options_.speed));
    }
  }
  fetch();
  if (pending_) {
    start_ = stamp_of(record_.data);
    last_ = start_;
  }
}

void TraceReplay::fetch() { pending_ = reader_->next(record_); }

std::optional<Time> TraceReplay::next_stamp() const noexcept {
  if (!pending_) return std::nullopt;
  return stamp_of(record_.data);
}

void TraceReplay::deliver_pending(TraceSink& sink) {
  const Time stamp = stamp_of(record_.data);
  if (stamp < last_) ++out_of_order_;
  else last_ = stamp;
  deliver(reader_->channel(record_.channel), record_.data, sink);
  ++delivered_;
  fetch();
}

std::size_t TraceReplay::advance_to(Time t, TraceSink& sink) {
  std::size_t n = 0;
  while (pending_ && stamp_of(record_.data) <= t) {
    deliver_pending(sink);
    ++n;
  }
  return n;
}

std::size_t TraceReplay::play(TraceSink& sink) {
  std::size_t n = 0;
  const bool paced = options_.pacing == ReplayPacing::kRealTime;
  const Time clock_start = paced ? options_.clock->now() : Time{};
  const Time trace_start = pending_ ? stamp_of(record_.data) : Time{};
  while (pending_) {
    if (paced) {
      const Duration trace_elapsed = std::max(Duration{0}, stamp_of(record_.data) - trace_start);
      const Time due = clock_start + std::chrono::duration_cast<Duration>(
                                         std::chrono::duration<double, std::nano>(
                                             static_cast<double>(trace_elapsed.count()) / options_.speed));
      const Time now = options_.clock->now();
      if (due > now) options_.sleep(due - now);
    }
    deliver_pending(sink);
    ++n;
  }
  return n;
}

}  // namespace tripodal::trace
