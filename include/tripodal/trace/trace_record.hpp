// The vocabulary of a sensor trace: channels (named resources of one kind) and the records a trace
// holds — every reading kind of resources/readings.hpp, plus motion commands and named events — so a
// recorded run can be replayed into behaviors and compared with the replayed run.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <variant>

#include "tripodal/core/time.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::trace {

/// What a channel carries. The numeric values are written to files: never renumber.
enum class ChannelKind : std::uint8_t {
  kLaser = 1,
  kOdometry = 2,
  kSonar = 3,
  kInfrared = 4,
  kBumper = 5,
  kBattery = 6,
  kGyro = 7,
  kCommand = 8,
  kEvent = 9,
};

/// "laser", "odometry", ... as `tripodal trace info` prints them; "unknown" for other values.
[[nodiscard]] std::string_view to_string(ChannelKind kind) noexcept;
/// True for the values listed in ChannelKind.
[[nodiscard]] bool is_valid(ChannelKind kind) noexcept;

/// Identifies a channel within one trace file (assigned by the writer, in declaration order).
using ChannelId = std::uint16_t;

/// A channel: a resource name such as "front_laser", and the kind of record it carries.
struct ChannelInfo {
  ChannelId id = 0;
  ChannelKind kind = ChannelKind::kLaser;
  std::string name;
  friend bool operator==(const ChannelInfo&, const ChannelInfo&) = default;
};

/// A motion command issued during a run, with the behavior or controller that issued it.
struct CommandRecord {
  Time stamp{};
  Twist2D twist;
  std::string source;
  friend bool operator==(const CommandRecord&, const CommandRecord&) = default;
};

/// A named event of a run (a net transition fired, a fault raised, a mission step reached).
struct EventRecord {
  Time stamp{};
  std::string name;
  friend bool operator==(const EventRecord&, const EventRecord&) = default;
};

/// The payload of one record; the alternative matches the kind of its channel.
using RecordData = std::variant<LaserScan, OdometryReading, SonarReading, InfraredReading, BumperReading,
                                BatteryReading, GyroReading, CommandRecord, EventRecord>;

/// The channel kind that carries the alternative `data` holds.
[[nodiscard]] ChannelKind kind_of(const RecordData& data) noexcept;
/// The time stamp of whichever alternative `data` holds.
[[nodiscard]] Time stamp_of(const RecordData& data) noexcept;

/// One record as read back from a trace.
struct TraceRecord {
  ChannelId channel = 0;
  std::uint64_t offset = 0;  ///< byte offset of the record's frame in the file
  RecordData data;
};

/// A trace file is malformed (bad magic, wrong version, checksum mismatch, undecodable record).
/// what() names the file and the byte offset; offset() gives the offset alone.
class TraceFormatError : public std::runtime_error {
 public:
  TraceFormatError(const std::string& file, std::uint64_t offset, const std::string& what);
  [[nodiscard]] std::uint64_t offset() const noexcept { return offset_; }

 private:
  std::uint64_t offset_;
};

/// A trace file could not be opened, read or written.
class TraceIoError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

}  // namespace tripodal::trace
