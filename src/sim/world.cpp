#include "tripodal/sim/world.hpp"

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <set>
#include <sstream>

#include "tripodal/sim/ray_caster.hpp"
#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal::sim {

std::string_view to_string(SensorKind kind) noexcept {
  switch (kind) {
    case SensorKind::laser: return "laser";
    case SensorKind::odometry: return "odometry";
    case SensorKind::gyro: return "gyro";
    case SensorKind::bumpers: return "bumpers";
    case SensorKind::cliff: return "cliff";
    case SensorKind::battery: return "battery";
  }
  return "?";
}

namespace {

constexpr double kDegToRad = std::numbers::pi / 180.0;

// Reads one world file's YAML into typed values, collecting every problem with its location:
// the shared yaml::Reader plus the shapes and windows of world files.
class Reader {
 public:
  explicit Reader(std::string file) : r_(std::move(file), d_) {}

  SourceLocation at(const YAML::Node& n) const { return r_.at(n); }
  void error(const YAML::Node& n, const std::string& msg) { r_.error(n, msg); }
  Diagnostics& diagnostics() { return d_; }

  static std::string kind(const YAML::Node& n) { return yaml::kind(n); }

  /// Reports keys of map `n` not in `allowed`; false when n is not a map.
  bool check_map(const YAML::Node& n, const std::string& what, yaml::KeyList allowed) {
    return r_.expect_keys(n, allowed, what);
  }

  std::optional<double> number(const YAML::Node& n, const std::string& what) { return r_.number(n, what); }
  /// A number >= lo (or > lo when strict) into `out` if the key is present.
  void number_at_least(const YAML::Node& map, const char* key, double& out, double lo, bool strict,
                       const std::string& where_in) {
    const YAML::Node n = map[key];
    if (!n) return;
    const std::string what = where_in + "." + key;
    if (auto v = number(n, what)) {
      if (strict ? *v <= lo : *v < lo) error(n, fmt::format("{}: expected a number {} {}, got {}", what, strict ? ">" : ">=", lo, *v));
      else out = *v;
    }
  }
  void boolean(const YAML::Node& map, const char* key, bool& out, const std::string& where_in) {
    if (const YAML::Node n = map[key]) out = r_.boolean(n, where_in + "." + key).value_or(out);
  }
  void text(const YAML::Node& map, const char* key, std::string& out, const std::string& where_in) {
    if (const YAML::Node n = map[key]) out = r_.text(n, where_in + "." + key, true).value_or(out);
  }
  /// A list of `count` numbers (optional_extra more allowed), or an error.
  std::optional<std::vector<double>> numbers(const YAML::Node& n, const std::string& what, std::size_t count,
                                             std::size_t optional_extra, const std::string& expected) {
    return r_.numbers(n, what, count, count + optional_extra, expected);
  }
  std::optional<Pose2D> pose(const YAML::Node& n, const std::string& what) {
    auto v = numbers(n, what, 2, 1, "[x, y] or [x, y, theta] (metres, radians)");
    if (!v) return std::nullopt;
    return Pose2D{(*v)[0], (*v)[1], v->size() > 2 ? (*v)[2] : 0.0};
  }
  /// `rectangle: [x_min, y_min, x_max, y_max]` or `polygon: [[x, y], ...]` of an entry.
  std::optional<std::vector<navi::Point2D>> shape(const YAML::Node& entry, const std::string& what) {
    const YAML::Node rect = entry["rectangle"];
    const YAML::Node poly = entry["polygon"];
    if (rect && poly) {
      error(entry, what + " has both rectangle and polygon, expected one");
      return std::nullopt;
    }
    if (rect) {
      auto v = numbers(rect, what + ".rectangle", 4, 0, "[x_min, y_min, x_max, y_max]");
      if (!v) return std::nullopt;
      const auto& r = *v;
      if (r[2] <= r[0] || r[3] <= r[1]) {
        error(rect, what + ".rectangle is empty: expected x_min < x_max and y_min < y_max");
        return std::nullopt;
      }
      return std::vector<navi::Point2D>{{r[0], r[1]}, {r[2], r[1]}, {r[2], r[3]}, {r[0], r[3]}};
    }
    if (poly) {
      if (!poly.IsSequence() || poly.size() < 3) {
        error(poly, what + ".polygon must be a list of at least 3 [x, y] corners, got " + kind(poly));
        return std::nullopt;
      }
      std::vector<navi::Point2D> out;
      bool ok = true;
      for (const auto& c : poly) {
        auto v = numbers(c, what + ".polygon corner", 2, 0, "[x, y]");
        ok = ok && v.has_value();
        if (v) out.push_back({(*v)[0], (*v)[1]});
      }
      if (!ok) return std::nullopt;
      return out;
    }
    return std::nullopt;  // the caller reports what is missing
  }
  /// A time window [start_s, end_s] in seconds.
  std::optional<std::pair<Time, Time>> window(const YAML::Node& start, const YAML::Node& end,
                                              const YAML::Node& entry, const std::string& what) {
    if (!start || !end) {
      error(entry, what + " needs start_s and end_s (seconds, 0 <= start_s < end_s)");
      return std::nullopt;
    }
    auto a = number(start, what + ".start_s");
    auto b = number(end, what + ".end_s");
    if (!a || !b) return std::nullopt;
    if (*a < 0.0 || *b <= *a) {
      error(entry, what + " is not a window: expected 0 <= start_s < end_s, got " + start.Scalar() + " and " +
                       end.Scalar());
      return std::nullopt;
    }
    return std::make_pair(time_from_seconds(*a), time_from_seconds(*b));
  }

 private:
  Diagnostics d_;
  yaml::Reader r_;
};

// `docks: [{name, pose: [x, y, theta] | node: NAME, contact_radius_m, heading_tolerance_deg, powered}]`.
void read_docks(Reader& r, const YAML::Node& list, World& w) {
  if (!list.IsSequence()) {
    r.error(list, "docks must be a list of {name, pose | node, contact_radius_m, heading_tolerance_deg, powered}, got " +
                      Reader::kind(list));
    return;
  }
  std::set<std::string> names;
  for (const auto& item : list) {
    if (!r.check_map(item, "a docks entry", {"name", "pose", "node", "contact_radius_m", "heading_tolerance_deg", "powered"}))
      continue;
    Dock k;
    k.where = r.at(item);
    r.text(item, "name", k.name, "docks entry");
    const YAML::Node pose = item["pose"];
    const YAML::Node node = item["node"];
    if ((pose ? 1 : 0) + (node ? 1 : 0) != 1) {
      r.error(item,
              "a docks entry needs exactly one of pose: [x, y, theta] (the robot docked, map frame) or node: "
              "NAME (a node of "
              "the regions file)");
      continue;
    }
    if (pose) {
      auto p = r.pose(pose, "dock pose");
      if (!p) continue;
      k.pose = *p;
    } else {
      const navi::MapNode* n = node.IsScalar() ? w.regions.node(node.Scalar()) : nullptr;
      if (n == nullptr) {
        r.error(node,
                "unknown node " + Reader::kind(node) + (w.regions_file.empty() ? " (the world names no regions file)" : ""));
        continue;
      }
      k.pose = n->pose;
      if (k.name.empty()) k.name = n->name;
    }
    if (k.name.empty()) k.name = "dock " + std::to_string(w.docks.size() + 1);
    if (!names.insert(k.name).second) r.error(item["name"] ? item["name"] : item, "duplicate dock name '" + k.name + "'");
    r.number_at_least(item, "contact_radius_m", k.contact_radius_m, 0.0, true, "dock '" + k.name + "'");
    double tolerance_deg = k.heading_tolerance_rad / kDegToRad;
    r.number_at_least(item, "heading_tolerance_deg", tolerance_deg, 0.0, false, "dock '" + k.name + "'");
    k.heading_tolerance_rad = tolerance_deg * kDegToRad;
    r.boolean(item, "powered", k.powered, "dock '" + k.name + "'");
    w.docks.push_back(std::move(k));
  }
}

void read_laser(Reader& r, const YAML::Node& n, LaserConfig& c) {
  const std::string w = "robot.laser";
  if (!r.check_map(n, w, {"preset", "enabled", "name", "angle_min_deg", "angle_max_deg", "beams", "range_min_m",
                          "range_max_m", "rate_hz", "noise_stddev_m", "mount"})) {
    return;
  }
  if (const YAML::Node p = n["preset"]) {
    const std::string s = p.IsScalar() ? p.Scalar() : std::string();
    if (s == "rplidar_a1") {
      c = LaserConfig::rplidar_a1();
    } else if (s == "sick_180") {
      c = LaserConfig::sick_180();
    } else {
      r.error(p, "unknown robot.laser.preset " + Reader::kind(p) + ", expected rplidar_a1 or sick_180");
    }
  }
  r.boolean(n, "enabled", c.enabled, w);
  r.text(n, "name", c.name, w);
  double min_deg = c.angle_min_rad / kDegToRad, max_deg = c.angle_max_rad / kDegToRad;
  const YAML::Node amin = n["angle_min_deg"], amax = n["angle_max_deg"];
  if (amin) {
    if (auto v = r.number(amin, w + ".angle_min_deg")) min_deg = *v;
  }
  if (amax) {
    if (auto v = r.number(amax, w + ".angle_max_deg")) max_deg = *v;
  }
  if (max_deg <= min_deg || max_deg - min_deg > 360.0 + 1e-9) {
    r.error(amax ? amax : (amin ? amin : n), w + ": expected angle_min_deg < angle_max_deg spanning at most 360 degrees");
  } else {
    c.angle_min_rad = min_deg * kDegToRad;
    c.angle_max_rad = max_deg * kDegToRad;
  }
  if (const YAML::Node b = n["beams"]) {
    if (auto v = r.number(b, w + ".beams")) {
      if (*v < 1.0 || *v > 100000.0 || std::floor(*v) != *v) {
        r.error(b, w + ".beams must be a whole number from 1 to 100000, got " + b.Scalar());
      } else {
        c.beams = static_cast<std::uint32_t>(*v);
      }
    }
  }
  r.number_at_least(n, "range_min_m", c.range_min_m, 0.0, false, w);
  r.number_at_least(n, "range_max_m", c.range_max_m, 0.0, true, w);
  if (c.range_max_m <= c.range_min_m) {
    r.error(n["range_max_m"] ? n["range_max_m"] : n, w + ": expected range_min_m < range_max_m");
  }
  r.number_at_least(n, "rate_hz", c.rate_hz, 0.0, true, w);
  r.number_at_least(n, "noise_stddev_m", c.noise_stddev_m, 0.0, false, w);
  if (const YAML::Node m = n["mount"]) {
    if (auto p = r.pose(m, w + ".mount")) c.mount = *p;
  }
}

void read_joints(Reader& r, const YAML::Node& n, std::vector<JointConfig>& out);
void read_buttons(Reader& r, const YAML::Node& n, std::vector<ButtonConfig>& out);

void read_odometry(Reader& r, const YAML::Node& o, SimRobotConfig& rc) {
  if (!r.check_map(o, "robot.odometry", {"name", "noise_ratio", "scale_error_stddev", "rate_hz"})) return;
  r.text(o, "name", rc.odometry.name, "robot.odometry");
  r.number_at_least(o, "noise_ratio", rc.odometry.noise_ratio, 0.0, false, "robot.odometry");
  r.number_at_least(o, "scale_error_stddev", rc.odometry.scale_error_stddev, 0.0, false, "robot.odometry");
  r.number_at_least(o, "rate_hz", rc.odometry.rate_hz, 0.0, true, "robot.odometry");
}

void read_gyro(Reader& r, const YAML::Node& g, SimRobotConfig& rc) {
  if (!r.check_map(g, "robot.gyro", {"name", "enabled", "noise_stddev_rad_s", "bias_rad_s", "rate_hz"})) return;
  r.text(g, "name", rc.gyro.name, "robot.gyro");
  r.boolean(g, "enabled", rc.gyro.enabled, "robot.gyro");
  r.number_at_least(g, "noise_stddev_rad_s", rc.gyro.noise_stddev_rad_s, 0.0, false, "robot.gyro");
  if (const YAML::Node b = g["bias_rad_s"]) {
    if (auto v = r.number(b, "robot.gyro.bias_rad_s")) rc.gyro.bias_rad_s = *v;
  }
  r.number_at_least(g, "rate_hz", rc.gyro.rate_hz, 0.0, true, "robot.gyro");
}

void read_bumpers(Reader& r, const YAML::Node& b, SimRobotConfig& rc) {
  if (!r.check_map(b, "robot.bumpers", {"name", "enabled", "sectors", "contact_margin_m", "rate_hz"})) return;
  r.text(b, "name", rc.bumpers.name, "robot.bumpers");
  r.boolean(b, "enabled", rc.bumpers.enabled, "robot.bumpers");
  if (const YAML::Node s = b["sectors"]) {
    if (auto v = r.number(s, "robot.bumpers.sectors")) {
      if (*v < 1.0 || *v > 32.0 || std::floor(*v) != *v) {
        r.error(s, "robot.bumpers.sectors must be a whole number from 1 to 32, got " + s.Scalar());
      } else {
        rc.bumpers.sectors = static_cast<std::uint32_t>(*v);
      }
    }
  }
  r.number_at_least(b, "contact_margin_m", rc.bumpers.contact_margin_m, 0.0, false, "robot.bumpers");
  r.number_at_least(b, "rate_hz", rc.bumpers.rate_hz, 0.0, true, "robot.bumpers");
}

void read_cliff(Reader& r, const YAML::Node& c, SimRobotConfig& rc) {
  if (!r.check_map(c, "robot.cliff", {"name", "enabled", "positions", "rate_hz"})) return;
  r.text(c, "name", rc.cliff.name, "robot.cliff");
  r.boolean(c, "enabled", rc.cliff.enabled, "robot.cliff");
  r.number_at_least(c, "rate_hz", rc.cliff.rate_hz, 0.0, true, "robot.cliff");
  const YAML::Node p = c["positions"];
  if (!p) return;
  if (!p.IsSequence()) {
    r.error(p, "robot.cliff.positions must be a list of [x, y] (base frame, metres), got " + Reader::kind(p));
    return;
  }
  rc.cliff.positions.clear();
  for (const auto& item : p) {
    if (auto v = r.numbers(item, "robot.cliff.positions", 2, 0, "[x, y] (base frame, metres)")) {
      rc.cliff.positions.push_back({(*v)[0], (*v)[1]});
    }
  }
}

void read_battery(Reader& r, const YAML::Node& b, SimRobotConfig& rc) {
  const std::string w = "robot.battery";
  if (!r.check_map(b, w,
                   {"name", "enabled", "initial", "capacity_ah", "voltage_empty_v", "voltage_full_v", "drain_per_s",
                    "drain_per_m", "charge_per_s", "rate_hz"})) {
    return;
  }
  BatteryConfig& bc = rc.battery;
  r.text(b, "name", bc.name, w);
  r.boolean(b, "enabled", bc.enabled, w);
  r.number_at_least(b, "initial", bc.initial, 0.0, false, w);
  if (bc.initial > 1.0) r.error(b["initial"], w + ".initial is a state of charge: expected 0..1, got " + b["initial"].Scalar());
  r.number_at_least(b, "capacity_ah", bc.capacity_ah, 0.0, true, w);
  r.number_at_least(b, "voltage_empty_v", bc.voltage_empty_v, 0.0, false, w);
  r.number_at_least(b, "voltage_full_v", bc.voltage_full_v, 0.0, true, w);
  if (bc.voltage_full_v <= bc.voltage_empty_v) {
    r.error(b["voltage_full_v"] ? b["voltage_full_v"] : b, w + ": expected voltage_empty_v < voltage_full_v");
  }
  r.number_at_least(b, "drain_per_s", bc.drain_per_s, 0.0, false, w);
  r.number_at_least(b, "drain_per_m", bc.drain_per_m, 0.0, false, w);
  r.number_at_least(b, "charge_per_s", bc.charge_per_s, 0.0, false, w);
  r.number_at_least(b, "rate_hz", bc.rate_hz, 0.0, true, w);
}

void read_robot(Reader& r, const YAML::Node& n, SimRobotConfig& rc) {
  if (!r.check_map(n, "robot", {"radius_m", "max_substep_s", "laser", "odometry", "gyro", "bumpers", "cliff", "battery", "joints",
                                "buttons"})) {
    return;
  }
  r.number_at_least(n, "radius_m", rc.radius_m, 0.0, true, "robot");
  if (const YAML::Node s = n["max_substep_s"]) {
    if (auto v = r.number(s, "robot.max_substep_s")) {
      if (*v <= 0.0 || *v > 1.0) {
        r.error(s, "robot.max_substep_s must be in (0, 1] seconds, got " + s.Scalar());
      } else {
        rc.max_substep = from_seconds(*v);
      }
    }
  }
  if (const YAML::Node l = n["laser"]) read_laser(r, l, rc.laser);
  if (const YAML::Node j = n["joints"]) read_joints(r, j, rc.joints);
  if (const YAML::Node b = n["buttons"]) read_buttons(r, b, rc.buttons);
  if (const YAML::Node o = n["odometry"]) read_odometry(r, o, rc);
  if (const YAML::Node g = n["gyro"]) read_gyro(r, g, rc);
  if (const YAML::Node b = n["bumpers"]) read_bumpers(r, b, rc);
  if (const YAML::Node c = n["cliff"]) read_cliff(r, c, rc);
  if (const YAML::Node b = n["battery"]) read_battery(r, b, rc);
}

void read_joints(Reader& r, const YAML::Node& n, std::vector<JointConfig>& out) {
  if (!n.IsSequence()) {
    r.error(n, "robot.joints must be a list of {name, min_deg, max_deg, speed_deg_s, initial_deg, rate_hz}, got " + Reader::kind(n));
    return;
  }
  std::set<std::string> names;
  for (const auto& item : n) {
    const std::string w = "robot.joints entry";
    if (!r.check_map(item, w, {"name", "min_deg", "max_deg", "speed_deg_s", "initial_deg", "rate_hz"})) continue;
    JointConfig j;
    j.where = r.at(item);
    r.text(item, "name", j.name, w);
    if (j.name.empty()) {
      r.error(item, "a robot.joints entry needs name: the resource of its state (e.g. neck)");
      continue;
    }
    if (!names.insert(j.name).second) r.error(item["name"], "duplicate joint name '" + j.name + "'");
    double min_deg = j.min_rad / kDegToRad, max_deg = j.max_rad / kDegToRad, speed = j.speed_rad_s / kDegToRad, init = 0.0;
    const std::string jw = "joint '" + j.name + "'";
    if (const YAML::Node v = item["min_deg"]) min_deg = r.number(v, jw + ".min_deg").value_or(min_deg);
    if (const YAML::Node v = item["max_deg"]) max_deg = r.number(v, jw + ".max_deg").value_or(max_deg);
    r.number_at_least(item, "speed_deg_s", speed, 0.0, true, jw);
    if (const YAML::Node v = item["initial_deg"]) init = r.number(v, jw + ".initial_deg").value_or(init);
    r.number_at_least(item, "rate_hz", j.rate_hz, 0.0, true, jw);
    if (max_deg <= min_deg) {
      r.error(item["max_deg"] ? item["max_deg"] : item, fmt::format("{}: expected min_deg < max_deg, got {} and {}", jw, min_deg, max_deg));
    } else if (init < min_deg || init > max_deg) {
      r.error(item["initial_deg"], fmt::format("{}.initial_deg must be within [{}, {}], got {}", jw, min_deg, max_deg, init));
    }
    j.min_rad = min_deg * kDegToRad;
    j.max_rad = max_deg * kDegToRad;
    j.speed_rad_s = speed * kDegToRad;
    j.initial_rad = init * kDegToRad;
    out.push_back(std::move(j));
  }
}

void read_buttons(Reader& r, const YAML::Node& n, std::vector<ButtonConfig>& out) {
  if (!n.IsSequence()) {
    r.error(n, "robot.buttons must be a list of button names, got " + Reader::kind(n));
    return;
  }
  std::set<std::string> names;
  for (const auto& item : n) {
    if (!item.IsScalar() || item.Scalar().empty()) {
      r.error(item, "a robot.buttons entry must be a button name, got " + Reader::kind(item));
      continue;
    }
    if (!names.insert(item.Scalar()).second) r.error(item, "duplicate button name '" + item.Scalar() + "'");
    out.push_back({item.Scalar(), r.at(item)});
  }
}

// A [lo, hi] range or one number (lo = hi) of a visitor entry.
bool read_range(Reader& r, const YAML::Node& entry, const char* key, double& lo, double& hi, const std::string& what,
                bool positive) {
  const YAML::Node n = entry[key];
  if (!n) return true;
  std::optional<std::vector<double>> v;
  if (n.IsScalar()) {
    if (auto x = r.number(n, what + "." + key)) v = std::vector<double>{*x, *x};
  } else {
    v = r.numbers(n, what + "." + key, 2, 0, "N or [min, max]");
  }
  if (!v) return false;
  const double a = (*v)[0], b = (*v)[1];
  if (a > b || (positive ? a <= 0.0 : a < 0.0)) {
    r.error(n, fmt::format("{}.{}: expected {} min <= max, got [{}, {}]", what, key, positive ? "0 <" : "0 <=", a, b));
    return false;
  }
  lo = a;
  hi = b;
  return true;
}

void read_visitors(Reader& r, const YAML::Node& n, std::vector<Visitor>& out) {
  if (!n.IsSequence()) {
    r.error(n, "visitors must be a list of {name, path, speed_m_s, pause_s, loop, radius_m, give_way_m, start_s}, got " +
                   Reader::kind(n));
    return;
  }
  std::set<std::string> names;
  for (const auto& item : n) {
    if (!r.check_map(item, "a visitors entry",
                     {"name", "path", "speed_m_s", "pause_s", "loop", "radius_m", "give_way_m", "start_s", "follow_robot",
                      "follow_gap_m"})) {
      continue;
    }
    Visitor v;
    v.where = r.at(item);
    r.text(item, "name", v.name, "visitors entry");
    if (v.name.empty()) v.name = "visitor " + std::to_string(out.size() + 1);
    if (!names.insert(v.name).second) r.error(item["name"] ? item["name"] : item, "duplicate visitor name '" + v.name + "'");
    const std::string w = "visitor '" + v.name + "'";
    bool ok = true;
    const YAML::Node path = item["path"];
    if (!path || !path.IsSequence() || path.size() == 0) {
      r.error(path ? path : item, w + " needs path: a list of [x, y] waypoints (map frame, metres), got " +
                                      (path ? Reader::kind(path) : std::string("nothing")));
      ok = false;
    } else {
      for (const auto& c : path) {
        auto p = r.numbers(c, w + ".path waypoint", 2, 0, "[x, y]");
        ok = ok && p.has_value();
        if (p) v.path.push_back({(*p)[0], (*p)[1]});
      }
    }
    ok = read_range(r, item, "speed_m_s", v.speed_min_m_s, v.speed_max_m_s, w, true) && ok;
    ok = read_range(r, item, "pause_s", v.pause_min_s, v.pause_max_s, w, false) && ok;
    r.boolean(item, "loop", v.loop, w);
    r.boolean(item, "follow_robot", v.follow_robot, w);
    r.number_at_least(item, "follow_gap_m", v.follow_gap_m, 0.0, true, w);
    if (v.follow_robot && v.path.size() > 1) {
      r.error(path, w + ": a visitor following the robot starts from one waypoint, got " + std::to_string(v.path.size()));
      ok = false;
    }
    r.number_at_least(item, "radius_m", v.radius_m, 0.0, true, w);
    r.number_at_least(item, "give_way_m", v.give_way_m, 0.0, false, w);
    double start = 0.0;
    r.number_at_least(item, "start_s", start, 0.0, false, w);
    v.start = time_from_seconds(start);
    if (ok) out.push_back(std::move(v));
  }
}

std::optional<SensorKind> sensor_of(const std::string& s) {
  for (SensorKind k : {SensorKind::laser, SensorKind::odometry, SensorKind::gyro, SensorKind::bumpers,
                       SensorKind::cliff, SensorKind::battery}) {
    if (s == to_string(k)) return k;
  }
  return std::nullopt;
}

void read_stuck_cliff(Reader& r, const YAML::Node& s, FaultSchedule& f) {
  if (!s.IsSequence()) {
    r.error(s, "faults.stuck_cliff must be a list of {index, reads: floor | drop}, got " + Reader::kind(s));
    return;
  }
  for (const auto& item : s) {
    if (!r.check_map(item, "a stuck_cliff entry", {"index", "reads"})) continue;
    StuckCliffSensor st;
    st.where = r.at(item);
    const YAML::Node index = item["index"];
    const YAML::Node reads = item["reads"];
    bool ok = true;
    if (!index) {
      r.error(item, "a stuck_cliff entry needs index: the cliff sensor (0-based, robot.cliff.positions order)");
      ok = false;
    } else {
      try {
        st.index = index.as<std::size_t>();
      } catch (const YAML::Exception&) {
        r.error(index, "stuck_cliff.index must be a non-negative whole number, got " + Reader::kind(index));
        ok = false;
      }
    }
    const std::string what = reads && reads.IsScalar() ? reads.Scalar() : std::string();
    if (!reads) {
      r.error(item, "a stuck_cliff entry needs reads: floor or drop");
      ok = false;
    } else if (what != "floor" && what != "drop") {
      r.error(reads, "stuck_cliff.reads must be floor or drop, got " + Reader::kind(reads));
      ok = false;
    }
    st.reads_drop = what == "drop";
    if (ok) f.stuck_cliff.push_back(st);
  }
}

void read_faults(Reader& r, const YAML::Node& n, FaultSchedule& f) {
  if (!r.check_map(n, "faults", {"localization_loss", "dead_sensors", "kidnap", "stuck_cliff"})) return;
  if (const YAML::Node s = n["stuck_cliff"]) read_stuck_cliff(r, s, f);
  if (const YAML::Node k = n["kidnap"]) {
    if (!k.IsSequence()) {
      r.error(k, "faults.kidnap must be a list of {at_s: S, to: [x, y, theta]}, got " + Reader::kind(k));
    } else {
      for (const auto& item : k) {
        if (!r.check_map(item, "a kidnap entry", {"at_s", "to"})) continue;
        if (!item["at_s"] || !item["to"]) {
          r.error(item, "a kidnap entry needs at_s (seconds, >= 0) and to: [x, y, theta] (map frame)");
          continue;
        }
        const auto at = r.number(item["at_s"], "kidnap.at_s");
        const auto to = r.pose(item["to"], "kidnap.to");
        if (at && *at < 0.0) r.error(item["at_s"], "kidnap.at_s must be >= 0");
        if (at && to && *at >= 0.0) f.kidnappings.push_back({time_from_seconds(*at), *to, r.at(item)});
      }
      std::stable_sort(f.kidnappings.begin(), f.kidnappings.end(),
                       [](const Kidnapping& a, const Kidnapping& b) { return a.at < b.at; });
    }
  }
  if (const YAML::Node l = n["localization_loss"]) {
    if (l.IsScalar()) {
      // The navi localizer's own schedule syntax, "10-20; 35.5-40".
      try {
        f.localization_loss = navi::parse_fault_schedule(l.Scalar(), r.at(l));
      } catch (const ConfigError& e) {
        r.diagnostics().append(e.diagnostics());
      }
    } else if (l.IsSequence()) {
      for (const auto& item : l) {
        if (item.IsMap()) {
          if (!r.check_map(item, "a localization_loss window", {"start_s", "end_s"})) continue;
          if (auto w = r.window(item["start_s"], item["end_s"], item, "localization_loss window")) {
            f.localization_loss.push_back({w->first, w->second});
          }
        } else {
          r.error(item, "a localization_loss window must be {start_s: S, end_s: E}, got " + Reader::kind(item));
        }
      }
    } else {
      r.error(l, "faults.localization_loss must be \"START-END; ...\" (seconds) or a list of {start_s, end_s}, got " +
                     Reader::kind(l));
    }
  }
  if (const YAML::Node s = n["dead_sensors"]) {
    if (!s.IsSequence()) {
      r.error(s, "faults.dead_sensors must be a list of {sensor, start_s, end_s}, got " + Reader::kind(s));
      return;
    }
    for (const auto& item : s) {
      if (!r.check_map(item, "a dead_sensors entry", {"sensor", "start_s", "end_s"})) continue;
      SensorOutage o;
      o.where = r.at(item);
      const YAML::Node name = item["sensor"];
      std::optional<SensorKind> k;
      if (!name) {
        r.error(item, "a dead_sensors entry needs sensor: one of laser, odometry, gyro, bumpers, cliff, battery");
      } else if (!(k = sensor_of(name.IsScalar() ? name.Scalar() : std::string()))) {
        r.error(name, "unknown sensor " + Reader::kind(name) + ", expected one of laser, odometry, gyro, bumpers, cliff, battery");
      }
      auto w = r.window(item["start_s"], item["end_s"], item, "dead_sensors entry");
      if (k && w) {
        o.sensor = *k;
        o.start = w->first;
        o.end = w->second;
        f.dead_sensors.push_back(o);
      }
    }
  }
}

// A file the world names, relative to the world file's folder `dir`; an error when it is not there.
std::optional<std::filesystem::path> resolve_file(Reader& r, const YAML::Node& n, const std::string& key,
                                                  const std::filesystem::path& dir) {
  if (!n.IsScalar() || n.Scalar().empty()) {
    r.error(n, key + " must be a file path, got " + Reader::kind(n));
    return std::nullopt;
  }
  std::filesystem::path p = n.Scalar();
  if (p.is_relative()) p = dir / p;
  std::error_code ec;
  if (!std::filesystem::is_regular_file(p, ec)) {
    r.error(n, key + " file '" + n.Scalar() + "' not found (looked for " + p.string() + ")");
    return std::nullopt;
  }
  return p;
}

// The map (required) and the regions file; whether the map loaded.
bool read_map_and_regions(Reader& r, const YAML::Node& root, const std::filesystem::path& dir, World& w) {
  bool have_map = false;
  if (const YAML::Node m = root["map"]) {
    if (auto p = resolve_file(r, m, "map", dir)) {
      try {
        w.grid = navi::load_map(*p).grid;
        w.map_file = *p;
        have_map = true;
      } catch (const ConfigError& e) {
        r.diagnostics().append(e.diagnostics());
      }
    }
  } else {
    r.error(root, "the world file needs map: a ROS map_server YAML file (relative to the world file)");
  }
  if (const YAML::Node g = root["regions"]) {
    if (auto p = resolve_file(r, g, "regions", dir)) {
      try {
        w.regions = navi::load_regions(*p);
        w.regions_file = *p;
      } catch (const ConfigError& e) {
        r.diagnostics().append(e.diagnostics());
      }
    }
  }
  return have_map;
}

void read_drops(Reader& r, const YAML::Node& drops, World& w) {
  if (!drops.IsSequence()) {
    r.error(drops, "drops must be a list of {name, rectangle | polygon | region}, got " + Reader::kind(drops));
    return;
  }
  for (const auto& item : drops) {
    if (!r.check_map(item, "a drops entry", {"name", "rectangle", "polygon", "region", "depth_m"})) continue;
    DropArea a;
    a.where = r.at(item);
    r.text(item, "name", a.name, "drops entry");
    if (const YAML::Node depth = item["depth_m"]) {
      if (auto v = r.number(depth, "drops entry depth_m")) {
        if (!(*v > 0.0)) r.error(depth, "drops entry depth_m must be > 0 (how far the floor falls), got " + depth.Scalar());
        a.depth_m = *v;
      }
    }
    const YAML::Node region = item["region"];
    const int given = (item["rectangle"] ? 1 : 0) + (item["polygon"] ? 1 : 0) + (region ? 1 : 0);
    if (given != 1) {
      r.error(item, "a drops entry needs exactly one of rectangle, polygon or region (a room of the regions file)");
      continue;
    }
    if (region) {
      const navi::Region* room = region.IsScalar() ? w.regions.room(region.Scalar()) : nullptr;
      if (room == nullptr) {
        r.error(region,
                "unknown region " + Reader::kind(region) + (w.regions_file.empty() ? " (the world names no regions file)" : ""));
        continue;
      }
      a.polygon = room->polygon;
      if (a.name.empty()) a.name = room->name;
    } else if (auto s = r.shape(item, "drops entry")) {
      a.polygon = std::move(*s);
    } else {
      continue;
    }
    w.drops.push_back(std::move(a));
  }
}

void read_sonar_only(Reader& r, const YAML::Node& glass, World& w) {
  if (!glass.IsSequence()) {
    r.error(glass,
            "sonar_only must be a list of {name, rectangle | polygon} (glass walls, low tables), got " + Reader::kind(glass));
    return;
  }
  std::set<std::string> names;
  for (const auto& item : glass) {
    if (!r.check_map(item, "a sonar_only entry", {"name", "rectangle", "polygon"})) continue;
    SonarOnlyObstacle o;
    o.where = r.at(item);
    r.text(item, "name", o.name, "sonar_only entry");
    if (o.name.empty()) o.name = "sonar_only " + std::to_string(w.sonar_only.size() + 1);
    if (!names.insert(o.name).second) r.error(item["name"] ? item["name"] : item, "duplicate sonar_only name '" + o.name + "'");
    if (!item["rectangle"] && !item["polygon"]) {
      r.error(item, "sonar_only '" + o.name + "' needs rectangle: [x_min, y_min, x_max, y_max] or polygon: [[x, y], ...]");
      continue;
    }
    if (auto s = r.shape(item, "sonar_only '" + o.name + "'")) {
      o.polygon = std::move(*s);
      w.sonar_only.push_back(std::move(o));
    }
  }
}

void read_obstacles(Reader& r, const YAML::Node& obs, World& w) {
  if (!obs.IsSequence()) {
    r.error(obs, "obstacles must be a list of {name, rectangle | polygon, appear_s, disappear_s}, got " + Reader::kind(obs));
    return;
  }
  std::set<std::string> names;
  for (const auto& item : obs) {
    if (!r.check_map(item, "an obstacles entry", {"name", "rectangle", "polygon", "appear_s", "disappear_s"})) continue;
    DynamicObstacle o;
    o.where = r.at(item);
    r.text(item, "name", o.name, "obstacles entry");
    if (o.name.empty()) o.name = "obstacle " + std::to_string(w.obstacles.size() + 1);
    if (!names.insert(o.name).second) r.error(item["name"] ? item["name"] : item, "duplicate obstacle name '" + o.name + "'");
    auto s = r.shape(item, "obstacle '" + o.name + "'");
    if (!s && !item["rectangle"] && !item["polygon"]) {
      r.error(item, "obstacle '" + o.name + "' needs rectangle: [x_min, y_min, x_max, y_max] or polygon: [[x, y], ...]");
    }
    double appear = 0.0;
    if (const YAML::Node a = item["appear_s"]) {
      if (auto v = r.number(a, "appear_s")) {
        if (*v < 0.0) r.error(a, "appear_s must be >= 0, got " + a.Scalar());
        appear = *v;
      }
    }
    o.appear = time_from_seconds(appear);
    if (const YAML::Node dis = item["disappear_s"]) {
      if (auto v = r.number(dis, "disappear_s")) {
        if (*v <= appear) {
          r.error(dis, "disappear_s must be later than appear_s (" + std::to_string(appear) + "), got " + dis.Scalar());
        }
        o.disappear = time_from_seconds(*v);
      }
    }
    if (s) {
      o.polygon = std::move(*s);
      w.obstacles.push_back(std::move(o));
    }
  }
}

// A visitor walks only where the map is open: its waypoints and the legs between them, sampled
// every 5 cm, must leave its disc clear of the static map.
void check_visitor_paths(Reader& r, const SolidMap& solid, const World& w) {
  for (const Visitor& v : w.visitors) {
    const std::size_t n = v.path.size();
    const std::size_t legs = n == 1 ? 1 : (v.loop ? n : n - 1);
    for (std::size_t i = 0; i < legs; ++i) {
      const navi::Point2D a = v.path[i], b = v.path[(i + 1) % n];
      const double len = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
      const int samples = std::max(1, static_cast<int>(std::ceil(len / 0.05)));
      for (int k = 0; k <= samples; ++k) {
        const double f = static_cast<double>(k) / samples;
        const navi::Point2D p{a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m)};
        if (solid.disc_overlaps(p, v.radius_m)) {
          r.diagnostics().error(v.where, fmt::format("visitor '{}': at ({:.2f}, {:.2f}), on its path from waypoint {} to {}, its "
                                                     "disc (radius {} m) overlaps an occupied cell or leaves the map",
                                                     v.name, p.x_m, p.y_m, i + 1, (i + 1) % n + 1, v.radius_m));
          k = samples + 1;
          i = legs;
        }
      }
    }
  }
}

// Where the world puts the robot (its start, kidnappings, docks) and the visitors, against the map.
void check_on_the_map(Reader& r, const YAML::Node& start, const World& w) {
  const SolidMap solid(w.grid);
  const navi::CellIndex c = w.grid.cell_at({w.start_pose.x_m, w.start_pose.y_m});
  if (!w.grid.contains(c)) {
    r.error(start, "start_pose is outside the map");
  } else if (!w.grid.is_free(c)) {
    r.error(start, "start_pose is not on a free cell of the map");
  } else if (solid.disc_overlaps({w.start_pose.x_m, w.start_pose.y_m}, w.robot.radius_m)) {
    r.error(start, "at start_pose the robot's footprint (radius " + std::to_string(w.robot.radius_m) +
                       " m) overlaps an occupied cell or leaves the map");
  }
  check_visitor_paths(r, solid, w);
  for (const StuckCliffSensor& st : w.faults.stuck_cliff) {
    if (st.index >= w.robot.cliff.positions.size()) {
      r.diagnostics().error(
          st.where, fmt::format("stuck_cliff.index {} names no cliff sensor: the robot has {} (robot.cliff.positions)", st.index,
                                w.robot.cliff.positions.size()));
    }
  }
  // A glass pane over the start: the robot would start inside it.
  const navi::Point2D start_point{w.start_pose.x_m, w.start_pose.y_m};
  for (const SonarOnlyObstacle& o : w.sonar_only) {
    if (navi::Region{o.name, o.polygon, o.where}.contains(start_point)) {
      r.diagnostics().error(o.where, "sonar_only '" + o.name + "' covers start_pose: the robot would start inside it");
    }
  }
  for (const Kidnapping& k : w.faults.kidnappings) {
    if (solid.disc_overlaps({k.to.x_m, k.to.y_m}, w.robot.radius_m)) {
      r.diagnostics().error(k.where, "kidnap.to: there the robot's footprint (radius " + std::to_string(w.robot.radius_m) +
                                         " m) overlaps an occupied cell or leaves the map");
    }
  }
  for (const Dock& k : w.docks) {
    if (solid.disc_overlaps({k.pose.x_m, k.pose.y_m}, w.robot.radius_m)) {
      r.diagnostics().error(k.where, "dock '" + k.name + "': docked there, the robot's footprint (radius " +
                                         std::to_string(w.robot.radius_m) + " m) overlaps an occupied cell or leaves the map");
    }
  }
}

World walk_world(std::string_view text, const std::filesystem::path& file) {
  const std::string fname = file.string();
  const YAML::Node root = yaml::parse(text, fname);
  Reader r(fname);
  World w;
  w.file = file;
  if (!r.check_map(
          root, "the world file",
          {"map", "regions", "start_pose", "seed", "robot", "drops", "obstacles", "visitors", "docks", "faults", "sonar_only"})) {
    throw ConfigError(std::move(r.diagnostics()));
  }
  const bool have_map = read_map_and_regions(r, root, file.parent_path(), w);
  const YAML::Node start = root["start_pose"];
  if (start) {
    if (auto p = r.pose(start, "start_pose")) w.start_pose = *p;
  } else {
    r.error(root, "the world file needs start_pose: [x, y, theta] (map frame, metres, radians)");
  }
  if (const YAML::Node s = root["seed"]) {
    try {
      w.seed = s.as<std::uint64_t>();
    } catch (const YAML::Exception&) {
      r.error(s, "seed must be a non-negative whole number, got " + Reader::kind(s));
    }
  }
  if (const YAML::Node rb = root["robot"]) read_robot(r, rb, w.robot);
  if (const YAML::Node drops = root["drops"]) read_drops(r, drops, w);
  if (const YAML::Node glass = root["sonar_only"]) read_sonar_only(r, glass, w);
  if (const YAML::Node obs = root["obstacles"]) read_obstacles(r, obs, w);
  if (const YAML::Node docks = root["docks"]) read_docks(r, docks, w);
  if (const YAML::Node f = root["faults"]) read_faults(r, f, w.faults);
  if (const YAML::Node v = root["visitors"]) read_visitors(r, v, w.visitors);
  if (have_map && start && !r.diagnostics().has_errors()) check_on_the_map(r, start, w);
  if (r.diagnostics().has_errors()) throw ConfigError(std::move(r.diagnostics()));
  return w;
}

}  // namespace

World parse_world(std::string_view text, const std::filesystem::path& file) {
  return yaml::guarded(file.string(), [&] { return walk_world(text, file); });
}

World load_world(const std::filesystem::path& file) {
  return parse_world(yaml::read_file(file), file);
}

}  // namespace tripodal::sim
