// rosbag2 bags as traces (rosbag.hpp): finds the bag's files (metadata.yaml or the folder's .mcap /
// .db3 files), walks their messages, decodes the supported types and writes trace records; and the
// reverse, a trace as an MCAP bag file.
#include "tripodal/trace/rosbag.hpp"

#include <yaml-cpp/yaml.h>

#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>

#include "rosbag_sqlite.hpp"
#include "tripodal/trace/cdr.hpp"

namespace tripodal::trace {

namespace fs = std::filesystem;

std::map<std::string, std::string> default_topic_channels() {
  return {{"/scan", "laser"},     {"/odom", "odometry"},   {"/imu", "imu"},
          {"/imu/data", "imu"},   {"/cmd_vel", "cmd_vel"}, {"/tf", "tf"}};
}

namespace {

enum class Storage { kMcap, kSqlite };

struct BagFiles {
  Storage storage = Storage::kMcap;
  std::vector<fs::path> files;
};

bool has_magic(const fs::path& file, std::string_view magic) {
  std::ifstream in(file, std::ios::binary);
  std::string head(magic.size(), '\0');
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  return in.gcount() == static_cast<std::streamsize>(magic.size()) && head == magic;
}

constexpr std::string_view kMcapMagic{"\x89MCAP0\r\n", 8};
constexpr std::string_view kSqliteMagic{"SQLite format 3\0", 16};

std::optional<Storage> storage_of_file(const fs::path& file) {
  if (file.extension() == ".mcap" || has_magic(file, kMcapMagic)) return Storage::kMcap;
  if (file.extension() == ".db3" || has_magic(file, kSqliteMagic)) return Storage::kSqlite;
  return std::nullopt;
}

BagFiles locate(const fs::path& given) {
  if (!fs::exists(given)) throw TraceIoError(given.string() + ": no such file or folder");
  // The bag's metadata.yaml names its folder.
  const fs::path path = given.filename() == "metadata.yaml" ? given.parent_path() : given;
  BagFiles bag;
  if (!fs::is_directory(path)) {
    const auto storage = storage_of_file(path);
    if (!storage) throw BagFormatError(path.string() + ": not a rosbag2 file (expected .mcap or .db3)");
    bag.storage = *storage;
    bag.files.push_back(path);
    return bag;
  }
  const fs::path meta = path / "metadata.yaml";
  if (fs::exists(meta)) {
    YAML::Node root;
    try {
      root = YAML::LoadFile(meta.string());
    } catch (const YAML::Exception& e) {
      throw BagFormatError(meta.string() + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
    }
    const YAML::Node info = root["rosbag2_bagfile_information"];
    if (!info || !info.IsMap()) throw BagFormatError(meta.string() + ": no rosbag2_bagfile_information map");
    try {
      const std::string id = info["storage_identifier"] ? info["storage_identifier"].as<std::string>() : "";
      if (id == "mcap") {
        bag.storage = Storage::kMcap;
      } else if (id == "sqlite3") {
        bag.storage = Storage::kSqlite;
      } else {
        throw BagFormatError(meta.string() + ": storage_identifier '" + id + "' is not read (mcap or sqlite3)");
      }
      const std::string mode = info["compression_mode"] ? info["compression_mode"].as<std::string>() : "";
      if (!mode.empty() && mode != "NONE") {
        throw BagFormatError(meta.string() + ": compression_mode " + mode +
                             " (a compressed bag) is not read; `ros2 bag decompress` it first");
      }
      if (const YAML::Node files = info["relative_file_paths"]; files && files.IsSequence()) {
        for (const auto& f : files) bag.files.push_back(path / f.as<std::string>());
      }
    } catch (const YAML::Exception& e) {
      throw BagFormatError(meta.string() + ":" + std::to_string(e.mark.line + 1) + ": " + e.msg);
    }
    if (bag.files.empty()) throw BagFormatError(meta.string() + ": relative_file_paths lists no file");
    return bag;
  }
  // A folder without metadata.yaml: its .mcap files, else its .db3 files, in name order.
  for (const char* ext : {".mcap", ".db3"}) {
    for (const auto& e : fs::directory_iterator(path)) {
      if (e.is_regular_file() && e.path().extension() == ext) bag.files.push_back(e.path());
    }
    if (!bag.files.empty()) {
      std::sort(bag.files.begin(), bag.files.end());
      bag.storage = std::string_view(ext) == ".mcap" ? Storage::kMcap : Storage::kSqlite;
      return bag;
    }
  }
  throw BagFormatError(path.string() + ": a folder with neither metadata.yaml nor .mcap/.db3 files");
}

void for_each_mcap_message(const fs::path& file, const std::function<void(const BagMessage&)>& visit,
                           BagImportReport& report, const mcap::ReaderOptions& options) {
  mcap::Reader reader(file, options);
  const std::string name = file.string();
  std::map<std::uint16_t, mcap::Schema> schemas;
  struct Topic {
    std::string topic, type, encoding;
  };
  std::map<std::uint16_t, Topic> channels;
  const std::string unknown_type;
  mcap::Record record;
  while (reader.next(record)) {
    if (auto* s = std::get_if<mcap::Schema>(&record.body)) {
      schemas[s->id] = std::move(*s);
    } else if (auto* c = std::get_if<mcap::Channel>(&record.body)) {
      std::string type;
      if (c->schema_id != 0) {
        const auto it = schemas.find(c->schema_id);
        if (it == schemas.end()) {
          throw TraceFormatError(name, record.offset, "Channel " + std::to_string(c->id) + " ('" + c->topic +
                                                          "') names schema " + std::to_string(c->schema_id) +
                                                          ", which no Schema record before it declares");
        }
        type = it->second.name;
      }
      report.topic_types[c->topic] = type;
      channels[c->id] = Topic{c->topic, type, c->message_encoding};
    } else if (const auto* md = std::get_if<mcap::Metadata>(&record.body)) {
      for (const auto& [k, v] : md->metadata) report.storage_metadata[md->name + "." + k] = v;
    } else if (auto* m = std::get_if<mcap::Message>(&record.body)) {
      const auto it = channels.find(m->channel_id);
      if (it == channels.end()) {
        throw TraceFormatError(name, record.offset, std::string("Message") + (record.in_chunk ? " in this Chunk" : "") +
                                                        " on channel " + std::to_string(m->channel_id) +
                                                        ", which no Channel record before it declares");
      }
      ++report.messages;
      ++report.topic_messages[it->second.topic];
      visit(BagMessage{it->second.topic, it->second.type, it->second.encoding, static_cast<std::int64_t>(m->log_time),
                       m->data, name, record.offset, record.in_chunk, record.chunk_offset});
    }
  }
  for (const auto& [op, n] : reader.counts()) report.mcap_records[op] += n;
  if (reader.state() == mcap::State::kTruncated) report.warnings.push_back(reader.warning());
}

// --- Conversion -----------------------------------------------------------------------------

std::string strip_slash(const std::string& frame) { return !frame.empty() && frame[0] == '/' ? frame.substr(1) : frame; }

std::string channel_for_topic(const std::string& topic) {
  std::string s = strip_slash(topic);
  std::replace(s.begin(), s.end(), '/', '_');
  return s.empty() ? "root" : s;
}

// "sensor_msgs/msg/LaserScan" and "sensor_msgs/LaserScan" name the same type.
std::string canonical_type(const std::string& type) {
  const auto slash = type.find('/');
  if (slash == std::string::npos || type.find('/', slash + 1) != std::string::npos) return type;
  return type.substr(0, slash) + "/msg" + type.substr(slash);
}

enum class Handler { kLaser, kOdometry, kImu, kTwist, kTwistStamped, kString, kTf, kJointState, kClock, kOccupancyGrid };

std::optional<Handler> handler_of(const std::string& type) {
  static const std::map<std::string, Handler> types = {
      {"sensor_msgs/msg/LaserScan", Handler::kLaser},        {"nav_msgs/msg/Odometry", Handler::kOdometry},
      {"sensor_msgs/msg/Imu", Handler::kImu},                {"geometry_msgs/msg/Twist", Handler::kTwist},
      {"geometry_msgs/msg/TwistStamped", Handler::kTwistStamped}, {"std_msgs/msg/String", Handler::kString},
      {"tf2_msgs/msg/TFMessage", Handler::kTf},              {"sensor_msgs/msg/JointState", Handler::kJointState},
      {"rosgraph_msgs/msg/Clock", Handler::kClock},          {"nav_msgs/msg/OccupancyGrid", Handler::kOccupancyGrid},
  };
  const auto it = types.find(canonical_type(type));
  if (it == types.end()) return std::nullopt;
  return it->second;
}

class Converter {
 public:
  Converter(TraceWriter& out, const BagImportOptions& options, BagImportReport& report)
      : out_(out), options_(options), report_(report) {}

  void operator()(const BagMessage& m) {
    const auto handler = handler_of(m.type);
    if (m.encoding != "cdr" || !handler) {
      const std::string key = m.type.empty() ? "(no schema)" : m.type;
      ++report_.skipped_unsupported[m.encoding == "cdr" ? key : key + " [" + m.encoding + "]"];
      return;
    }
    std::string channel;
    if (const auto it = options_.topic_channels.find(m.topic); it != options_.topic_channels.end()) {
      channel = it->second;
    } else if (options_.only_mapped) {
      ++report_.skipped_unmapped[m.topic];
      return;
    } else {
      channel = channel_for_topic(m.topic);
    }
    try {
      convert(*handler, m, channel);
    } catch (const TraceFormatError& e) {
      // Re-located: the message's record (or chunk) in its file, and the byte within its CDR data.
      const std::string what = e.what();
      const auto cut = what.find(": byte ");
      const auto rest = cut == std::string::npos ? what : what.substr(what.find(": ", cut + 7) + 2);
      throw TraceFormatError(m.file, m.offset,
                             "Message on " + m.topic + " (" + m.type + ")" +
                                 (m.in_chunk ? " at byte " + std::to_string(m.chunk_offset) + " of this Chunk's records"
                                             : std::string()) +
                                 ", byte " + std::to_string(e.offset()) + " of its data: " + rest);
    }
  }

 private:
  template <typename T>
  T decode(const BagMessage& m) {
    return ros::decode_cdr<T>(m.data, m.file, 0);
  }

  Time stamp(const ros::Header& h, const BagMessage& m) const {
    if (options_.use_header_stamp && (h.stamp.sec != 0 || h.stamp.nanosec != 0)) return time_from_ns(h.stamp.ns());
    return time_from_ns(m.log_time_ns);
  }

  ChannelId channel(const std::string& name, ChannelKind kind, const BagMessage& m) {
    const auto it = channels_.find(name);
    if (it != channels_.end()) {
      if (it->second.second != kind) {
        throw BagFormatError(m.file + ": topic " + m.topic + " maps to channel '" + name + "', which already carries " +
                             std::string(to_string(it->second.second)) + " records, not " + std::string(to_string(kind)));
      }
      return it->second.first;
    }
    const ChannelId id = out_.add_channel(name, kind);
    channels_.emplace(name, std::make_pair(id, kind));
    return id;
  }

  void written(const BagMessage& m) {
    ++report_.converted[canonical_type(m.type)];
    ++report_.records_written;
  }

  void convert(Handler h, const BagMessage& m, const std::string& name) {
    switch (h) {
      case Handler::kLaser: {
        const auto msg = decode<ros::LaserScan>(m);
        LaserScan scan;
        scan.stamp = stamp(msg.header, m);
        scan.angle_min_rad = msg.angle_min;
        scan.angle_max_rad = msg.angle_max;
        scan.angle_increment_rad = msg.angle_increment;
        scan.time_increment_s = msg.time_increment;
        scan.scan_time_s = msg.scan_time;
        scan.range_min_m = msg.range_min;
        scan.range_max_m = msg.range_max;
        scan.ranges_m = msg.ranges;
        scan.intensities = msg.intensities;
        out_.write(channel(name, ChannelKind::kLaser, m), scan);
        written(m);
        return;
      }
      case Handler::kOdometry: {
        const auto msg = decode<ros::Odometry>(m);
        OdometryReading r;
        r.stamp = stamp(msg.header, m);
        r.pose = Pose2D{msg.pose.position.x, msg.pose.position.y, ros::yaw_of(msg.pose.orientation)};
        r.twist = Twist2D{msg.twist.linear.x, msg.twist.linear.y, msg.twist.angular.z};
        out_.write(channel(name, ChannelKind::kOdometry, m), r);
        written(m);
        return;
      }
      case Handler::kImu: {
        const auto msg = decode<ros::Imu>(m);
        GyroReading r;
        r.stamp = stamp(msg.header, m);
        r.yaw_rate_rad_s = msg.angular_velocity.z;
        // orientation_covariance[0] == -1: the device gives no orientation (REP 145).
        r.yaw_rad = msg.orientation_covariance[0] == -1.0 ? 0.0 : ros::yaw_of(msg.orientation);
        out_.write(channel(name, ChannelKind::kGyro, m), r);
        written(m);
        return;
      }
      case Handler::kTwist:
      case Handler::kTwistStamped: {
        CommandRecord c;
        ros::Twist t;
        if (h == Handler::kTwist) {
          t = decode<ros::Twist>(m);
          c.stamp = time_from_ns(m.log_time_ns);
        } else {
          const auto msg = decode<ros::TwistStamped>(m);
          t = msg.twist;
          c.stamp = stamp(msg.header, m);
        }
        c.twist = Twist2D{t.linear.x, t.linear.y, t.angular.z};
        c.source = m.topic;
        out_.write(channel(name, ChannelKind::kCommand, m), c);
        written(m);
        return;
      }
      case Handler::kString: {
        EventRecord e;
        e.stamp = time_from_ns(m.log_time_ns);
        e.name = decode<ros::String>(m).data;
        out_.write(channel(name, ChannelKind::kEvent, m), e);
        written(m);
        return;
      }
      case Handler::kTf: {
        const auto msg = decode<ros::TFMessage>(m);
        for (const auto& t : msg.transforms) {
          if (strip_slash(t.header.frame_id) != strip_slash(options_.tf_parent_frame) ||
              strip_slash(t.child_frame_id) != strip_slash(options_.tf_child_frame)) {
            ++report_.tf_transforms_skipped;
            continue;
          }
          OdometryReading r;
          r.stamp = stamp(t.header, m);
          r.pose = Pose2D{t.translation.x, t.translation.y, ros::yaw_of(t.rotation)};
          out_.write(channel(name, ChannelKind::kOdometry, m), r);
          ++report_.records_written;
        }
        ++report_.converted[canonical_type(m.type)];
        return;
      }
      case Handler::kJointState: (void)decode<ros::JointState>(m); break;
      case Handler::kClock: (void)decode<ros::Clock>(m); break;
      case Handler::kOccupancyGrid: (void)decode<ros::OccupancyGrid>(m); break;
    }
    // Decoded (so a malformed one is still refused) but no trace channel kind carries it.
    ++report_.skipped_no_channel_kind[canonical_type(m.type)];
  }

  TraceWriter& out_;
  const BagImportOptions& options_;
  BagImportReport& report_;
  std::map<std::string, std::pair<ChannelId, ChannelKind>> channels_;
};

}  // namespace

bool is_rosbag(const fs::path& path) {
  std::error_code ec;
  if (path.filename() == "metadata.yaml") return fs::is_regular_file(path, ec);
  if (fs::is_directory(path, ec)) {
    if (fs::exists(path / "metadata.yaml", ec)) return true;
    for (const auto& e : fs::directory_iterator(path, ec)) {
      if (e.path().extension() == ".mcap" || e.path().extension() == ".db3") return true;
    }
    return false;
  }
  return fs::is_regular_file(path, ec) && storage_of_file(path).has_value();
}

void for_each_bag_message(const fs::path& path, const std::function<void(const BagMessage&)>& visit,
                          BagImportReport& report, const mcap::ReaderOptions& options) {
  const BagFiles bag = locate(path);
  report.storage = bag.storage == Storage::kMcap ? "mcap" : "sqlite3";
  for (const auto& file : bag.files) {
    report.files.push_back(file);
    if (bag.storage == Storage::kMcap) {
      for_each_mcap_message(file, visit, report, options);
    } else {
      detail::for_each_db3_message(file, visit, report);
    }
  }
}

BagImportReport import_rosbag(const fs::path& path, TraceWriter& out, const BagImportOptions& options) {
  BagImportReport report;
  Converter convert(out, options, report);
  for_each_bag_message(path, std::ref(convert), report, options.mcap);
  return report;
}

std::unique_ptr<TraceReader> read_bag(const fs::path& path, const BagImportOptions& options, BagImportReport* report) {
  auto text = std::make_shared<std::stringbuf>();
  BagImportReport r;
  {
    // The writer owns (and on close() destroys) its stream; the buffer stays ours.
    TraceWriter writer(std::make_unique<std::ostream>(text.get()), path.string() + " (as a trace)");
    r = import_rosbag(path, writer, options);
    writer.close();
  }
  if (report != nullptr) *report = std::move(r);
  return std::make_unique<TraceReader>(std::make_unique<std::istringstream>(text->str()), path.string());
}

TraceSource::TraceSource(const fs::path& path, const BagImportOptions& options) : trace_(path) {
  if (!is_rosbag(path)) return;
  static std::atomic<unsigned> counter{0};
  trace_ = fs::temp_directory_path() /
           ("tripodal_bag_" + std::to_string(::getpid()) + "_" + std::to_string(counter++) + ".trp");
  temporary_ = true;
  try {
    TraceWriter writer(trace_);
    report_ = import_rosbag(path, writer, options);
    writer.close();
  } catch (...) {
    std::error_code ec;
    fs::remove(trace_, ec);
    throw;
  }
}

TraceSource::~TraceSource() {
  if (!temporary_) return;
  std::error_code ec;
  fs::remove(trace_, ec);
}

// --- Export -------------------------------------------------------------------------------------

std::string ros2msg_definition(const std::string& type) {
  static const std::string sep = "\n================================================================================\n";
  static const std::string header_def = "MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id";
  static const std::string time_def = "MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec";
  static const std::string vector3_def = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z";
  static const std::string quaternion_def =
      "MSG: geometry_msgs/Quaternion\nfloat64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1";
  static const std::string twist_def = "MSG: geometry_msgs/Twist\nVector3 linear\nVector3 angular";
  if (type == "sensor_msgs/msg/LaserScan") {
    return "std_msgs/Header header\nfloat32 angle_min\nfloat32 angle_max\nfloat32 angle_increment\n"
           "float32 time_increment\nfloat32 scan_time\nfloat32 range_min\nfloat32 range_max\nfloat32[] ranges\n"
           "float32[] intensities" + sep + header_def + sep + time_def;
  }
  if (type == "nav_msgs/msg/Odometry") {
    return "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/PoseWithCovariance pose\n"
           "geometry_msgs/TwistWithCovariance twist" + sep + header_def + sep + time_def + sep +
           "MSG: geometry_msgs/PoseWithCovariance\nPose pose\nfloat64[36] covariance" + sep +
           "MSG: geometry_msgs/Pose\nPoint position\nQuaternion orientation" + sep +
           "MSG: geometry_msgs/Point\nfloat64 x\nfloat64 y\nfloat64 z" + sep + quaternion_def + sep +
           "MSG: geometry_msgs/TwistWithCovariance\nTwist twist\nfloat64[36] covariance" + sep + twist_def + sep + vector3_def;
  }
  if (type == "sensor_msgs/msg/Imu") {
    return "std_msgs/Header header\ngeometry_msgs/Quaternion orientation\nfloat64[9] orientation_covariance\n"
           "geometry_msgs/Vector3 angular_velocity\nfloat64[9] angular_velocity_covariance\n"
           "geometry_msgs/Vector3 linear_acceleration\nfloat64[9] linear_acceleration_covariance" + sep + header_def +
           sep + time_def + sep + quaternion_def + sep + vector3_def;
  }
  if (type == "geometry_msgs/msg/Twist") return "Vector3 linear\nVector3 angular" + sep + vector3_def;
  if (type == "std_msgs/msg/String") return "string data";
  throw std::invalid_argument("ros2msg_definition: no definition for '" + type + "'");
}

McapExportReport export_trace_to_mcap(TraceReader& in, mcap::Writer& out) {
  McapExportReport report;
  std::map<std::string, std::uint16_t> schemas;
  std::map<ChannelId, std::uint16_t> channels;
  const auto channel_for = [&](const ChannelInfo& c, const std::string& type) {
    if (const auto it = channels.find(c.id); it != channels.end()) return it->second;
    auto s = schemas.find(type);
    if (s == schemas.end()) s = schemas.emplace(type, out.add_schema(type, "ros2msg", ros2msg_definition(type))).first;
    const std::uint16_t id = out.add_channel("/" + c.name, "cdr", s->second);
    channels.emplace(c.id, id);
    return id;
  };
  const auto header = [](Time t, const std::string& frame) {
    ros::Header h;
    const std::int64_t ns = std::max<std::int64_t>(0, to_ns(t));  // a ROS stamp is not before 1970
    h.stamp.sec = static_cast<std::int32_t>(ns / 1'000'000'000);
    h.stamp.nanosec = static_cast<std::uint32_t>(ns % 1'000'000'000);
    h.frame_id = frame;
    return h;
  };
  TraceRecord rec;
  while (in.next(rec)) {
    ++report.records;
    const ChannelInfo& c = in.channel(rec.channel);
    const Time t = stamp_of(rec.data);
    const auto log_time = static_cast<std::uint64_t>(std::max<std::int64_t>(0, to_ns(t)));
    std::string type;
    std::vector<std::uint8_t> data;
    std::visit(
        [&](const auto& r) {
          using T = std::decay_t<decltype(r)>;
          if constexpr (std::is_same_v<T, LaserScan>) {
            ros::LaserScan m;
            m.header = header(r.stamp, c.name);
            m.angle_min = static_cast<float>(r.angle_min_rad);
            m.angle_max = static_cast<float>(r.angle_max_rad);
            m.angle_increment = static_cast<float>(r.angle_increment_rad);
            m.time_increment = static_cast<float>(r.time_increment_s);
            m.scan_time = static_cast<float>(r.scan_time_s);
            m.range_min = static_cast<float>(r.range_min_m);
            m.range_max = static_cast<float>(r.range_max_m);
            m.ranges = r.ranges_m;
            m.intensities = r.intensities;
            type = "sensor_msgs/msg/LaserScan";
            data = ros::encode_cdr(m);
          } else if constexpr (std::is_same_v<T, OdometryReading>) {
            ros::Odometry m;
            m.header = header(r.stamp, "odom");
            m.child_frame_id = "base_link";
            m.pose.position = {r.pose.x_m, r.pose.y_m, 0.0};
            m.pose.orientation = ros::quaternion_from_yaw(r.pose.theta_rad);
            m.twist.linear = {r.twist.vx_m_s, r.twist.vy_m_s, 0.0};
            m.twist.angular = {0.0, 0.0, r.twist.wz_rad_s};
            type = "nav_msgs/msg/Odometry";
            data = ros::encode_cdr(m);
          } else if constexpr (std::is_same_v<T, GyroReading>) {
            ros::Imu m;
            m.header = header(r.stamp, c.name);
            m.orientation = ros::quaternion_from_yaw(r.yaw_rad);
            m.angular_velocity.z = r.yaw_rate_rad_s;
            m.linear_acceleration_covariance[0] = -1.0;  // no acceleration measured (REP 145)
            type = "sensor_msgs/msg/Imu";
            data = ros::encode_cdr(m);
          } else if constexpr (std::is_same_v<T, CommandRecord>) {
            ros::Twist m;
            m.linear = {r.twist.vx_m_s, r.twist.vy_m_s, 0.0};
            m.angular = {0.0, 0.0, r.twist.wz_rad_s};
            type = "geometry_msgs/msg/Twist";
            data = ros::encode_cdr(m);
          } else if constexpr (std::is_same_v<T, EventRecord>) {
            type = "std_msgs/msg/String";
            data = ros::encode_cdr(ros::String{r.name});
          }
        },
        rec.data);
    if (type.empty()) {
      ++report.skipped[std::string(to_string(c.kind))];
      continue;
    }
    out.write(channel_for(c, type), log_time, log_time, data);
    ++report.messages;
  }
  out.close();
  return report;
}

}  // namespace tripodal::trace
