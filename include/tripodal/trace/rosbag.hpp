// rosbag2 bags (MCAP or SQLite3 storage, with the bag folder's metadata.yaml) as tripodal traces:
// the bags a behavior author already holds become what the trace replay, the behavior harness and
// RobotHarness take. Sits beside the CARMEN importer: mcap.hpp reads the container, cdr.hpp decodes
// the messages, this maps topics to trace channels. What is read and the limits: docs/rosbag.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "tripodal/trace/mcap.hpp"
#include "tripodal/trace/trace_reader.hpp"
#include "tripodal/trace/trace_writer.hpp"

namespace tripodal::trace {

/// A bag is malformed where no byte offset applies (a db3 table or row, metadata.yaml): what()
/// names the file and the table/row or key. MCAP and CDR errors are TraceFormatError (byte offset).
class BagFormatError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The default topic -> channel names: /scan -> laser, /odom -> odometry, /imu (and /imu/data) ->
/// imu, /cmd_vel -> cmd_vel, /tf -> tf (the odom -> base_link transform as odometry).
[[nodiscard]] std::map<std::string, std::string> default_topic_channels();

struct BagImportOptions {
  /// Topic -> trace channel name. The channel's kind follows from the topic's message type.
  std::map<std::string, std::string> topic_channels = default_topic_channels();
  /// false: a supported topic not in topic_channels gets a channel named after it ("/a/b" -> "a_b").
  bool only_mapped = false;
  /// Stamp records with the message's header stamp (where it has one and it is not zero), else
  /// with the bag's receive time (log time).
  bool use_header_stamp = true;
  /// The transform of /tf messages that becomes odometry (leading '/' ignored); others are counted.
  std::string tf_parent_frame = "odom";
  std::string tf_child_frame = "base_link";
  mcap::ReaderOptions mcap;
};

struct BagImportReport {
  std::string storage;  ///< "mcap" or "sqlite3"
  std::vector<std::filesystem::path> files;
  std::uint64_t messages = 0;  ///< every message the bag holds (read, whatever became of it)
  std::map<std::string, std::uint64_t> topic_messages;  ///< topic -> messages
  std::map<std::string, std::string> topic_types;       ///< topic -> message type
  std::uint64_t records_written = 0;
  std::map<std::string, std::uint64_t> converted;  ///< type -> messages that became records
  /// type -> messages not decoded: a type (or an encoding other than cdr) this importer does not know.
  std::map<std::string, std::uint64_t> skipped_unsupported;
  /// type -> messages decoded, but with no trace channel kind to carry them (JointState, Clock,
  /// OccupancyGrid): decode them with cdr.hpp through for_each_bag_message.
  std::map<std::string, std::uint64_t> skipped_no_channel_kind;
  std::map<std::string, std::uint64_t> skipped_unmapped;  ///< topic -> messages (only_mapped)
  std::uint64_t tf_transforms_skipped = 0;  ///< /tf transforms other than parent -> child
  std::map<mcap::Opcode, std::uint64_t> mcap_records;  ///< MCAP records read, by opcode
  /// What the storage says of itself: MCAP Metadata records as "NAME.KEY" (rosbag2 writes one
  /// named "rosbag2"), the db3 table schema (where present) as "schema_version" and "ros_distro".
  std::map<std::string, std::string> storage_metadata;
  /// Files cut short (no MCAP footer): what was recovered and what is lost.
  std::vector<std::string> warnings;
};

/// One stored message as the bag holds it (before decoding).
struct BagMessage {
  const std::string& topic;
  const std::string& type;      ///< "sensor_msgs/msg/LaserScan"; "" for an MCAP channel without schema
  const std::string& encoding;  ///< "cdr" for ROS 2
  std::int64_t log_time_ns = 0;
  std::span<const std::uint8_t> data;
  const std::string& file;
  /// MCAP: byte offset of the Message (or of its Chunk); db3: the row id in table messages.
  std::uint64_t offset = 0;
  bool in_chunk = false;
  std::uint64_t chunk_offset = 0;  ///< in_chunk: offset in the chunk's uncompressed records
};

/// True when `path` looks like a rosbag2 bag: a folder with metadata.yaml, .mcap or .db3 files, or
/// an .mcap/.db3 file (or one that starts with the MCAP or SQLite3 magic).
[[nodiscard]] bool is_rosbag(const std::filesystem::path& path);

/// Calls `visit` for each message of the bag at `path` (folder or file), in storage order (MCAP:
/// file order; db3: by time stamp). Fills the storage, files, counts and warnings of `report`.
/// Throws TraceIoError, TraceFormatError (MCAP) or BagFormatError (db3, metadata.yaml).
void for_each_bag_message(const std::filesystem::path& path, const std::function<void(const BagMessage&)>& visit,
                          BagImportReport& report, const mcap::ReaderOptions& options = {});

/// Converts the bag at `path` into `out`: each supported message on a mapped topic becomes one
/// record (LaserScan -> laser, Odometry -> odometry, Imu -> gyro, Twist/TwistStamped -> command,
/// String -> event, the /tf odom -> base_link transform -> odometry). Throws as for_each_bag_message,
/// and TraceFormatError for a message whose CDR does not decode (naming the file and offset).
BagImportReport import_rosbag(const std::filesystem::path& path, TraceWriter& out, const BagImportOptions& options = {});

/// The bag as a trace, converted in memory, for TraceReplay / the behavior harness: a bag replays
/// where a trace does. `report` (optional) receives the conversion report.
[[nodiscard]] std::unique_ptr<TraceReader> read_bag(const std::filesystem::path& path,
                                                    const BagImportOptions& options = {},
                                                    BagImportReport* report = nullptr);

/// The trace file to open for `path`: `path` itself when it is not a rosbag2 bag; a bag is
/// converted (with `options`) into a temporary trace file, removed with this object. Lets what
/// opens a trace by path (BehaviorHarness::load_trace, TraceHardware and so RobotHarness) take a bag.
class TraceSource final {
 public:
  /// Throws as import_rosbag for a bag; nothing for a trace path (opening it reports errors).
  explicit TraceSource(const std::filesystem::path& path, const BagImportOptions& options = {});
  ~TraceSource();
  TraceSource(const TraceSource&) = delete;
  TraceSource& operator=(const TraceSource&) = delete;

  [[nodiscard]] const std::filesystem::path& trace() const noexcept { return trace_; }
  /// The conversion report when `path` was a bag.
  [[nodiscard]] const std::optional<BagImportReport>& bag_report() const noexcept { return report_; }

 private:
  std::filesystem::path trace_;
  bool temporary_ = false;
  std::optional<BagImportReport> report_;
};

struct McapExportReport {
  std::uint64_t records = 0;   ///< trace records read
  std::uint64_t messages = 0;  ///< MCAP messages written
  std::map<std::string, std::uint64_t> skipped;  ///< channel kind -> records with no ROS message here
};

/// Writes a trace as a ROS 2 MCAP bag file: laser -> sensor_msgs/msg/LaserScan, odometry ->
/// nav_msgs/msg/Odometry, gyro -> sensor_msgs/msg/Imu, command -> geometry_msgs/msg/Twist, event ->
/// std_msgs/msg/String, each on topic "/<channel>"; sonar, infrared, bumper and battery are counted
/// as skipped. Closes `out`.
McapExportReport export_trace_to_mcap(TraceReader& in, mcap::Writer& out);

/// The ros2msg definition stored as the schema of `type` (one of the types export writes).
[[nodiscard]] std::string ros2msg_definition(const std::string& type);

}  // namespace tripodal::trace
