#include "robot_topics.hpp"

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>

#include "robot_panels.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/section_splitter.hpp"
#include "wire.hpp"

namespace tripodal::monitor {
namespace {

using nlohmann::json;

// JSON schemas of the topics (Foxglove reads them to name fields); the foxglove.* shapes are the
// ones its panels draw.
constexpr std::string_view kTimeSchema = R"({"type":"object","properties":{"sec":{"type":"integer"},"nsec":{"type":"integer"}}})";

std::string pose_schema() {
  return std::string(R"({"type":"object","properties":{"timestamp":)") + std::string(kTimeSchema) +
         R"(,"frame_id":{"type":"string"},"pose":{"type":"object","properties":{"position":{"type":"object"},"orientation":{"type":"object"}}}}})";
}

json stamp(double t_s) {
  const double sec = std::floor(std::max(t_s, 0.0));
  return json{{"sec", static_cast<std::int64_t>(sec)}, {"nsec", static_cast<std::int64_t>((std::max(t_s, 0.0) - sec) * 1e9)}};
}

json pose_json(const Pose2D& p) {
  return json{{"position", {{"x", p.x_m}, {"y", p.y_m}, {"z", 0.0}}},
              {"orientation", {{"x", 0.0}, {"y", 0.0}, {"z", std::sin(p.theta_rad / 2.0)}, {"w", std::cos(p.theta_rad / 2.0)}}}};
}

std::string base64_bytes(const std::vector<std::uint8_t>& v) {
  return base64(std::string_view(reinterpret_cast<const char*>(v.data()), v.size()));
}

}  // namespace

RobotTopics::RobotTopics(Robot& robot, const Clock& clock, MonitorServer& server)
    : robot_(robot), clock_(clock), server_(server) {
  ch_pose_ = server_.advertise("/pose", "foxglove.PoseInFrame", pose_schema(), Delivery::bulk);
  ch_path_ = server_.advertise("/path", "foxglove.PosesInFrame",
                               R"({"type":"object","properties":{"frame_id":{"type":"string"},"poses":{"type":"array"}}})",
                               Delivery::state);
  ch_map_ = server_.advertise(
      "/map", "tripodal.Map",
      R"({"type":"object","properties":{"width":{"type":"integer"},"height":{"type":"integer"},"resolution":{"type":"number"},"cells":{"type":"string","contentEncoding":"base64"},"section_of_cell":{"type":"string","contentEncoding":"base64"},"sections":{"type":"array"}}})",
      Delivery::state);
  ch_cleaned_ = server_.advertise(
      "/cleaned", "tripodal.CleanedCells",
      R"({"type":"object","properties":{"width":{"type":"integer"},"height":{"type":"integer"},"mask":{"type":"string","contentEncoding":"base64"}}})",
      Delivery::bulk);
  ch_laser_ = server_.advertise(
      "/laser", "foxglove.LaserScan",
      R"({"type":"object","properties":{"frame_id":{"type":"string"},"pose":{"type":"object"},"start_angle":{"type":"number"},"end_angle":{"type":"number"},"ranges":{"type":"array","items":{"type":"number"}},"intensities":{"type":"array","items":{"type":"number"}}}})",
      Delivery::bulk);
  ch_nets_ = server_.advertise(
      "/nets", "tripodal.Nets",
      R"({"type":"object","properties":{"nets":{"type":"array","items":{"type":"object","properties":{"run":{"type":"string"},"net":{"type":"string"},"places":{"type":"array"},"transitions":{"type":"array"},"svg":{"type":"string","description":"Graphviz dot layout"}}}}}})",
      Delivery::state);
  ch_markings_ = server_.advertise(
      "/markings", "tripodal.Markings",
      R"({"type":"object","properties":{"nets":{"type":"array","items":{"type":"object","properties":{"run":{"type":"string"},"marked":{"type":"array"},"last_firing":{"type":"string"}}}}}})",
      Delivery::bulk);
  ch_lifecycle_ = server_.advertise(
      "/lifecycle", "tripodal.LifecycleEntry",
      R"({"type":"object","properties":{"robot":{"type":"string","description":"the robot's name"},"identity":{"type":["string","null"],"description":"how the fleet reaches it: DDS domain, namespace and security identity; null when not on DDS"},"time_s":{"type":"number"},"kind":{"type":"string"},"text":{"type":"string"}}})",
      Delivery::event);
  ch_status_ = server_.advertise(
      "/status", "tripodal.Status",
      R"({"type":"object","properties":{"time_s":{"type":"number"},"paused":{"type":"boolean"},"task_state":{"type":"string"},"velocity":{"type":"object"},"battery":{"type":["number","null"]},"coverage":{"type":["number","null"]},"behaviors":{"type":"array"},"winner":{"type":"string"},"board":{"type":"object","description":"the control board's link as the host sees it; only on hardware board"},"hri":{"type":["object","null"],"description":"what the robot_'s HRI displays: task, task_state, process, fault, status, and the last input with its answer (last); null without an HRI"}}})",
      Delivery::bulk);
}

std::vector<NetView> RobotTopics::running_nets() const {
  std::vector<NetView> out;
  if (const Engine* e = robot_.planner().net_engine()) out.push_back({"task", &e->net(), e});
  for (const std::string& run : robot_.supervisor().running_runs()) {
    if (const Engine* e = robot_.supervisor().engine(run)) out.push_back({run, &e->net(), e});
  }
  return out;
}

void RobotTopics::publish_nets() {
  const std::vector<NetView> nets = running_nets();
  json j{{"nets", json::array()}};
  for (const NetView& v : nets) {
    json places = json::array(), transitions = json::array();
    for (const Place& p : v.net->places()) {
      json jp{{"id", p.id}, {"name", p.name}, {"initial", p.initial_tokens}};
      if (p.behavior) jp["behavior"] = p.behavior->behavior;
      if (p.process) jp["process"] = true;
      if (p.outcome != Outcome::none) jp["outcome"] = p.outcome == Outcome::success ? "success" : "fault";
      places.push_back(std::move(jp));
    }
    for (const Transition& t : v.net->transitions()) {
      json in = json::array(), out = json::array();
      for (const ArcRef& a : t.inputs) in.push_back(a.place);
      for (const ArcRef& a : t.reads) in.push_back(a.place);
      for (const ArcRef& a : t.outputs) out.push_back(a.place);
      transitions.push_back({{"id", t.id}, {"name", t.name}, {"event", t.event}, {"in", in}, {"out", out}});
    }
    j["nets"].push_back(
        {{"run", v.run}, {"net", v.net->id}, {"places", places}, {"transitions", transitions}, {"svg", drawing_.svg(*v.net)}});
  }
  server_.publish(ch_nets_, now_s(), j.dump());
}

void RobotTopics::publish_map_once() {
  if (!map_sent_) publish_map();
}

void RobotTopics::publish_map() {
  const auto* maps = robot_.module<navi::CGridMaps>();
  if (maps == nullptr) return;
  const navi::OccupancyGrid& g = maps->grid();
  if (g.size() == 0) return;
  std::vector<std::uint8_t> cells(g.size()), section_of(g.size(), 0);
  for (std::size_t i = 0; i < g.size(); ++i) {
    const auto s = g.state(i);
    cells[i] = s == navi::Occupancy::free ? 0 : s == navi::Occupancy::occupied ? 1 : 2;
  }
  json sections = json::array();
  if (const auto* splitter = robot_.module<navi::CSectionSplitter>()) {
    for (const navi::Section& s : splitter->sections().sections) {
      for (const std::size_t i : s.cells) section_of[i] = static_cast<std::uint8_t>(1 + s.id % 250);
      sections.push_back(
          {{"name", s.name}, {"index", 1 + s.id % 250}, {"x", s.centroid.x_m}, {"y", s.centroid.y_m}, {"area_m2", s.area_m2}});
    }
  }
  const json j{{"width", g.width()},
               {"height", g.height()},
               {"resolution", g.resolution_m()},
               {"origin", {{"x", g.origin().x_m}, {"y", g.origin().y_m}}},
               {"cells", base64_bytes(cells)},
               {"section_of_cell", base64_bytes(section_of)},
               {"sections", sections}};
  server_.publish(ch_map_, now_s(), j.dump());
  map_sent_ = true;
}

void RobotTopics::publish_lifecycle(const LifecycleRecorder& life) {
  const auto& entries = life.entries();
  for (; life_published_ < entries.size(); ++life_published_) {
    const LifecycleEntry& e = entries[life_published_];
    const bool firing = e.text.find(" fire ") != std::string::npos;
    if (firing) continue;  // firings travel as markings (last_firing), not as timeline entries
    const std::string kind = e.text.starts_with("task")                                                                ? "task"
                             : e.text.starts_with("process")                                                           ? "process"
                             : e.text.find("fault") != std::string::npos || e.text.find("failed") != std::string::npos ? "fault"
                             : e.text.find("recover") != std::string::npos ? "recovery"
                                                                           : "note";
    server_.publish(ch_lifecycle_, to_seconds(e.time),
                    json{{"time_s", to_seconds(e.time)}, {"kind", kind}, {"text", e.text}}.dump());
  }
}

void RobotTopics::publish_periodic(const MonitorExtras& extras, const ConsoleState& console) {
  const double t = now_s();
  const NavigationData& nav = robot_.navigation();
  server_.publish(ch_pose_, t, json{{"timestamp", stamp(t)}, {"frame_id", "map"}, {"pose", pose_json(nav.map_from_base)}}.dump());
  if (nav.path_id != path_id_) {
    path_id_ = nav.path_id;
    json poses = json::array();
    for (const Pose2D& p : nav.path) poses.push_back({{"timestamp", stamp(t)}, {"frame_id", "map"}, {"pose", pose_json(p)}});
    server_.publish(ch_path_, t, json{{"timestamp", stamp(t)}, {"frame_id", "map"}, {"poses", poses}}.dump());
  }
  publish_laser(t, nav);
  publish_markings(t, console);
  server_.publish(ch_status_, t, status_panel(robot_, clock_.now(), t, extras, console).dump());
}

// A scan once, when it is new (a scanner turns slower than the monitor publishes).
void RobotTopics::publish_laser(double t, const NavigationData& nav) {
  if (const auto* laser = robot_.resources().first<LaserScan>();
      laser != nullptr && laser->has_reading() && laser->stamp() != last_scan_) {
    last_scan_ = laser->stamp();
    const LaserScan& s = laser->latest();
    json ranges = json::array();
    // Millimetres are all a drawing needs, and the scan is the largest message (shortest decimals).
    for (const float r : s.ranges_m) {
      ranges.push_back(std::isfinite(r) && r >= s.range_min_m && r <= s.range_max_m
                           ? std::round(static_cast<double>(r) * 1000.0) / 1000.0
                           : 0.0);
    }
    server_.publish(ch_laser_, t,
                    json{{"timestamp", stamp(to_seconds(s.stamp))},
                         {"frame_id", "map"},
                         {"pose", pose_json(nav.map_from_base)},
                         {"start_angle", s.angle_min_rad},
                         {"end_angle", s.angle_max_rad},
                         {"ranges", ranges},
                         {"intensities", json::array()}}
                        .dump());
  }
}

void RobotTopics::publish_markings(double t, const ConsoleState& console) {
  json marked = json::array();
  for (const NetView& v : running_nets()) {
    json places = json::array();
    const auto m = v.engine->marking();
    for (std::size_t i = 0; i < m.size(); ++i) {
      if (m[i] > 0) places.push_back({{"place", v.net->places()[i].id}, {"tokens", m[i]}});
    }
    const auto lf = console.last_firing.find(v.run);
    marked.push_back({{"run", v.run},
                      {"net", v.net->id},
                      {"marked", places},
                      {"last_firing", lf == console.last_firing.end() ? "" : lf->second}});
  }
  server_.publish(ch_markings_, t, json{{"timestamp", stamp(t)}, {"nets", marked}}.dump());
}

void RobotTopics::publish_cleaned(const std::vector<std::uint8_t>& m) {
  std::vector<std::uint8_t> bits((m.size() + 7) / 8, 0);
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (m[i] != 0) bits[i / 8] = static_cast<std::uint8_t>(bits[i / 8] | (1U << (i % 8)));
  }
  server_.publish(ch_cleaned_, now_s(), json{{"cells", m.size()}, {"mask", base64_bytes(bits)}}.dump());
}

}  // namespace tripodal::monitor
