// `tripodal trace import|convert|info|dump`: convert CARMEN logs and rosbag2 bags to tripodal traces
// (and traces to MCAP bags), inspect traces.
#include <algorithm>
#include <filesystem>
#include <functional>
#include <map>
#include <memory>
#include <ostream>

#include "cli_tool.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/trace/carmen_import.hpp"
#include "tripodal/trace/rosbag.hpp"
#include "tripodal/trace/trace_reader.hpp"

namespace tripodal::tool {
namespace {

using namespace tripodal::trace;
using namespace cli;

std::string seconds(Time t) { return format_seconds(t, 6); }
std::string seconds(Duration d) { return format_seconds(d, 6); }

// ---------------------------------------------------------------------------------------------
constexpr std::string_view kImportDescription =
    "Converts a CARMEN log (plain or gzip-compressed) to a tripodal trace.\n"
    "FLASER/ROBOTLASER1 -> laser channel (default front_laser), RLASER/ROBOTLASER2 -> rear_laser,\n"
    "ODOM -> odometry channel (default odom), the laser pose of each scan -> laser_pose.\n"
    "Other messages are skipped and counted; time stamps that go backwards are clamped.\n"
    "Malformed lines are reported as LOG:LINE:COL and OUT is removed (exit 1).";

constexpr std::string_view kExitCodes = "exit codes: 0 ok, 1 bad input, 2 bad command line, 3 I/O error";

struct ImportArgs {
  std::filesystem::path log, trace;
  bool no_laser_pose = false;
  CarmenImportOptions options;
};

int trace_import(const ImportArgs& args, std::ostream& out, std::ostream& err) {
  CarmenImportOptions options = args.options;
  if (args.no_laser_pose) options.laser_pose_channel.clear();
  const std::filesystem::path& log = args.log;
  const std::filesystem::path& trace_path = args.trace;
  if (!std::filesystem::exists(log)) {
    err << "tripodal trace import: " << log.string() << ": no such file\n";
    return kIoError;
  }
  CarmenImportReport report;
  try {
    TraceWriter writer(trace_path);
    report = import_carmen_log(log, writer, options);
    writer.close();
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    std::error_code ec;
    std::filesystem::remove(trace_path, ec);
    return kBadInput;
  } catch (const TraceIoError& e) {
    err << "tripodal trace import: " << e.what() << '\n';
    std::error_code ec;
    std::filesystem::remove(trace_path, ec);
    return kIoError;
  }
  out << "imported " << log.string() << " -> " << trace_path.string() << '\n'
      << "lines: " << report.lines << '\n'
      << "laser scans: " << report.laser_scans << '\n'
      << "odometry readings: " << report.odometry_readings << '\n'
      << "laser poses: " << report.laser_poses << '\n'
      << "params: " << report.params.size() << '\n';
  for (const auto& [type, n] : report.skipped) out << "skipped " << type << ": " << n << '\n';
  out << "backwards time stamps clamped: " << report.backwards_steps;
  if (report.backwards_steps > 0) out << " (largest step back " << seconds(report.largest_backwards_step) << " s)";
  out << '\n' << "duration: " << seconds(report.last_stamp - report.first_stamp) << " s\n";
  return kOk;
}

// ---------------------------------------------------------------------------------------------
constexpr std::string_view kInfoDescription =
    "Prints the format version, duration, channels and the number of records of each kind.\n"
    "FILE may be a rosbag2 bag: it is read as the trace it converts to (docs/rosbag.md).\n"
    "A trace cut inside a record (recorder killed) is summarised up to its last whole record\n"
    "with a warning (exit 0); a corrupt trace is an error naming the byte offset (exit 1).";

constexpr std::string_view kind_label(ChannelKind kind) {
  switch (kind) {
    case ChannelKind::kLaser: return "laser scans";
    case ChannelKind::kOdometry: return "odometry readings";
    case ChannelKind::kSonar: return "sonar readings";
    case ChannelKind::kInfrared: return "infrared readings";
    case ChannelKind::kBumper: return "bumper readings";
    case ChannelKind::kBattery: return "battery readings";
    case ChannelKind::kGyro: return "gyro readings";
    case ChannelKind::kCommand: return "commands";
    case ChannelKind::kEvent: return "events";
  }
  return "unknown";
}

// A rosbag2 bag is read as the trace it converts to (default topic mapping, docs/rosbag.md).
int with_reader(const std::string& path, std::ostream& err, const std::function<int(TraceReader&)>& body) {
  try {
    BagImportReport bag;
    const bool is_bag = is_rosbag(path);
    const auto reader = is_bag ? read_bag(path, {}, &bag) : std::make_unique<TraceReader>(path);
    const int rc = body(*reader);
    if (reader->state() == ReadState::kTruncated) err << "warning: " << reader->warning() << '\n';
    for (const auto& w : bag.warnings) err << "warning: " << w << '\n';
    return rc;
  } catch (const BagFormatError& e) {
    err << "error: " << e.what() << '\n';
    return kBadInput;
  } catch (const TraceFormatError& e) {
    err << "error: " << e.what() << '\n';
    return kBadInput;
  } catch (const TraceIoError& e) {
    err << "error: " << e.what() << '\n';
    return kIoError;
  }
}

int trace_info(const std::string& path, std::ostream& out, std::ostream& err) {
  std::map<ChannelId, std::uint64_t> per_channel;
  std::uint64_t records = 0;
  Time first{};
  Time last{};
  std::uint64_t backwards = 0;
  // Counted while reading so that a corrupt tail still shows what came before it.
  const auto report = [&](TraceReader& r) {
    out << "file: " << path << '\n'
        << "format version: " << r.format_version() << '\n'
        << "bytes: " << r.offset() << '\n'
        << "records: " << records << '\n';
    if (records > 0) {
      out << "start: " << seconds(first) << " s\n"
          << "end: " << seconds(last) << " s\n"
          << "duration: " << seconds(last - first) << " s\n";
    }
    if (backwards > 0) out << "records stamped before their predecessor: " << backwards << '\n';
    out << "channels:\n";
    std::map<ChannelKind, std::uint64_t> per_kind;
    for (const auto& c : r.channels()) {
      const auto n = per_channel[c.id];
      per_kind[c.kind] += n;
      out << "  " << c.name << " (" << to_string(c.kind) << "): " << n << '\n';
    }
    for (const auto& [kind, n] : per_kind) out << kind_label(kind) << ": " << n << '\n';
    out << "status: " << (r.state() == ReadState::kTruncated ? "truncated" : "complete") << '\n';
  };
  return with_reader(path, err, [&](TraceReader& r) {
    TraceRecord rec;
    try {
      while (r.next(rec)) {
        const Time t = stamp_of(rec.data);
        if (records == 0) first = t;
        if (records > 0 && t < last) ++backwards;
        last = std::max(last, t);
        ++records;
        ++per_channel[rec.channel];
      }
    } catch (const TraceFormatError&) {
      report(r);
      throw;
    }
    report(r);
    return static_cast<int>(kOk);
  });
}

// ---------------------------------------------------------------------------------------------
constexpr std::string_view kDumpDescription =
    "Prints one line per record: time stamp (s), channel, kind and values. --limit stops after N\n"
    "records; --beams K shows the first K ranges of each scan (default 8, 0 for all).";

struct DumpArgs {
  std::string file;
  std::size_t limit = 0;
  std::size_t beams = 8;
};

template <typename T>
void list(std::ostream& out, const std::vector<T>& v, std::size_t limit) {
  const std::size_t n = limit == 0 ? v.size() : std::min(limit, v.size());
  out << '[';
  for (std::size_t i = 0; i < n; ++i) out << (i ? " " : "") << +v[i];
  if (n < v.size()) out << " ...";
  out << ']';
}

void dump_record(std::ostream& out, const ChannelInfo& c, const RecordData& data, std::size_t beams) {
  out << seconds(stamp_of(data)) << ' ' << c.name << ' ' << to_string(c.kind);
  std::visit(
      [&](const auto& r) {
        using T = std::decay_t<decltype(r)>;
        if constexpr (std::is_same_v<T, LaserScan>) {
          out << " beams=" << r.ranges_m.size() << " angle=[" << r.angle_min_rad << ", " << r.angle_max_rad
              << "] inc=" << r.angle_increment_rad << " range=[" << r.range_min_m << ", " << r.range_max_m
              << "] ranges=";
          list(out, r.ranges_m, beams);
          if (!r.intensities.empty()) {
            out << " intensities=";
            list(out, r.intensities, beams);
          }
        } else if constexpr (std::is_same_v<T, OdometryReading>) {
          out << " x=" << r.pose.x_m << " y=" << r.pose.y_m << " theta=" << r.pose.theta_rad << " vx=" << r.twist.vx_m_s
              << " vy=" << r.twist.vy_m_s << " wz=" << r.twist.wz_rad_s;
        } else if constexpr (std::is_same_v<T, SonarReading>) {
          out << " fov=" << r.field_of_view_rad << " range=[" << r.range_min_m << ", " << r.range_max_m << "] ranges=";
          list(out, r.ranges_m, 0);
        } else if constexpr (std::is_same_v<T, InfraredReading>) {
          out << " cliff=";
          list(out, r.cliff, 0);
          out << " wall=";
          list(out, r.wall_ranges_m, 0);
        } else if constexpr (std::is_same_v<T, BumperReading>) {
          out << " count=" << r.count << " pressed=0x" << std::hex << r.pressed_mask << std::dec;
        } else if constexpr (std::is_same_v<T, BatteryReading>) {
          out << " voltage=" << r.voltage_v << " current=" << r.current_a << " percentage=" << r.percentage
              << " charging=" << (r.charging ? "yes" : "no");
        } else if constexpr (std::is_same_v<T, GyroReading>) {
          out << " yaw_rate=" << r.yaw_rate_rad_s << " yaw=" << r.yaw_rad;
        } else if constexpr (std::is_same_v<T, CommandRecord>) {
          out << " source=" << r.source << " vx=" << r.twist.vx_m_s << " vy=" << r.twist.vy_m_s
              << " wz=" << r.twist.wz_rad_s;
        } else {
          out << " name=" << r.name;
        }
      },
      data);
  out << '\n';
}

int trace_dump(const DumpArgs& args, std::ostream& out, std::ostream& err) {
  const std::size_t limit = args.limit;
  const std::size_t beams = args.beams;
  return with_reader(args.file, err, [&](TraceReader& r) {
    TraceRecord rec;
    std::size_t n = 0;
    std::vector<bool> announced;
    while ((limit == 0 || n < limit) && r.next(rec)) {
      if (announced.size() <= rec.channel) announced.resize(rec.channel + 1u, false);
      const ChannelInfo& c = r.channel(rec.channel);
      if (!announced[rec.channel]) {
        out << "# channel " << c.id << ": " << c.name << " (" << to_string(c.kind) << ")\n";
        announced[rec.channel] = true;
      }
      dump_record(out, c, rec.data, beams);
      ++n;
    }
    return static_cast<int>(kOk);
  });
}

// ---------------------------------------------------------------------------------------------
constexpr std::string_view kConvertDescription =
    "Converts a rosbag2 bag (a folder with metadata.yaml, or an .mcap or .db3 file) to a tripodal\n"
    "trace, or a trace to an MCAP bag file when OUT ends in .mcap (docs/rosbag.md).\n"
    "Topics become channels: /scan -> laser, /odom -> odometry, /imu -> imu, /cmd_vel -> cmd_vel,\n"
    "/tf -> tf (the odom -> base_link transform); --topic /my_scan=front_laser adds or overrides one;\n"
    "other supported topics are named after the topic unless --only-mapped. Messages of types not\n"
    "decoded are skipped and counted per type. A bad bag is an error naming the file and the\n"
    "record's byte offset (or db3 row) and OUT is removed (exit 1).";

struct ConvertArgs {
  std::filesystem::path in, out;
  std::vector<std::string> topics;
  bool only_mapped = false;
  bool header_stamps = true;
  std::string compression = "zstd";
};

int convert_trace_to_mcap(const ConvertArgs& args, std::ostream& out, std::ostream& err) {
  mcap::WriterOptions options;
  options.compression = args.compression == "none" ? mcap::Compression::kNone : mcap::Compression::kZstd;
  McapExportReport report;
  const int rc = with_reader(args.in.string(), err, [&](TraceReader& r) {
    mcap::Writer writer(args.out, options);
    report = export_trace_to_mcap(r, writer);
    return static_cast<int>(kOk);
  });
  if (rc != kOk) {
    std::error_code ec;
    std::filesystem::remove(args.out, ec);
    return rc;
  }
  out << "converted " << args.in.string() << " -> " << args.out.string() << '\n'
      << "records: " << report.records << '\n'
      << "messages: " << report.messages << '\n';
  for (const auto& [kind, n] : report.skipped) out << "skipped " << kind << " (no ROS message here): " << n << '\n';
  return kOk;
}

int trace_convert(const ConvertArgs& args, std::ostream& out, std::ostream& err) {
  if (!std::filesystem::exists(args.in)) {
    err << "tripodal trace convert: " << args.in.string() << ": no such file or folder\n";
    return kIoError;
  }
  // To MCAP: a trace, or a bag read as the trace it converts to (its supported topics re-encoded).
  if (args.out.extension() == ".mcap") return convert_trace_to_mcap(args, out, err);
  BagImportOptions options;
  options.only_mapped = args.only_mapped;
  options.use_header_stamp = args.header_stamps;
  for (const auto& t : args.topics) {
    const auto eq = t.find('=');
    if (eq == std::string::npos || eq == 0 || eq + 1 == t.size()) {
      err << "tripodal trace convert: --topic " << t << ": expected TOPIC=CHANNEL, e.g. /my_scan=laser\n";
      return kUsage;
    }
    options.topic_channels[t.substr(0, eq)] = t.substr(eq + 1);
  }
  BagImportReport report;
  const auto failed = [&](const std::string& what, int rc) {
    err << "error: " << what << '\n';
    std::error_code ec;
    std::filesystem::remove(args.out, ec);
    return rc;
  };
  try {
    TraceWriter writer(args.out);
    report = import_rosbag(args.in, writer, options);
    writer.close();
  } catch (const TraceFormatError& e) {
    return failed(e.what(), kBadInput);
  } catch (const BagFormatError& e) {
    return failed(e.what(), kBadInput);
  } catch (const TraceIoError& e) {
    return failed(e.what(), kIoError);
  }
  out << "converted " << args.in.string() << " (" << report.storage << ") -> " << args.out.string() << '\n'
      << "messages: " << report.messages << '\n';
  for (const auto& [topic, n] : report.topic_messages) {
    out << "  " << topic << " (" << report.topic_types[topic] << "): " << n << '\n';
  }
  out << "records: " << report.records_written << '\n';
  for (const auto& [type, n] : report.converted) out << "converted " << type << ": " << n << '\n';
  for (const auto& [type, n] : report.skipped_unsupported) out << "skipped unsupported " << type << ": " << n << '\n';
  for (const auto& [type, n] : report.skipped_no_channel_kind) out << "skipped, no channel kind " << type << ": " << n << '\n';
  for (const auto& [topic, n] : report.skipped_unmapped) out << "skipped unmapped " << topic << ": " << n << '\n';
  if (report.tf_transforms_skipped > 0) out << "tf transforms skipped: " << report.tf_transforms_skipped << '\n';
  for (const auto& w : report.warnings) err << "warning: " << w << '\n';
  return kOk;
}

cli::Action setup_convert(CLI::App& cmd) {
  auto a = std::make_shared<ConvertArgs>();
  cmd.add_option("IN", a->in, "the bag (folder, .mcap or .db3), or a trace to write as MCAP")->required();
  cmd.add_option("--out", a->out, "OUT: the trace to write (or an .mcap file)")->required();
  cmd.add_option("--topic", a->topics, "TOPIC=CHANNEL: the trace channel of a topic (repeatable)");
  cmd.add_flag("--only-mapped", a->only_mapped, "convert only the topics --topic and the defaults name");
  cmd.add_flag("!--receive-stamps", a->header_stamps, "stamp records with the bag's receive time, not the header's");
  cmd.add_option("--compression", a->compression, "zstd|none: MCAP chunks, when writing .mcap")
      ->check(CLI::IsMember({"zstd", "none"}))
      ->capture_default_str();
  return [a](std::ostream& out, std::ostream& err) { return trace_convert(*a, out, err); };
}

cli::Action setup_import(CLI::App& cmd) {
  auto a = std::make_shared<ImportArgs>();
  cmd.add_option("LOG", a->log, "the CARMEN log (.log or .log.gz)")->required();
  cmd.add_option("OUT", a->trace, "the trace to write")->required();
  cmd.add_option("--laser-channel", a->options.laser_channel, "NAME: channel of the front laser")->capture_default_str();
  cmd.add_option("--odom-channel", a->options.odometry_channel, "NAME: channel of the odometry")->capture_default_str();
  auto* pose = cmd.add_option("--laser-pose-channel", a->options.laser_pose_channel, "NAME: channel of the laser poses")
                   ->capture_default_str();
  cmd.add_flag("--no-laser-pose", a->no_laser_pose, "leave the laser poses out")->excludes(pose);
  return [a](std::ostream& out, std::ostream& err) { return trace_import(*a, out, err); };
}

cli::Action setup_info(CLI::App& cmd) {
  auto file = std::make_shared<std::string>();
  cmd.add_option("FILE", *file, "the trace (or a rosbag2 bag)")->required();
  return [file](std::ostream& out, std::ostream& err) { return trace_info(*file, out, err); };
}

cli::Action setup_dump(CLI::App& cmd) {
  auto a = std::make_shared<DumpArgs>();
  cmd.add_option("FILE", a->file, "the trace (or a rosbag2 bag)")->required();
  cmd.add_option("--limit", a->limit, "N: stop after N records (0: all)")->capture_default_str();
  cmd.add_option("--beams", a->beams, "K: the first K ranges of each scan (0: all)")->capture_default_str();
  return [a](std::ostream& out, std::ostream& err) { return trace_dump(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("trace", "import", "convert a CARMEN log (.log or .log.gz) to a tripodal trace", kImportDescription,
                     kExitCodes, &setup_import);
TRIPODAL_CLI_COMMAND("trace", "convert", "convert a rosbag2 bag (MCAP or db3) to a trace, or a trace to MCAP",
                     kConvertDescription, kExitCodes, &setup_convert);
TRIPODAL_CLI_COMMAND("trace", "info", "duration, channels and record counts of a trace", kInfoDescription, kExitCodes,
                     &setup_info);
TRIPODAL_CLI_COMMAND("trace", "dump", "print a trace's records, one per line", kDumpDescription, kExitCodes, &setup_dump);

}  // namespace tripodal::tool
