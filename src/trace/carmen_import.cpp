#include "tripodal/trace/carmen_import.hpp"

#include <zlib.h>

#include <charconv>
#include <cmath>
#include <cstring>
#include <numbers>
#include <optional>
#include <string_view>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/geometry.hpp"

namespace tripodal::trace {

namespace {

struct Token {
  std::string_view text;
  int column = 0;  // 1-based
};

// A line longer than kCarmenMaxLineBytes is kept only up to one byte past the limit (the importer
// reports it), so a file without newlines cannot grow the line buffer without bound.
void append_capped(std::string& line, std::string_view piece) {
  const std::size_t room = kCarmenMaxLineBytes + 1 - std::min(line.size(), kCarmenMaxLineBytes + 1);
  line.append(piece.substr(0, std::min(room, piece.size())));
}

// Reads lines from a file through zlib, which also reads uncompressed files unchanged.
class GzLines {
 public:
  explicit GzLines(const std::filesystem::path& path) : name_(path.string()) {
    file_ = gzopen(name_.c_str(), "rb");
    if (file_ == nullptr) throw TraceIoError(name_ + ": cannot open the log for reading");
    gzbuffer(file_, 1 << 16);
    chunk_.resize(1 << 16);
  }
  ~GzLines() {
    if (file_ != nullptr) gzclose(file_);
  }
  GzLines(const GzLines&) = delete;
  GzLines& operator=(const GzLines&) = delete;

  bool getline(std::string& line) {
    line.clear();
    for (;;) {
      if (pos_ == len_) {
        if (eof_) return !line.empty();
        const int n = gzread(file_, chunk_.data(), static_cast<unsigned>(chunk_.size()));
        if (n < 0) {
          int code = 0;
          const char* msg = gzerror(file_, &code);
          throw TraceIoError(name_ + ": cannot read the log: " + (msg != nullptr ? msg : "zlib error"));
        }
        pos_ = 0;
        len_ = static_cast<std::size_t>(n);
        if (n == 0) {
          eof_ = true;
          // A truncated gzip stream reads as a short file; zlib reports it only through gzerror.
          int code = 0;
          const char* msg = gzerror(file_, &code);
          if (code != Z_OK && code != Z_STREAM_END) {
            throw TraceIoError(name_ + ": cannot read the log: " + (msg != nullptr ? msg : "zlib error"));
          }
          continue;
        }
      }
      const char* begin = chunk_.data() + pos_;
      const auto* nl = static_cast<const char*>(std::memchr(begin, '\n', len_ - pos_));
      const std::size_t piece = nl == nullptr ? len_ - pos_ : static_cast<std::size_t>(nl - begin);
      append_capped(line, std::string_view(begin, piece));
      if (nl == nullptr) {
        pos_ = len_;
        continue;
      }
      pos_ += piece + 1;
      return true;
    }
  }

 private:
  std::string name_;
  gzFile file_ = nullptr;
  std::vector<char> chunk_;
  std::size_t pos_ = 0;
  std::size_t len_ = 0;
  bool eof_ = false;
};

void split(std::string_view line, std::vector<Token>& tokens) {
  tokens.clear();
  std::size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const std::size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) tokens.push_back(Token{line.substr(start, i - start), static_cast<int>(start) + 1});
  }
}

// Thrown by the line parsers; caught per line and turned into a located diagnostic.
struct LineError {
  int column;
  std::string what;
};

class Fields {
 public:
  Fields(const std::vector<Token>& tokens, std::string_view type) : tokens_(tokens), type_(type) {}

  double number(const char* field) {
    const Token& t = take(field);
    double v = 0;
    const auto [end, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), v);
    if (ec != std::errc() || end != t.text.data() + t.text.size() || !std::isfinite(v)) {
      throw LineError{t.column, std::string(type_) + " " + field + " '" + std::string(t.text) + "' is not a finite number"};
    }
    return v;
  }

  std::size_t count(const char* field, std::size_t max) {
    const Token& t = take(field);
    std::size_t v = 0;
    const auto [end, ec] = std::from_chars(t.text.data(), t.text.data() + t.text.size(), v);
    if (ec != std::errc() || end != t.text.data() + t.text.size()) {
      throw LineError{t.column, std::string(type_) + " " + field + " '" + std::string(t.text) + "' is not a count"};
    }
    if (v > max) {
      throw LineError{t.column, std::string(type_) + " " + field + " " + std::to_string(v) + " exceeds the " +
                                    std::to_string(max) + " fields left on the line"};
    }
    return v;
  }

  // The trailer every message ends with: timestamp [hostname [logger_timestamp]].
  Time stamp() {
    const int column = tokens_[std::min(next_, tokens_.size() - 1)].column;
    const double seconds = number("timestamp");
    if (std::fabs(seconds) > kMaxSeconds) {
      throw LineError{column, std::string(type_) + " timestamp " + std::to_string(seconds) + " s is out of range"};
    }
    const std::size_t rest = tokens_.size() - next_;
    if (rest > 2) {
      throw LineError{tokens_[next_ + 2].column, std::string(type_) + " has " + std::to_string(rest - 2) +
                                                     " unexpected fields after logger_timestamp"};
    }
    return time_from_seconds(seconds);
  }

  [[nodiscard]] std::size_t left() const noexcept { return tokens_.size() - next_; }

 private:
  const Token& take(const char* field) {
    if (next_ >= tokens_.size()) {
      const Token& last = tokens_.back();
      throw LineError{last.column + static_cast<int>(last.text.size()),
                      std::string(type_) + " line ends before the " + field + " field"};
    }
    return tokens_[next_++];
  }

  const std::vector<Token>& tokens_;
  std::string_view type_;
  std::size_t next_ = 1;
};

class Importer {
 public:
  Importer(std::string name, TraceWriter& out, const CarmenImportOptions& options)
      : name_(std::move(name)), out_(out), options_(options) {}

  template <typename Lines>
  CarmenImportReport run(Lines& lines) {
    std::string line;
    std::vector<Token> tokens;
    int line_number = 0;
    while (lines.getline(line)) {
      ++line_number;
      ++report_.lines;
      if (line.size() > kCarmenMaxLineBytes) {
        diagnostics_.error(SourceLocation{name_, line_number, static_cast<int>(kCarmenMaxLineBytes) + 1},
                           "line longer than " + std::to_string(kCarmenMaxLineBytes) +
                               " bytes (a CARMEN message is one line; is this a CARMEN log?)");
        continue;
      }
      split(line, tokens);
      if (tokens.empty()) {
        ++report_.blank_lines;
        continue;
      }
      if (tokens[0].text[0] == '#') {
        ++report_.comments;
        continue;
      }
      try {
        parse(tokens);
      } catch (const LineError& e) {
        diagnostics_.error(SourceLocation{name_, line_number, e.column}, e.what);
      }
    }
    if (diagnostics_.has_errors()) throw ConfigError(diagnostics_);
    classify_odometry();
    return report_;
  }

 private:
  void parse(const std::vector<Token>& tokens) {
    const std::string_view type = tokens[0].text;
    if (type == "FLASER" || type == "RLASER") {
      laser_old(tokens, type, type == "FLASER" ? options_.laser_channel : options_.rear_laser_channel);
    } else if (type == "ROBOTLASER1" || type == "ROBOTLASER2") {
      robot_laser(tokens, type, type == "ROBOTLASER1" ? options_.laser_channel : options_.rear_laser_channel);
    } else if (type == "ODOM") {
      odom(tokens);
    } else if (type == "PARAM") {
      if (tokens.size() < 3) throw LineError{tokens[0].column, "PARAM needs a name and a value"};
      report_.params.emplace_back(std::string(tokens[1].text), std::string(tokens[2].text));
    } else {
      ++report_.skipped[std::string(type)];
    }
  }

  // FLASER num_readings r1..rn x y theta odom_x odom_y odom_theta timestamp hostname logger_timestamp
  void laser_old(const std::vector<Token>& tokens, std::string_view type, const std::string& channel) {
    Fields f(tokens, type);
    const std::size_t n = f.count("num_readings", tokens.size() - 2);
    LaserScan& scan = scan_;
    scan.ranges_m.resize(n);
    for (auto& r : scan.ranges_m) r = static_cast<float>(f.number("range"));
    scan.intensities.clear();
    Pose2D laser_pose;
    laser_pose.x_m = f.number("x");
    laser_pose.y_m = f.number("y");
    laser_pose.theta_rad = f.number("theta");
    f.number("odom_x");
    f.number("odom_y");
    f.number("odom_theta");
    const Time stamp = clamp(f.stamp());
    scan.stamp = stamp;
    scan.angle_min_rad = -std::numbers::pi / 2.0;
    scan.angle_increment_rad = carmen_flaser_angle_increment(n);
    scan.angle_max_rad = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(n > 0 ? n - 1 : 0);
    scan.time_increment_s = 0.0;
    scan.scan_time_s = 0.0;
    scan.range_min_m = 0.0;
    scan.range_max_m = kCarmenFlaserMaxRangeM;
    emit_scan(channel, laser_pose, laser_pose);
  }

  // ROBOTLASER1 laser_type start_angle field_of_view angular_resolution maximum_range accuracy
  // remission_mode num_readings ranges.. num_remissions remissions.. laser_pose_x y theta
  // robot_pose_x y theta laser_tv laser_rv forward_safety_dist side_safety_dist turn_axis
  // timestamp hostname logger_timestamp
  void robot_laser(const std::vector<Token>& tokens, std::string_view type, const std::string& channel) {
    Fields f(tokens, type);
    LaserScan& scan = scan_;
    f.number("laser_type");
    scan.angle_min_rad = f.number("start_angle");
    f.number("field_of_view");
    scan.angle_increment_rad = f.number("angular_resolution");
    scan.range_max_m = f.number("maximum_range");
    scan.range_min_m = 0.0;
    f.number("accuracy");
    f.number("remission_mode");
    const std::size_t n = f.count("num_readings", f.left());
    scan.ranges_m.resize(n);
    for (auto& r : scan.ranges_m) r = static_cast<float>(f.number("range"));
    const std::size_t m = f.count("num_remissions", f.left());
    scan.intensities.resize(m);
    for (auto& r : scan.intensities) r = static_cast<float>(f.number("remission"));
    if (m != 0 && m != n) {
      throw LineError{tokens[0].column, std::string(type) + " has " + std::to_string(m) + " remissions for " +
                                            std::to_string(n) + " ranges"};
    }
    Pose2D laser_pose;
    laser_pose.x_m = f.number("laser_pose_x");
    laser_pose.y_m = f.number("laser_pose_y");
    laser_pose.theta_rad = f.number("laser_pose_theta");
    Pose2D robot_pose;
    robot_pose.x_m = f.number("robot_pose_x");
    robot_pose.y_m = f.number("robot_pose_y");
    robot_pose.theta_rad = f.number("robot_pose_theta");
    for (const char* field : {"laser_tv", "laser_rv", "forward_safety_dist", "side_safety_dist", "turn_axis"}) {
      f.number(field);
    }
    scan.stamp = clamp(f.stamp());
    scan.angle_max_rad = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(n > 0 ? n - 1 : 0);
    scan.time_increment_s = 0.0;
    scan.scan_time_s = 0.0;
    emit_scan(channel, laser_pose, robot_pose);
  }

  // ODOM x y theta tv rv accel timestamp hostname logger_timestamp
  void odom(const std::vector<Token>& tokens) {
    Fields f(tokens, "ODOM");
    OdometryReading r;
    r.pose.x_m = f.number("x");
    r.pose.y_m = f.number("y");
    r.pose.theta_rad = f.number("theta");
    r.twist.vx_m_s = f.number("tv");
    r.twist.wz_rad_s = f.number("rv");
    f.number("accel");
    const Time stamp = f.stamp();
    // The first ODOM after a scan that repeats the scan's pose is the log's re-anchoring, not a
    // reading (its stamp is 0 in the corrected logs): dropped, and the increments that follow
    // are chained onto the odometry the robot had at the scan.
    const std::optional<Pose2D> echoed = echo_of_;
    echo_of_.reset();
    if (echoed && (same_pose(r.pose, *echoed) || same_pose(r.pose, echo_of_robot_))) {
      ++report_.odometry_echoes;
      if (options_.recover_anchored_odometry) {
        anchor_log_ = r.pose;
        anchor_odom_ = written_odom_.value_or(r.pose);
        return;
      }
    }
    if (anchor_log_) r.pose = compose(anchor_odom_, compose(inverse(*anchor_log_), r.pose));
    r.stamp = clamp(stamp);
    written_odom_ = r.pose;
    out_.write(channel(options_.odometry_channel, ChannelKind::kOdometry, odom_id_), r);
    ++report_.odometry_readings;
  }

  // Digits as printed: an echo repeats the scan's pose to the last digit.
  static bool same_pose(const Pose2D& a, const Pose2D& b) noexcept {
    constexpr double kTol = 1e-6;
    return std::abs(a.x_m - b.x_m) <= kTol && std::abs(a.y_m - b.y_m) <= kTol &&
           std::abs(a.theta_rad - b.theta_rad) <= kTol;
  }

  // Odometry that stays exactly still while the laser poses move is no odometry (orebro's ODOMs
  // repeat the previous scan's pose).
  void watch_odometry(const Pose2D& laser_pose) {
    if (last_scan_pose_) {
      const Pose2D moved = compose(inverse(*last_scan_pose_), laser_pose);
      if (std::hypot(moved.x_m, moved.y_m) >= 0.05 || std::abs(wrap_angle(moved.theta_rad)) >= 0.05) {
        ++report_.moving_scans;
        const bool still = !written_odom_ || (odom_at_last_scan_ && same_pose(*written_odom_, *odom_at_last_scan_));
        if (still) ++report_.still_odometry_scans;
      }
    }
    last_scan_pose_ = laser_pose;
    odom_at_last_scan_ = written_odom_;
  }

  void classify_odometry() {
    CarmenImportReport& r = report_;
    const std::uint64_t front = front_scans_;
    if (r.odometry_readings == 0 || (r.moving_scans >= 3 && 2 * r.still_odometry_scans > r.moving_scans)) {
      r.odometry = CarmenOdometry::kNone;
    } else if (r.odometry_echoes > 0 && 2 * r.odometry_echoes >= front) {
      r.odometry = options_.recover_anchored_odometry ? CarmenOdometry::kRecovered : CarmenOdometry::kAnchored;
    } else {
      r.odometry = CarmenOdometry::kRaw;
    }
  }

  void emit_scan(const std::string& name, const Pose2D& laser_pose, const Pose2D& robot_pose) {
    const bool front = name == options_.laser_channel;
    if (front) {
      ++front_scans_;
      watch_odometry(laser_pose);
      // FLASER's echo is its laser pose; a ROBOTLASER1 log may echo the robot's pose instead
      echo_of_ = laser_pose;
      echo_of_robot_ = robot_pose;
    }
    auto& id = front ? front_id_ : rear_id_;
    out_.write(channel(name, ChannelKind::kLaser, id), scan_);
    ++report_.laser_scans;
    if (!options_.laser_pose_channel.empty()) {
      OdometryReading pose;
      pose.stamp = scan_.stamp;
      pose.pose = laser_pose;
      out_.write(channel(options_.laser_pose_channel, ChannelKind::kOdometry, pose_id_), pose);
      ++report_.laser_poses;
    }
  }

  ChannelId channel(const std::string& name, ChannelKind kind, std::optional<ChannelId>& id) {
    if (!id) id = out_.add_channel(name, kind);
    return *id;
  }

  // Keeps the trace in time order: a message stamped before its predecessor takes its predecessor's stamp.
  Time clamp(Time stamp) {
    if (!started_) {
      started_ = true;
      report_.first_stamp = stamp;
      last_ = stamp;
    } else if (stamp < last_) {
      ++report_.backwards_steps;
      report_.largest_backwards_step = std::max(report_.largest_backwards_step, last_ - stamp);
      stamp = last_;
    }
    last_ = stamp;
    report_.last_stamp = stamp;
    return stamp;
  }

  std::string name_;
  TraceWriter& out_;
  const CarmenImportOptions& options_;
  CarmenImportReport report_;
  Diagnostics diagnostics_;
  LaserScan scan_;  // reused: no allocation per scan once the largest scan was seen
  std::optional<ChannelId> front_id_, rear_id_, odom_id_, pose_id_;
  // re-anchored odometry: the pose the next ODOM may echo, the last echo and the odometry then
  std::optional<Pose2D> echo_of_;
  Pose2D echo_of_robot_;
  std::optional<Pose2D> anchor_log_;
  Pose2D anchor_odom_;
  std::optional<Pose2D> written_odom_;
  std::optional<Pose2D> last_scan_pose_, odom_at_last_scan_;
  std::uint64_t front_scans_ = 0;
  bool started_ = false;
  Time last_{};
};

class StreamLines {
 public:
  explicit StreamLines(std::istream& in) : in_(in) {}
  bool getline(std::string& line) {
    line.clear();
    std::streambuf* buf = in_.rdbuf();
    bool any = false;
    for (int c = buf->sbumpc(); c != std::char_traits<char>::eof(); c = buf->sbumpc()) {
      any = true;
      if (c == '\n') return true;
      if (line.size() <= kCarmenMaxLineBytes) line.push_back(static_cast<char>(c));
    }
    in_.setstate(std::ios::eofbit);
    return any;
  }

 private:
  std::istream& in_;
};

}  // namespace

std::string CarmenImportReport::odometry_note() const {
  const std::string echoes = std::to_string(odometry_echoes);
  switch (odometry) {
    case CarmenOdometry::kNone:
      if (odometry_readings == 0) return "no odometry in this log (no ODOM message)";
      return "no odometry in this log: its ODOMs repeat the previous pose (" + std::to_string(still_odometry_scans) +
             " of " + std::to_string(moving_scans) + " moving scans without odometry motion)";
    case CarmenOdometry::kRaw: return "odometry as logged (no re-anchoring found)";
    case CarmenOdometry::kRecovered:
      return "re-anchored odometry recovered: " + echoes +
             " ODOMs echoing the corrected scan pose dropped, the wheel increments chained again";
    case CarmenOdometry::kAnchored:
      return "odometry re-anchored to the corrected pose at every scan (" + echoes +
             " echoes): it cannot drift, it is not raw odometry";
  }
  return {};
}

double carmen_flaser_angle_increment(std::size_t beams) noexcept {
  constexpr double kPi = std::numbers::pi;
  if (beams == 180 || beams == 181) return kPi / 180.0;
  if (beams == 360 || beams == 361) return kPi / 360.0;
  if (beams == 400 || beams == 401) return kPi / 720.0;
  if (beams < 2) return 0.0;
  return kPi / static_cast<double>(beams - 1);
}

CarmenImportReport import_carmen_log(const std::filesystem::path& path, TraceWriter& out,
                                     const CarmenImportOptions& options) {
  GzLines lines(path);
  Importer importer(path.string(), out, options);
  return importer.run(lines);
}

CarmenImportReport import_carmen_log(std::istream& in, const std::string& name, TraceWriter& out,
                                     const CarmenImportOptions& options) {
  StreamLines lines(in);
  Importer importer(name, out, options);
  return importer.run(lines);
}

}  // namespace tripodal::trace
