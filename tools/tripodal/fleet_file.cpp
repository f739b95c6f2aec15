// The fleet file (fleet_file.hpp).
#include "fleet_file.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <sstream>

#include "run_outputs.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/ray_caster.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"
#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal::tool {

std::vector<FleetMember> load_fleet_file(const std::filesystem::path& file) {
  const std::string name = file.string();
  const YAML::Node root = yaml::parse(yaml::read_file(file), name);
  const std::filesystem::path dir = std::filesystem::absolute(file).parent_path();
  Diagnostics d;
  yaml::Reader r(name, d);
  std::vector<FleetMember> out;
  yaml::guarded(name, [&] {
    if (!r.expect_map(root, "a fleet file") || !r.expect_keys(root, {"robots"}, "a fleet file")) return;
    const YAML::Node robots = r.require(root, "robots", "a fleet file", "a list of robots, each with name and profile");
    if (!robots || !r.expect_list(robots, "robots")) return;
    if (robots.size() == 0) r.error(robots, "robots: the list is empty; a fleet needs at least one robot");
    std::map<std::string, SourceLocation> names;
    std::map<std::string, std::string> namespaces;  // namespace -> "robot 'a' (FILE:L:C)"
    for (std::size_t i = 0; i < robots.size(); ++i) {
      const YAML::Node e = robots[i];
      const std::string what = "robots[" + std::to_string(i) + "]";
      if (!r.expect_map(e, what) || !r.expect_keys(e, {"name", "profile", "namespace", "start_pose", "sensors"}, what)) continue;
      FleetMember m;
      m.where = r.at(e);
      bool twice = false;  // its name's namespace then clashes too: said once
      const YAML::Node n = r.require(e, "name", what, "the robot's name: letters, digits and '_'");
      if (n) {
        if (const auto v = r.text(n, what + ".name", true)) {
          if (!is_ros_namespace(*v) || v->find('/') != std::string::npos) {
            r.error(n, what + ".name: '" + *v + "' is not a name of letters, digits and '_' not starting with a digit");
          } else if (const auto [it, added] = names.emplace(*v, r.at(n)); !added) {
            r.error(n, what + ".name: '" + *v + "' is given twice (first at " + it->second.str() + ")");
            twice = true;
          }
          m.name = *v;
        }
      }
      m.ns = m.name;
      if (const YAML::Node ns = e["namespace"]) {
        if (const auto v = r.text(ns, what + ".namespace", true)) {
          if (!is_ros_namespace(*v)) {
            r.error(ns, what + ".namespace: '" + *v +
                            "' is not a ROS 2 namespace (names of letters, digits and '_', "
                            "separated by '/')");
          }
          m.ns = *v;
        }
      }
      if (!m.ns.empty() && !(twice && !e["namespace"])) {
        const YAML::Node at = e["namespace"] ? e["namespace"] : e;
        const std::string owner = "robot '" + m.name + "' (" + r.at(at).str() + ")";
        if (const auto [it, added] = namespaces.emplace(m.ns, owner); !added) {
          r.error(at, what + ": namespace '" + m.ns + "' is already that of " + it->second + ": two robots cannot share one");
        }
      }
      const YAML::Node p = r.require(e, "profile", what, "the robot's profile, a path relative to this file");
      if (p) {
        if (const auto v = r.text(p, what + ".profile", true)) {
          m.profile = std::filesystem::path(*v).is_absolute() ? std::filesystem::path(*v) : dir / *v;
          std::error_code ec;
          if (!std::filesystem::is_regular_file(m.profile, ec)) {
            r.error(p, what + ".profile: cannot read '" + m.profile.string() + "'");
          } else {
            m.profile = std::filesystem::weakly_canonical(m.profile);
          }
        }
      }
      if (const YAML::Node s = e["sensors"]) {
        if (const auto v = r.names(s, what + ".sensors")) {
          m.sensors.emplace();
          for (const std::string& sensor : *v) {
            if (sensor != "gyro" && sensor != "bumpers" && sensor != "cliff" && sensor != "battery") {
              r.error(s, what + ".sensors: unknown sensor '" + sensor + "'; expected some of gyro, bumpers, cliff, battery");
            }
            *m.sensors += (m.sensors->empty() ? "" : ",") + sensor;
          }
        }
      }
      if (const YAML::Node s = e["start_pose"]) {
        if (const auto v = r.numbers(s, what + ".start_pose", 3, 3, "[x_m, y_m, theta_rad]")) {
          m.start = Pose2D{(*v)[0], (*v)[1], (*v)[2]};
        }
      }
      out.push_back(std::move(m));
    }
  });
  if (d.has_errors()) throw ConfigError(std::move(d));
  return out;
}

std::vector<FleetMember> numbered_fleet(int n, const std::filesystem::path& profile, const std::string& prefix) {
  std::vector<FleetMember> out;
  for (int k = 1; k <= n; ++k) {
    const std::string name = prefix + std::to_string(k);
    out.push_back({name, name, profile, std::nullopt, {}, SourceLocation{"--robots", 1, 1}});
  }
  return out;
}

std::string world_sensors(const sim::World& world) {
  const sim::SimRobotConfig& rc = world.robot;
  std::string out;
  const auto add = [&](bool enabled, const char* name) {
    if (enabled) out += (out.empty() ? "" : ",") + std::string(name);
  };
  add(rc.gyro.enabled, "gyro");
  add(rc.bumpers.enabled, "bumpers");
  add(rc.cliff.enabled, "cliff");
  add(rc.battery.enabled, "battery");
  return out;
}

std::vector<Pose2D> fleet_starts(const sim::World& world, const std::vector<FleetMember>& members) {
  const double r = world.robot.radius_m;
  const sim::SolidMap solid(world.grid);
  Diagnostics d;
  std::vector<const FleetMember*> given;
  for (const FleetMember& m : members) {
    if (!m.start) continue;
    if (solid.disc_overlaps({m.start->x_m, m.start->y_m}, r)) {
      d.error(m.where, "robot '" + m.name + "': its start pose (" + app::fixed(m.start->x_m, 2) + ", " +
                           app::fixed(m.start->y_m, 2) + ") is not free floor of " + world.file.string() +
                           " for a body of radius " + app::fixed(r, 2) + " m");
    }
    for (const FleetMember* o : given) {
      if (std::hypot(o->start->x_m - m.start->x_m, o->start->y_m - m.start->y_m) < 2.0 * r + 0.1) {
        d.error(m.where, "robot '" + m.name + "' starts within " + app::fixed(2.0 * r + 0.1, 2) + " m of robot '" + o->name +
                             "' (bodies of radius " + app::fixed(r, 2) + " m)");
      }
    }
    given.push_back(&m);
  }
  if (d.has_errors()) throw ConfigError(std::move(d));
  // The grid's places, nearest the world's start pose first, minus those a given pose takes (up
  // to four each: those closer to it than the grid's spacing).
  const std::size_t wanted = members.size() - given.size();
  std::vector<Pose2D> grid;
  try {
    grid = sim::fleet_start_poses(world, wanted + 4 * given.size(), kFleetStartGap_m);
  } catch (const ConfigError&) {
    grid = sim::fleet_start_poses(world, wanted, kFleetStartGap_m);  // throws "no room for N robots"
  }
  std::vector<Pose2D> out;
  std::size_t next = 0;
  for (const FleetMember& m : members) {
    if (m.start) {
      out.push_back(*m.start);
      continue;
    }
    for (;; ++next) {
      if (next >= grid.size()) {
        throw ConfigError(m.where, "robot '" + m.name + "': no free place left for it around the start pose of " +
                                       world.file.string() + " beside the start poses given; give it one");
      }
      const Pose2D& p = grid[next];
      const bool taken = std::any_of(given.begin(), given.end(), [&](const FleetMember* g) {
        return std::hypot(g->start->x_m - p.x_m, g->start->y_m - p.y_m) < 2.0 * r + kFleetStartGap_m - 1e-6;
      });
      if (!taken) break;
    }
    out.push_back(grid[next++]);
  }
  return out;
}

std::string fleet_file_text(const std::vector<FleetMember>& members, const std::vector<Pose2D>& starts) {
  YAML::Node root(YAML::NodeType::Map);
  YAML::Node list(YAML::NodeType::Sequence);
  for (std::size_t i = 0; i < members.size(); ++i) {
    YAML::Node e(YAML::NodeType::Map);
    e["name"] = members[i].name;
    e["namespace"] = members[i].ns;
    e["profile"] = std::filesystem::absolute(members[i].profile).string();
    if (members[i].sensors) e["sensors"] = YAML::Load("[" + *members[i].sensors + "]");
    YAML::Node pose(YAML::NodeType::Sequence);
    pose.SetStyle(YAML::EmitterStyle::Flow);
    pose.push_back(starts.at(i).x_m);
    pose.push_back(starts.at(i).y_m);
    pose.push_back(starts.at(i).theta_rad);
    e["start_pose"] = pose;
    list.push_back(e);
  }
  root["robots"] = list;
  YAML::Emitter e;
  e.SetDoublePrecision(12);  // 0.8, not 0.80000000000000004
  e << root;
  return std::string("# Generated by tripodal fleet: its robots, each with its start pose in the shared world\n") + e.c_str() +
         "\n";
}

}  // namespace tripodal::tool
