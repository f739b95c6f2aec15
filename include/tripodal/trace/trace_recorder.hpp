// Records a running robot (simulated or real) into a trace: attached beside a control loop, it
// observes resources and, each cycle, writes every reading published since the previous cycle, plus
// the commands and events the caller hands it. Replaying the file feeds behaviors the same readings.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/time.hpp"
#include "tripodal/resources/resource.hpp"
#include "tripodal/trace/trace_writer.hpp"

namespace tripodal::trace {

/// Observes resources and writes their new readings to a TraceWriter. Runs on the loop's thread
/// (resources are not thread-safe); record() is called once per cycle, after the resources were
/// polled or published and before (or after) the behaviors step: readings keep their own stamps.
class TraceRecorder final {
 public:
  /// `writer` must outlive the recorder.
  explicit TraceRecorder(TraceWriter& writer) noexcept : writer_(writer) {}

  /// Observes `resource` (must outlive the recorder) on a channel named as the resource. Its kind
  /// comes from the resource's reading type. Throws std::invalid_argument for a resource holding
  /// no reading kind a trace carries, or a name already declared in the writer.
  ChannelId watch(const CResource& resource);
  /// Observes every resource of `table` whose reading a trace carries, in order; returns how many
  /// it left out (the operator's teleop input, joints, buttons: inputs a replay does not feed).
  std::size_t watch_all(const ResourceTable& table);
  /// Declares the channel record_command() writes to (default name "cmd").
  ChannelId record_commands(std::string_view channel = "cmd");
  /// Declares the channel record_event() writes to (default name "events").
  ChannelId record_events(std::string_view channel = "events");

  /// Writes the latest reading of every observed resource that published since the last call
  /// (a resource that published twice in between loses the earlier reading: call once per
  /// publish period at least). Returns how many readings were written. Throws TraceIoError.
  std::size_t record(Time now);
  /// Writes a command (record_commands() must have been called; std::logic_error otherwise).
  void record_command(Time stamp, const Twist2D& command, std::string_view source);
  /// Writes an event (record_events() must have been called; std::logic_error otherwise).
  void record_event(Time stamp, std::string_view name);

  [[nodiscard]] std::size_t watched() const noexcept { return watched_.size(); }
  [[nodiscard]] std::uint64_t readings_written() const noexcept { return readings_; }

 private:
  struct Watched {
    const CResource* resource;
    ChannelId channel;
    ChannelKind kind;
    std::size_t sequence;  // resource sequence() already written
  };
  TraceWriter& writer_;
  std::vector<Watched> watched_;
  bool has_commands_ = false, has_events_ = false;
  ChannelId commands_ = 0, events_ = 0;
  std::uint64_t readings_ = 0;
  CommandRecord command_;  // reused: the source string keeps its capacity
  EventRecord event_;
};

}  // namespace tripodal::trace
