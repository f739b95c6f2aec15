// rosbag2 bags in (MCAP, db3, CDR) and MCAP out: the real bags of tests/data/bags, every MCAP record
// type written by hand from the specification, synthetic sensor bags, and bad input refused with
// the file and the record's offset.
#include <lz4frame.h>
#include <sqlite3.h>
#include <zlib.h>
#include <zstd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "tripodal/trace/cdr.hpp"
#include "tripodal/trace/mcap.hpp"
#include "tripodal/trace/rosbag.hpp"
#include "tripodal/trace/trace_replay.hpp"

namespace fs = std::filesystem;
using namespace tripodal;
using namespace tripodal::trace;
using Catch::Matchers::Contains;

namespace {

const fs::path kBags = fs::path(TRIPODAL_TEST_DATA_DIR) / "bags";

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::temp_directory_path() / "tripodal_rosbag_test";
  fs::create_directories(dir);
  return dir / name;
}

std::vector<TraceRecord> all_records(TraceReader& r) {
  std::vector<TraceRecord> out;
  TraceRecord rec;
  while (r.next(rec)) out.push_back(rec);
  return out;
}

std::vector<std::uint8_t> encode_cdr_string(const std::string& s) { return ros::encode_cdr(ros::String{s}); }

// Builds MCAP bytes by hand, field by field as the specification lays them out.
struct Bytes {
  std::vector<std::uint8_t> b;
  Bytes& u8(std::uint8_t v) { b.push_back(v); return *this; }
  Bytes& le(std::uint64_t v, int n) {
    for (int i = 0; i < n; ++i) b.push_back(static_cast<std::uint8_t>(v >> (8 * i)));
    return *this;
  }
  Bytes& u16(std::uint16_t v) { return le(v, 2); }
  Bytes& u32(std::uint32_t v) { return le(v, 4); }
  Bytes& u64(std::uint64_t v) { return le(v, 8); }
  Bytes& str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    b.insert(b.end(), s.begin(), s.end());
    return *this;
  }
  Bytes& raw(const std::vector<std::uint8_t>& v) {
    b.insert(b.end(), v.begin(), v.end());
    return *this;
  }
  Bytes& record(std::uint8_t op, const Bytes& body) {
    u8(op).u64(body.b.size());
    return raw(body.b);
  }
  Bytes& magic() { return raw({0x89, 'M', 'C', 'A', 'P', '0', '\r', '\n'}); }
};

std::uint32_t crc(const std::vector<std::uint8_t>& v, std::size_t from = 0, std::size_t to = SIZE_MAX) {
  to = std::min(to, v.size());
  return static_cast<std::uint32_t>(::crc32(0, v.data() + from, static_cast<uInt>(to - from)));
}

Bytes schema_body(std::uint16_t id, const std::string& name) {
  Bytes s;
  s.u16(id).str(name).str("ros2msg").str("string data");
  return s;
}
Bytes channel_body(std::uint16_t id, std::uint16_t schema, const std::string& topic) {
  Bytes c;
  Bytes meta;
  meta.str("offered_qos_profiles").str("");
  c.u16(id).u16(schema).str(topic).str("cdr").u32(static_cast<std::uint32_t>(meta.b.size())).raw(meta.b);
  return c;
}
Bytes message_body(std::uint16_t channel, std::uint64_t t, const std::vector<std::uint8_t>& data) {
  Bytes m;
  m.u16(channel).u32(7).u64(t).u64(t).raw(data);
  return m;
}
Bytes chunk_body(const std::vector<std::uint8_t>& records, const std::string& compression,
                 const std::vector<std::uint8_t>& packed, std::uint32_t records_crc) {
  Bytes c;
  c.u64(1).u64(3).u64(records.size()).u32(records_crc).str(compression).u64(packed.size()).raw(packed);
  return c;
}

std::vector<std::uint8_t> lz4_frame(const std::vector<std::uint8_t>& in) {
  std::vector<std::uint8_t> out(LZ4F_compressFrameBound(in.size(), nullptr));
  const std::size_t n = LZ4F_compressFrame(out.data(), out.size(), in.data(), in.size(), nullptr);
  REQUIRE(LZ4F_isError(n) == 0u);
  out.resize(n);
  return out;
}
std::vector<std::uint8_t> zstd_frame(const std::vector<std::uint8_t>& in) {
  std::vector<std::uint8_t> out(ZSTD_compressBound(in.size()));
  const std::size_t n = ZSTD_compress(out.data(), out.size(), in.data(), in.size(), 1);
  REQUIRE(ZSTD_isError(n) == 0u);
  out.resize(n);
  return out;
}

// One file holding every record type of the specification: three chunks (none, zstd, lz4), their
// message indexes, an attachment, metadata, a user record, then the summary and a footer with CRCs.
std::vector<std::uint8_t> every_record_file() {
  Bytes f;
  f.magic();
  f.record(0x01, Bytes().str("ros2").str("hand-built"));
  Bytes records;
  records.record(0x03, schema_body(1, "std_msgs/msg/String"));
  records.record(0x04, channel_body(0, 1, "/chatter"));
  records.record(0x05, message_body(0, 1, encode_cdr_string("one")));
  const std::vector<std::string> compressions = {"", "zstd", "lz4"};
  std::uint64_t t = 1;
  for (const auto& compression : compressions) {
    Bytes rec;
    if (t == 1) {
      rec = records;
    } else {
      rec.record(0x05, message_body(0, t, encode_cdr_string(t == 2 ? "two" : "three")));
    }
    const auto packed = compression.empty() ? rec.b : compression == "zstd" ? zstd_frame(rec.b) : lz4_frame(rec.b);
    f.record(0x06, chunk_body(rec.b, compression, packed, crc(rec.b)));
    Bytes index;
    index.u16(0).u32(16).u64(t).u64(0);
    f.record(0x07, index);
    ++t;
  }
  Bytes att;
  att.u64(5).u64(6).str("calibration.yaml").str("text/yaml").u64(3).raw({'a', '=', '1'});
  att.u32(crc(att.b));
  f.record(0x09, att);
  Bytes meta;
  Bytes pairs;
  pairs.str("ros_distro").str("jazzy");
  meta.str("rosbag2").u32(static_cast<std::uint32_t>(pairs.b.size())).raw(pairs.b);
  f.record(0x0C, meta);
  f.record(0x80, Bytes().u32(0xdeadbeef));  // a user record: skipped knowingly
  f.record(0x0F, Bytes().u32(crc(f.b)));
  const std::uint64_t summary_start = f.b.size();
  f.record(0x03, schema_body(1, "std_msgs/msg/String"));
  f.record(0x04, channel_body(0, 1, "/chatter"));
  Bytes stats;
  stats.u64(3).u16(1).u32(1).u32(1).u32(1).u32(3).u64(1).u64(3).u32(10).u16(0).u64(3);
  f.record(0x0B, stats);
  Bytes ci;
  ci.u64(1).u64(1).u64(0).u64(0).u32(10).u16(0).u64(0).u64(0).str("").u64(0).u64(0);
  f.record(0x08, ci);
  Bytes ai;
  ai.u64(0).u64(0).u64(5).u64(6).u64(3).str("calibration.yaml").str("text/yaml");
  f.record(0x0A, ai);
  Bytes mi;
  mi.u64(0).u64(0).str("rosbag2");
  f.record(0x0D, mi);
  const std::uint64_t offsets_start = f.b.size();
  Bytes so;
  so.u8(0x03).u64(summary_start).u64(10);
  f.record(0x0E, so);
  const std::size_t footer_at = f.b.size();
  f.u8(0x02).u64(20).u64(summary_start).u64(offsets_start);
  f.u32(crc(f.b, summary_start, footer_at + 25));
  f.magic();
  return f.b;
}

std::vector<std::uint8_t> read_file(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::vector<std::uint8_t>(std::istreambuf_iterator<char>(in), {});
}
void write_file(const fs::path& p, const std::vector<std::uint8_t>& bytes) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

std::vector<mcap::Record> read_mcap(const std::vector<std::uint8_t>& bytes) {
  mcap::Reader reader(std::make_unique<std::istringstream>(std::string(bytes.begin(), bytes.end())), "mem.mcap");
  std::vector<mcap::Record> out;
  mcap::Record r;
  while (reader.next(r)) out.push_back(r);
  REQUIRE(reader.state() == mcap::State::kEnd);
  return out;
}

std::string mcap_error(const std::vector<std::uint8_t>& bytes) {
  try {
    mcap::Reader reader(std::make_unique<std::istringstream>(std::string(bytes.begin(), bytes.end())), "bad.mcap");
    mcap::Record r;
    while (reader.next(r)) {
    }
  } catch (const TraceFormatError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

// --- The real bags --------------------------------------------------------------------------------

TEST_CASE("rosbag: the talker MCAP bag (zstd chunks, Go writer): every message counted, strings decoded",
          "[trace][rosbag]") {
  BagImportReport report;
  auto reader = read_bag(kBags / "rosbag2-talker-mcap", {}, &report);
  CHECK(report.storage == "mcap");
  CHECK(report.messages == 20);
  CHECK(report.topic_messages.at("/topic") == 10);
  CHECK(report.topic_messages.at("/rosout") == 10);
  CHECK(report.topic_types.at("/topic") == "std_msgs/msg/String");
  CHECK(report.converted.at("std_msgs/msg/String") == 10);
  CHECK(report.skipped_unsupported.at("rcl_interfaces/msg/Log") == 10);
  CHECK(report.records_written == 10);
  CHECK(report.mcap_records.at(mcap::Opcode::kChunk) >= 1);
  // Header, a zstd chunk (3 schemas, 3 channels, 20 messages), 2 message indexes, DataEnd, and the
  // summary: 3 schemas, 3 channels, statistics, a chunk index, 4 summary offsets; then the footer.
  CHECK(report.mcap_records.at(mcap::Opcode::kChunk) == 1);
  CHECK(report.mcap_records.at(mcap::Opcode::kMessage) == 20);
  CHECK(report.mcap_records.at(mcap::Opcode::kMessageIndex) == 2);
  CHECK(report.mcap_records.at(mcap::Opcode::kSchema) == 6);
  CHECK(report.mcap_records.at(mcap::Opcode::kSummaryOffset) == 4);
  CHECK(report.mcap_records.at(mcap::Opcode::kFooter) == 1);
  CHECK(report.warnings.empty());
  const auto records = all_records(*reader);
  REQUIRE(records.size() == 10);
  CHECK(reader->channels().at(0).name == "topic");
  CHECK(reader->channels().at(0).kind == ChannelKind::kEvent);
  for (std::size_t i = 0; i < records.size(); ++i) {
    CHECK(std::get<EventRecord>(records[i].data).name == "Hello, world! " + std::to_string(i));
  }
  CHECK(to_ns(stamp_of(records.front().data)) >= 1585866235112411371);
}

TEST_CASE("rosbag: the talker db3 bag agrees with its MCAP twin", "[trace][rosbag]") {
  BagImportReport db3;
  BagImportReport mcap;
  auto from_db3 = read_bag(kBags / "rosbag2-talker-db3", {}, &db3);
  auto from_mcap = read_bag(kBags / "rosbag2-talker-mcap", {}, &mcap);
  CHECK(db3.storage == "sqlite3");
  CHECK(db3.messages == 20);
  CHECK(db3.topic_messages == mcap.topic_messages);
  CHECK(db3.skipped_unsupported == mcap.skipped_unsupported);
  const auto a = all_records(*from_db3);
  const auto b = all_records(*from_mcap);
  REQUIRE(a.size() == 10);
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) CHECK(a[i].data == b[i].data);
}

TEST_CASE("rosbag: the cdr_test bag's test_msgs types are counted as unsupported, not decoded", "[trace][rosbag]") {
  BagImportReport report;
  auto reader = read_bag(kBags / "rosbag2-cdr_test-mcap" / "cdr_test_0.mcap", {}, &report);
  CHECK(report.messages == 7);
  CHECK(report.skipped_unsupported.at("test_msgs/msg/BasicTypes") == 3);
  CHECK(report.skipped_unsupported.at("test_msgs/msg/Arrays") == 4);
  CHECK(report.records_written == 0);
  CHECK(all_records(*reader).empty());
}

TEST_CASE("rosbag: a converted bag replays through TraceReplay", "[trace][rosbag]") {
  struct Sink : TraceSink {
    std::vector<std::string> events;
    void on_event(const ChannelInfo&, const EventRecord& e) override { events.push_back(e.name); }
  } sink;
  TraceReplay replay(read_bag(kBags / "rosbag2-talker-db3"));
  CHECK(replay.play(sink) == 10);
  CHECK(sink.events.front() == "Hello, world! 0");
  CHECK(sink.events.back() == "Hello, world! 9");
}

// --- Every record type, by hand from the specification ------------------------------------------

TEST_CASE("mcap: a file with every record type reads in order, chunks (none, zstd, lz4) expanded, CRCs checked",
          "[trace][rosbag]") {
  const auto records = read_mcap(every_record_file());
  std::vector<std::string> ops;
  for (const auto& r : records) ops.push_back(r.in_chunk ? std::string("  ") + mcap::to_string(r.opcode) : mcap::to_string(r.opcode));
  const std::vector<std::string> expected = {
      "Header", "Chunk", "  Schema", "  Channel", "  Message", "MessageIndex", "Chunk", "  Message", "MessageIndex",
      "Chunk", "  Message", "MessageIndex", "Attachment", "Metadata", "Unknown", "DataEnd", "Schema", "Channel",
      "Statistics", "ChunkIndex", "AttachmentIndex", "MetadataIndex", "SummaryOffset", "Footer"};
  CHECK(ops == expected);
  std::vector<std::string> texts;
  for (const auto& r : records) {
    if (const auto* m = std::get_if<mcap::Message>(&r.body)) {
      texts.push_back(ros::decode_cdr<ros::String>(m->data).data);
      CHECK(m->sequence == 7);
    }
  }
  CHECK(texts == std::vector<std::string>{"one", "two", "three"});
  CHECK(std::get<mcap::Header>(records[0].body).library == "hand-built");
  CHECK(std::get<mcap::Chunk>(records[6].body).compression == "zstd");
  CHECK(std::get<mcap::Chunk>(records[9].body).compression == "lz4");
  CHECK(std::get<mcap::Channel>(records[3].body).metadata.count("offered_qos_profiles") == 1);
  CHECK(std::get<mcap::Attachment>(records[12].body).name == "calibration.yaml");
  CHECK(std::get<mcap::Metadata>(records[13].body).metadata.at("ros_distro") == "jazzy");
  CHECK(std::get<mcap::Unknown>(records[14].body).opcode == 0x80);
  const auto& stats = std::get<mcap::Statistics>(records[18].body);
  CHECK(stats.message_count == 3);
  CHECK(stats.channel_message_counts.at(0) == 3);
  CHECK(std::get<mcap::SummaryOffset>(records[22].body).group_opcode == 0x03);
}

TEST_CASE("mcap: the writer's files read back with their summary, uncompressed and zstd", "[trace][rosbag]") {
  for (const auto compression : {mcap::Compression::kNone, mcap::Compression::kZstd}) {
    std::stringbuf buffer;
    {
      mcap::WriterOptions options;
      options.compression = compression;
      options.chunk_bytes = 64;  // several chunks
      mcap::Writer w(std::make_unique<std::ostream>(&buffer), "mem.mcap", options);
      const auto schema = w.add_schema("std_msgs/msg/String", "ros2msg", "string data");
      const auto channel = w.add_channel("/chatter", "cdr", schema);
      w.write_metadata("rosbag2", {{"ros_distro", "jazzy"}});
      for (int i = 0; i < 20; ++i) w.write(channel, 100 + i, 100 + i, encode_cdr_string("msg " + std::to_string(i)));
      w.close();
    }
    const std::string s = buffer.str();
    const auto records = read_mcap(std::vector<std::uint8_t>(s.begin(), s.end()));
    std::size_t messages = 0;
    std::size_t chunks = 0;
    std::size_t chunk_indexes = 0;
    const mcap::Statistics* stats = nullptr;
    for (const auto& r : records) {
      messages += r.opcode == mcap::Opcode::kMessage ? 1 : 0;
      chunks += r.opcode == mcap::Opcode::kChunk ? 1 : 0;
      chunk_indexes += r.opcode == mcap::Opcode::kChunkIndex ? 1 : 0;
      if (const auto* st = std::get_if<mcap::Statistics>(&r.body)) stats = st;
    }
    CHECK(messages == 20);
    CHECK(chunks > 1);
    CHECK(chunk_indexes == chunks);
    REQUIRE(stats != nullptr);
    CHECK(stats->message_count == 20);
    CHECK(stats->message_start_time == 100);
    CHECK(stats->message_end_time == 119);
    CHECK(stats->metadata_count == 1);
  }
}

// --- Synthetic sensor bags: each supported type, field by field ---------------------------------

namespace {
ros::Header header(std::int32_t sec, std::uint32_t ns, const std::string& frame) { return {{sec, ns}, frame}; }

fs::path sensor_bag() {
  const fs::path path = scratch("sensors.mcap");
  mcap::Writer w(path);
  const auto add = [&](const std::string& topic, const std::string& type) {
    return w.add_channel(topic, "cdr", w.add_schema(type, "ros2msg", ""));
  };
  ros::LaserScan scan;
  scan.header = header(10, 500, "laser");
  scan.angle_min = -1.5f;
  scan.angle_max = 1.5f;
  scan.angle_increment = 0.75f;
  scan.time_increment = 0.001f;
  scan.scan_time = 0.1f;
  scan.range_min = 0.05f;
  scan.range_max = 30.0f;
  scan.ranges = {1.0f, 2.0f, 3.0f, 4.0f, 5.0f};
  scan.intensities = {10.0f, 20.0f, 30.0f, 40.0f, 50.0f};
  w.write(add("/scan", "sensor_msgs/msg/LaserScan"), 10'000'000'600, 0, ros::encode_cdr(scan));
  ros::Odometry odom;
  odom.header = header(11, 0, "odom");
  odom.child_frame_id = "base_link";
  odom.pose.position = {1.0, 2.0, 0.0};
  odom.pose.orientation = ros::quaternion_from_yaw(0.5);
  odom.pose_covariance[0] = 0.01;
  odom.twist.linear = {0.3, 0.1, 0.0};
  odom.twist.angular = {0.0, 0.0, -0.2};
  w.write(add("/odom", "nav_msgs/msg/Odometry"), 11'000'000'100, 0, ros::encode_cdr(odom, /*little_endian=*/false));
  ros::Imu imu;
  imu.header = header(12, 0, "imu");
  imu.orientation = ros::quaternion_from_yaw(-1.0);
  imu.angular_velocity = {0.0, 0.0, 0.25};
  imu.linear_acceleration = {0.0, 0.0, 9.81};
  w.write(add("/imu", "sensor_msgs/msg/Imu"), 12'000'000'000, 0, ros::encode_cdr(imu));
  ros::Twist twist;
  twist.linear.x = 0.4;
  twist.angular.z = 0.6;
  w.write(add("/cmd_vel", "geometry_msgs/msg/Twist"), 13'000'000'000, 0, ros::encode_cdr(twist));
  ros::TFMessage tf;
  tf.transforms.push_back({header(14, 0, "odom"), "base_link", {3.0, 4.0, 0.0}, ros::quaternion_from_yaw(1.0)});
  tf.transforms.push_back({header(14, 0, "base_link"), "laser", {0.2, 0.0, 0.3}, {}});
  w.write(add("/tf", "tf2_msgs/msg/TFMessage"), 14'000'000'000, 0, ros::encode_cdr(tf));
  ros::JointState js;
  js.header = header(15, 0, "");
  js.name = {"left_wheel", "right_wheel"};
  js.position = {1.0, 2.0};
  js.velocity = {0.1, 0.2};
  w.write(add("/joint_states", "sensor_msgs/msg/JointState"), 15'000'000'000, 0, ros::encode_cdr(js));
  w.write(add("/clock", "rosgraph_msgs/msg/Clock"), 16'000'000'000, 0, ros::encode_cdr(ros::Clock{{16, 5}}));
  ros::OccupancyGrid grid;
  grid.header = header(17, 0, "map");
  grid.resolution = 0.05f;
  grid.width = 3;
  grid.height = 2;
  grid.origin.position = {-1.0, -2.0, 0.0};
  grid.data = {0, 100, -1, 0, 50, 0};
  w.write(add("/map", "nav_msgs/msg/OccupancyGrid"), 17'000'000'000, 0, ros::encode_cdr(grid));
  w.write(add("/note", "std_msgs/msg/String"), 18'000'000'000, 0, encode_cdr_string("docked"));
  w.write_metadata("rosbag2", {{"ros_distro", "jazzy"}});
  w.close();
  return path;
}
}  // namespace

TEST_CASE("rosbag: a synthetic sensor bag converts each supported type field by field", "[trace][rosbag]") {
  BagImportReport report;
  auto reader = read_bag(sensor_bag(), {}, &report);
  CHECK(report.messages == 9);
  CHECK(report.storage_metadata.at("rosbag2.ros_distro") == "jazzy");
  CHECK(report.skipped_no_channel_kind.at("sensor_msgs/msg/JointState") == 1);
  CHECK(report.skipped_no_channel_kind.at("rosgraph_msgs/msg/Clock") == 1);
  CHECK(report.skipped_no_channel_kind.at("nav_msgs/msg/OccupancyGrid") == 1);
  CHECK(report.tf_transforms_skipped == 1);
  const auto records = all_records(*reader);
  REQUIRE(records.size() == 6);
  const auto& scan = std::get<LaserScan>(records[0].data);
  CHECK(reader->channel(records[0].channel).name == "laser");
  CHECK(to_ns(scan.stamp) == 10'000'000'500);
  CHECK(scan.angle_min_rad == -1.5);
  CHECK(scan.angle_increment_rad == 0.75);
  CHECK(scan.range_max_m == 30.0);
  CHECK(scan.time_increment_s == Approx(0.001));
  CHECK(scan.ranges_m == std::vector<float>{1, 2, 3, 4, 5});
  CHECK(scan.intensities == std::vector<float>{10, 20, 30, 40, 50});
  const auto& odom = std::get<OdometryReading>(records[1].data);
  CHECK(reader->channel(records[1].channel).name == "odometry");
  CHECK(to_ns(odom.stamp) == 11'000'000'000);
  CHECK(odom.pose.x_m == 1.0);
  CHECK(odom.pose.y_m == 2.0);
  CHECK(odom.pose.theta_rad == Approx(0.5));
  CHECK(odom.twist.vx_m_s == 0.3);
  CHECK(odom.twist.vy_m_s == 0.1);
  CHECK(odom.twist.wz_rad_s == -0.2);
  const auto& gyro = std::get<GyroReading>(records[2].data);
  CHECK(gyro.yaw_rate_rad_s == 0.25);
  CHECK(gyro.yaw_rad == Approx(-1.0));
  const auto& cmd = std::get<CommandRecord>(records[3].data);
  CHECK(cmd.twist.vx_m_s == 0.4);
  CHECK(cmd.twist.wz_rad_s == 0.6);
  CHECK(cmd.source == "/cmd_vel");
  CHECK(to_ns(cmd.stamp) == 13'000'000'000);  // a Twist has no header: the receive time
  const auto& tf = std::get<OdometryReading>(records[4].data);
  CHECK(reader->channel(records[4].channel).name == "tf");
  CHECK(tf.pose.x_m == 3.0);
  CHECK(tf.pose.theta_rad == Approx(1.0));
  CHECK(std::get<EventRecord>(records[5].data).name == "docked");
  CHECK(reader->channel(records[5].channel).name == "note");
}

TEST_CASE("rosbag: the decoders without a channel kind read every field", "[trace][rosbag]") {
  BagImportReport report;
  std::map<std::string, std::vector<std::uint8_t>> data;
  for_each_bag_message(sensor_bag(), [&](const BagMessage& m) { data[m.topic].assign(m.data.begin(), m.data.end()); },
                       report);
  const auto js = ros::decode_cdr<ros::JointState>(data.at("/joint_states"));
  CHECK(js.name == std::vector<std::string>{"left_wheel", "right_wheel"});
  CHECK(js.position == std::vector<double>{1.0, 2.0});
  CHECK(js.velocity == std::vector<double>{0.1, 0.2});
  CHECK(js.effort.empty());
  CHECK(ros::decode_cdr<ros::Clock>(data.at("/clock")).clock == ros::Time{16, 5});
  const auto grid = ros::decode_cdr<ros::OccupancyGrid>(data.at("/map"));
  CHECK(grid.resolution == 0.05f);
  CHECK(grid.width == 3);
  CHECK(grid.height == 2);
  CHECK(grid.origin.position.y == -2.0);
  CHECK(grid.data == std::vector<std::int8_t>{0, 100, -1, 0, 50, 0});
  const auto odom = ros::decode_cdr<ros::Odometry>(data.at("/odom"));  // written big endian
  CHECK(odom.child_frame_id == "base_link");
  CHECK(odom.pose_covariance[0] == 0.01);
  CHECK(odom.header.frame_id == "odom");
  const auto tf = ros::decode_cdr<ros::TFMessage>(data.at("/tf"));
  REQUIRE(tf.transforms.size() == 2);
  CHECK(tf.transforms[1].child_frame_id == "laser");
  CHECK(tf.transforms[1].translation.z == 0.3);
}

TEST_CASE("rosbag: the topic mapping renames channels and --only-mapped leaves the rest", "[trace][rosbag]") {
  BagImportOptions options;
  options.topic_channels = {{"/scan", "front_laser"}};
  options.only_mapped = true;
  BagImportReport report;
  auto reader = read_bag(sensor_bag(), options, &report);
  const auto records = all_records(*reader);
  REQUIRE(records.size() == 1);
  CHECK(reader->channel(records[0].channel).name == "front_laser");
  CHECK(report.skipped_unmapped.at("/odom") == 1);
}

TEST_CASE("rosbag: a trace exported as MCAP converts back to the same records", "[trace][rosbag]") {
  const fs::path trace_path = scratch("export.trace");
  {
    TraceWriter w(trace_path);
    const auto laser = w.add_channel("laser", ChannelKind::kLaser);
    const auto odom = w.add_channel("odometry", ChannelKind::kOdometry);
    const auto cmd = w.add_channel("cmd_vel", ChannelKind::kCommand);
    const auto ev = w.add_channel("events", ChannelKind::kEvent);
    const auto bat = w.add_channel("battery", ChannelKind::kBattery);
    LaserScan s;
    s.stamp = time_from_ns(1'000'000'000);
    s.angle_min_rad = -1.0;
    s.angle_max_rad = 1.0;
    s.angle_increment_rad = 0.5;
    s.range_max_m = 10.0;
    s.ranges_m = {1, 2, 3, 4, 5};
    w.write(laser, s);
    w.write(odom, OdometryReading{time_from_ns(2'000'000'000), {1.0, 2.0, 0.25}, {0.5, 0.0, 0.1}});
    w.write(cmd, CommandRecord{time_from_ns(3'000'000'000), {0.2, 0.0, 0.3}, "cmd_vel"});
    w.write(ev, EventRecord{time_from_ns(4'000'000'000), "goal reached"});
    w.write(bat, BatteryReading{time_from_ns(5'000'000'000), 24.0, 1.0, 0.5, false});
    w.close();
  }
  const fs::path bag = scratch("export.mcap");
  McapExportReport exported;
  {
    TraceReader in(trace_path);
    mcap::Writer out(bag);
    exported = export_trace_to_mcap(in, out);
  }
  CHECK(exported.records == 5);
  CHECK(exported.messages == 4);
  CHECK(exported.skipped.at("battery") == 1);
  BagImportOptions options;
  options.topic_channels.clear();  // channels named after the topics: /laser -> laser, ...
  auto back = read_bag(bag, options);
  const auto records = all_records(*back);
  REQUIRE(records.size() == 4);
  const auto& s = std::get<LaserScan>(records[0].data);
  CHECK(s.ranges_m == std::vector<float>{1, 2, 3, 4, 5});
  CHECK(to_ns(s.stamp) == 1'000'000'000);
  const auto& o = std::get<OdometryReading>(records[1].data);
  CHECK(o.pose.theta_rad == Approx(0.25));
  CHECK(o.twist.wz_rad_s == 0.1);
  CHECK(std::get<CommandRecord>(records[2].data).twist.wz_rad_s == 0.3);
  CHECK(std::get<EventRecord>(records[3].data).name == "goal reached");
  CHECK(back->channel(records[3].channel).name == "events");
}

// --- Bad input ----------------------------------------------------------------------------------

TEST_CASE("rosbag: a truncated MCAP (no footer) gives the whole chunks before the cut and says what is lost",
          "[trace][rosbag]") {
  auto bytes = read_file(kBags / "rosbag2-talker-mcap" / "talker.mcap");
  // Keep the header and the first chunk, then cut inside the next record.
  const auto whole = read_mcap(bytes);
  std::uint64_t second_record = 0;
  for (const auto& r : whole) {
    if (!r.in_chunk && r.offset > 8 && r.opcode != mcap::Opcode::kHeader && r.opcode != mcap::Opcode::kChunk) {
      second_record = r.offset;  // the record after the first chunk (its MessageIndex)
      break;
    }
  }
  REQUIRE(second_record > 0);
  bytes.resize(second_record + 5);
  const fs::path cut = scratch("truncated.mcap");
  write_file(cut, bytes);
  BagImportReport report;
  auto reader = read_bag(cut, {}, &report);
  CHECK(report.messages == 20);  // the talker's only chunk came through
  REQUIRE(report.warnings.size() == 1);
  CHECK_THAT(report.warnings[0], Contains("truncated.mcap: truncated at byte " + std::to_string(second_record)));
  CHECK_THAT(report.warnings[0], Contains("with no Footer the summary"));

  // Cut inside the zstd chunk: its one zstd block decodes only whole, so nothing is recovered.
  bytes.resize(600);
  write_file(cut, bytes);
  BagImportReport part;
  auto partial = read_bag(cut, {}, &part);
  CHECK(part.messages == 0);
  REQUIRE(part.warnings.size() == 1);
  CHECK_THAT(part.warnings[0], Contains("truncated at byte 45 (the Chunk record there declares 2956 bytes, only 546 "
                                        "follow): the 555 bytes from there on are lost"));

  // Cut inside an uncompressed chunk: the same, without a decompressor.
  auto plain = read_file(kBags / "rosbag2-cdr_test-mcap" / "cdr_test_0.mcap");
  plain.resize(plain.size() / 3);
  write_file(cut, plain);
  BagImportReport cdr;
  (void)read_bag(cut, {}, &cdr);
  CHECK(cdr.messages > 0);
  CHECK(cdr.messages < 7);
  REQUIRE(cdr.warnings.size() == 1);
  CHECK_THAT(cdr.warnings[0], Contains("whole records were recovered from the start of that Chunk"));
}

TEST_CASE("rosbag: bad MCAP input is refused with the file and the record offset", "[trace][rosbag]") {
  SECTION("a bad chunk CRC") {
    auto bytes = every_record_file();
    // The first chunk is uncompressed: flip a byte of its message text ("one").
    const std::string text = "one";
    const auto it = std::search(bytes.begin(), bytes.end(), text.begin(), text.end());
    REQUIRE(it != bytes.end());
    *it = 'x';
    CHECK_THAT(mcap_error(bytes), Contains("bad.mcap: byte 39: Chunk: CRC-32"));
  }
  SECTION("a bad data section CRC") {
    auto bytes = every_record_file();
    const std::string lib = "hand-built";
    const auto it = std::search(bytes.begin(), bytes.end(), lib.begin(), lib.end());
    *it = 'H';
    CHECK_THAT(mcap_error(bytes), Contains("DataEnd: data section CRC-32"));
  }
  SECTION("a bad summary CRC") {
    auto bytes = every_record_file();
    bytes[bytes.size() - 8 - 1] ^= 0xff;  // the footer's summary_crc
    CHECK_THAT(mcap_error(bytes), Contains("Footer: summary CRC-32"));
  }
  SECTION("an unknown compression") {
    Bytes f;
    f.magic().record(0x01, Bytes().str("").str(""));
    Bytes rec;
    rec.record(0x03, schema_body(1, "std_msgs/msg/String"));
    f.record(0x06, chunk_body(rec.b, "brotli", rec.b, 0));
    CHECK_THAT(mcap_error(f.b), Contains("bad.mcap: byte 25: Chunk: unknown compression 'brotli'"));
  }
  SECTION("a chunk claiming 4 GiB is refused before allocating") {
    Bytes f;
    f.magic().record(0x01, Bytes().str("").str(""));
    Bytes c;
    c.u64(0).u64(0).u64(std::uint64_t{4} << 30).u32(0).str("zstd").u64(4).raw({1, 2, 3, 4});
    f.record(0x06, c);
    CHECK_THAT(mcap_error(f.b), Contains("byte 25: Chunk declares 4294967296 uncompressed bytes"));
    Bytes g;
    g.magic().u8(0x06).u64(std::uint64_t{4} << 30);
    CHECK_THAT(mcap_error(g.b), Contains("byte 8: Chunk record declares 4294967296 bytes"));
  }
  SECTION("not an MCAP file") {
    CHECK_THAT(mcap_error({'h', 'e', 'l', 'l', 'o', 0, 0, 0, 0}), Contains("bad.mcap: byte 0: not an MCAP file"));
  }
  SECTION("a field running past its record") {
    Bytes f;
    f.magic().record(0x01, Bytes().u32(100));
    CHECK_THAT(mcap_error(f.b), Contains("byte 8: Header record: string field of 100 bytes runs past"));
  }
}

TEST_CASE("rosbag: a message whose schema is not supported is skipped with a count", "[trace][rosbag]") {
  const fs::path path = scratch("unsupported.mcap");
  {
    mcap::Writer w(path);
    const auto c = w.add_channel("/diag", "cdr", w.add_schema("diagnostic_msgs/msg/DiagnosticArray", "ros2msg", ""));
    const auto j = w.add_channel("/json", "json", w.add_schema("std_msgs/msg/String", "jsonschema", ""));
    for (int i = 0; i < 3; ++i) w.write(c, 1, 1, {0, 1, 0, 0, 1, 2, 3, 4});
    w.write(j, 2, 2, {'{', '}'});
    w.close();
  }
  BagImportReport report;
  auto reader = read_bag(path, {}, &report);
  CHECK(report.messages == 4);
  CHECK(report.skipped_unsupported.at("diagnostic_msgs/msg/DiagnosticArray") == 3);
  CHECK(report.skipped_unsupported.at("std_msgs/msg/String [json]") == 1);
  CHECK(all_records(*reader).empty());
}

TEST_CASE("rosbag: CDR with a wrong encapsulation or a length past the end is refused with its offset",
          "[trace][rosbag]") {
  CHECK_THROWS_WITH(ros::decode_cdr<ros::String>(std::vector<std::uint8_t>{0, 6, 0, 0, 1, 0, 0, 0, 0}, "m", 100),
                    Contains("m: byte 100: CDR encapsulation 00 06 is not plain XCDR1"));
  CHECK_THROWS_WITH(ros::decode_cdr<ros::String>(std::vector<std::uint8_t>{0, 1}, "m", 0),
                    Contains("no 4-byte encapsulation header"));
  // A string claiming 1000 bytes in an 8-byte message.
  CHECK_THROWS_WITH(ros::decode_cdr<ros::String>(std::vector<std::uint8_t>{0, 1, 0, 0, 0xe8, 3, 0, 0}, "m", 0),
                    Contains("m: byte 8: CDR: string of 1000 bytes past the end of the message (0 left)"));
  // A scan claiming 2^30 ranges: refused from the length, before allocating.
  ros::LaserScan scan;
  auto bytes = ros::encode_cdr(scan);
  bytes[bytes.size() - 5] = 0x40;  // the high byte of the ranges count (the last field is intensities)
  CHECK_THROWS_WITH(ros::decode_cdr<ros::LaserScan>(bytes), Contains("sequence of"));
  // Big endian decodes as little endian does.
  ros::String s{"big"};
  CHECK(ros::decode_cdr<ros::String>(ros::encode_cdr(s, false)) == s);

  // In a bag, the refusal names the file, the chunk and the message's byte.
  const fs::path path = scratch("bad_cdr.mcap");
  {
    mcap::Writer w(path, {mcap::Compression::kNone});
    const auto c = w.add_channel("/chatter", "cdr", w.add_schema("std_msgs/msg/String", "ros2msg", ""));
    w.write(c, 1, 1, {0, 1, 0, 0, 0xe8, 3, 0, 0});
    w.close();
  }
  CHECK_THROWS_WITH(read_bag(path), Contains("bad_cdr.mcap: byte ") && Contains("Message on /chatter (std_msgs/msg/String)") &&
                                        Contains("of this Chunk's records, byte 8 of its data"));
}

TEST_CASE("rosbag: a db3 without table messages is refused naming the file and the table", "[trace][rosbag]") {
  const fs::path path = scratch("no_messages.db3");
  fs::remove(path);
  fs::copy_file(kBags / "rosbag2-talker-db3" / "talker.db3", path);
  sqlite3* db = nullptr;
  REQUIRE(sqlite3_open(path.string().c_str(), &db) == SQLITE_OK);
  REQUIRE(sqlite3_exec(db, "DROP TABLE messages", nullptr, nullptr, nullptr) == SQLITE_OK);
  sqlite3_close(db);
  CHECK_THROWS_WITH(read_bag(path), Contains("no_messages.db3: no table 'messages': not a rosbag2 SQLite3 bag"));

  const fs::path junk = scratch("junk.db3");
  write_file(junk, std::vector<std::uint8_t>(100, 'x'));
  CHECK_THROWS_AS(read_bag(junk), BagFormatError);

  // The talker's table schema says which ROS release wrote it (schema 4, rolling).
  BagImportReport report;
  (void)read_bag(kBags / "rosbag2-talker-db3", {}, &report);
  CHECK(report.storage_metadata.at("ros_distro") == "rolling");
  CHECK(report.storage_metadata.at("schema_version") == "4");
}
