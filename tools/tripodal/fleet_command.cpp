// `tripodal fleet --robots 4 --world WORLD.yaml --task "clean the room 3211"`: a fleet on one
// machine over loopback DDS (docs/distribution.md, "A fleet"). Each robot is a `tripodal run`
// process of its own, on a copy of the profile with its own dds: namespace; the fleet planner
// (tripodal/dds/fleet.hpp) shares the task's units among them, reassigns the work of a robot that
// goes silent and prints one result. Built only with the dds area.
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_tool.hpp"
#include "fleet_file.hpp"
#include "run_outputs.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/dds/fleet.hpp"
#include "tripodal/dds/participant.hpp"
#include "tripodal/navi/section_splitter.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

extern char** environ;

namespace tripodal::tool {
namespace {

using namespace cli;

constexpr int kFleetFailed = 4;

constexpr std::string_view kDescription =
    "Runs a fleet of N robots on one machine over loopback DDS: each robot is a `tripodal run`\n"
    "process of its own (the same profile, a copy per robot with the dds: namespace robotK, task\n"
    "commands on, participant lease --lease-s), each in its own copy of the simulated world. The\n"
    "fleet planner divides the task into units, \"clean the room R\" into the room's sections\n"
    "(\"clean the section A\", ...) and \"clean the rooms R1, R2 and R3\" into the rooms, gives each\n"
    "robot a balanced share (by area, then nearest), sends each robot its next unit as a\n"
    "TaskCommand when the last one is done, and when a robot goes silent (its DDS liveliness lost:\n"
    "its process died) gives the unit it had in hand and the ones it had not begun to the others.\n"
    "Prints what happens and one result: which units were done by whom, the reassignments, the\n"
    "failures. With --out, DIR receives fleet.json, fleet.txt, the robots' profiles and their logs\n"
    "(robotK.log); without, they go to a temporary folder that is removed. The robots run at\n"
    "--speed times real time. --kill-robot K --kill-after-s S kills robot K with SIGKILL S seconds\n"
    "after it was given its first unit (the test of a robot lost mid-task). The robots are stopped\n"
    "when the fleet ends, fails or is interrupted (Ctrl-C, SIGTERM). --fleet FILE names the robots\n"
    "instead (name, profile, namespace and start pose each); --keys DIR secures the fleet's domain\n"
    "with the keys of tripodal fleet-keys.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 every unit done, 1 bad profile/world/task, 2 bad command line, 3 I/O error (a file,\n"
    "            a robot process, DDS), 4 a unit failed or was not done (no robot left, timeout, stopped).";

struct Args {
  int robots = 0;
  std::filesystem::path fleet;  // a fleet file: its robots instead of --robots N x --robot
  std::filesystem::path world, robot, out;
  std::string task;
  double speed = 50.0;
  unsigned domain = 0;
  double lease_s = 5.0;
  double grace_s = 0.0;
  double timeout_s = 900.0;
  std::optional<double> kill_after_s;
  std::optional<int> kill_robot;
  std::optional<std::uint64_t> seed;
  bool shared_world = false;           // one sim-server world for every robot
  std::optional<unsigned> sim_domain;  // its DDS domain (default --domain + 1)
  bool sim_loopback = true;
  bool system_network = false;     // the fleet's DDS on Cyclone's own configuration (CYCLONEDDS_URI)
  std::string launcher;            // a command before each process, {name} replaced (ip netns exec ns_{name})
  std::filesystem::path keys;      // DDS Security: the fleet's keys (tripodal fleet-keys); empty: not secured
  std::string identity = "fleet";  // the fleet tool's identity in them
};

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_fleet_stop_signal(int) { g_stop = 1; }

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return s;
}

std::vector<std::string> words_of(std::string_view text) {
  std::string t(text);
  while (!t.empty() && (t.back() == '.' || t.back() == '!' || t.back() == '?' || std::isspace(static_cast<unsigned char>(t.back())))) {
    t.pop_back();
  }
  std::replace(t.begin(), t.end(), ',', ' ');
  std::istringstream s(t);
  std::vector<std::string> out;
  for (std::string w; s >> w;) out.push_back(w);
  return out;
}

// The robot's section splitter, configured from the profile's entry as the robot configures it
// (the module's manifest: defaults, types, ranges, errors located in the profile): the same split
// the robots make of the same map.
void configure_from_profile(navi::CSectionSplitter& splitter, const RobotProfile& profile) {
  for (const ModuleEntry& e : profile.navigation) {
    if (e.type != navi::CSectionSplitter::static_manifest().name) continue;
    ParameterValues given;
    for (const auto& [k, v] : e.parameters) given.emplace(k, Value{v});
    splitter.configure(given, e.where);
    return;
  }
  throw ConfigError(profile.where, "tripodal fleet: sharing a room by sections needs the robot's SectionSplitter module");
}

constexpr std::string_view kForms =
    "the fleet shares \"clean [the] room ROOM\" (by its sections) and \"clean [the] rooms ROOM1, ROOM2 and ROOM3\" (by room)";

// The units of the task: a room's sections, or the rooms named. Throws ConfigError (located at
// --task) when the task does not divide or names an unknown room.
std::vector<dds::FleetUnit> units_of(const std::string& task, const sim::World& world, const RobotProfile& profile) {
  const SourceLocation where{"--task", 1, 1};
  std::vector<std::string> w = words_of(lower(task));
  if (w.empty() || w[0] != "clean") throw ConfigError(where, "\"" + task + "\" does not divide among robots: " + std::string(kForms));
  w.erase(w.begin());
  if (!w.empty() && w[0] == "the") w.erase(w.begin());
  const auto known = [&] {
    std::string k;
    for (const std::string& n : world.regions.room_names()) k += " " + n;
    return "(known:" + k + ")";
  };
  std::vector<dds::FleetUnit> units;
  if (!w.empty() && w[0] == "rooms") {
    std::vector<std::string> rooms;
    for (std::size_t i = 1; i < w.size(); ++i) {
      if (w[i] != "and") rooms.push_back(w[i]);
    }
    if (rooms.empty()) throw ConfigError(where, "\"" + task + "\" names no room: " + std::string(kForms));
    for (const std::string& name : rooms) {
      const navi::Region* r = world.regions.room(name);
      if (r == nullptr) throw ConfigError(where, "unknown room '" + name + "' in \"" + task + "\" " + known());
      if (std::any_of(units.begin(), units.end(), [&](const dds::FleetUnit& u) { return u.name == name; })) {
        throw ConfigError(where, "room '" + name + "' is named twice in \"" + task + "\"");
      }
      double cx = 0.0, cy = 0.0;
      for (const navi::Point2D& p : r->polygon) cx += p.x_m, cy += p.y_m;
      const double n = static_cast<double>(std::max<std::size_t>(r->polygon.size(), 1));
      units.push_back({name, "clean the room " + name, std::max(r->area_m2(), 1e-3), cx / n, cy / n});
    }
    return units;
  }
  if (!w.empty() && w[0] == "room") w.erase(w.begin());
  if (w.size() != 1) throw ConfigError(where, "\"" + task + "\" does not divide among robots: " + std::string(kForms));
  navi::CSectionSplitter splitter;
  configure_from_profile(splitter, profile);
  splitter.split_map(world.grid, world.regions);
  const KnowledgeAnswer a = splitter.sections_of_room(w[0]);
  if (!a.ok) throw ConfigError(where, a.error);
  if (a.items.empty()) throw ConfigError(where, "room '" + w[0] + "' has no section with free floor to clean");
  for (const std::string& name : a.items) {
    const navi::Section* s = splitter.section(name);
    units.push_back({name, "clean the section " + name, std::max(s->area_m2, 1e-3), s->centroid.x_m, s->centroid.y_m});
  }
  return units;
}

// Relative paths of the profile (nets, tasks, module parameters) made absolute, so that the copy
// may live anywhere: a scalar that names an existing file or folder beside the profile.
void absolutize(YAML::Node node, const std::filesystem::path& dir) {
  if (node.IsMap()) {
    for (auto it = node.begin(); it != node.end(); ++it) absolutize(it->second, dir);
  } else if (node.IsSequence()) {
    for (std::size_t i = 0; i < node.size(); ++i) absolutize(node[i], dir);
  } else if (node.IsScalar()) {
    const std::string v = node.Scalar();
    if (v.empty() || v.find('/') == std::string::npos || std::filesystem::path(v).is_absolute()) return;
    std::error_code ec;
    if (std::filesystem::exists(dir / v, ec)) node = std::filesystem::weakly_canonical(dir / v).string();
  }
}

// The profile of robot `ns`: the given one with a dds: section of its own (any dds: section of the
// original is replaced).
std::string fleet_profile(const std::filesystem::path& profile, const std::string& ns, unsigned domain, double lease_s,
                          bool loopback, const std::filesystem::path& keys = {}, const std::string& identity = {}) {
  YAML::Node root = YAML::LoadFile(profile.string());
  absolutize(root, std::filesystem::absolute(profile).parent_path());
  root.remove("dds");
  YAML::Node d(YAML::NodeType::Map);
  d["domain_id"] = domain;
  d["namespace"] = ns;
  d["loopback"] = loopback;
  d["participant_lease_s"] = lease_s;
  d["tasks"] = true;
  YAML::Node publish(YAML::NodeType::Sequence);
  publish.push_back("events");  // the fleet follows the events only; the rest would cost CPU
  d["publish"] = publish;
  if (!keys.empty()) {  // the robot's identity in the fleet's keys: it takes commands only from the CA's identities
    YAML::Node sec(YAML::NodeType::Map);
    sec["keys"] = std::filesystem::absolute(keys).string();
    sec["identity"] = identity;
    d["security"] = sec;
  }
  root["dds"] = d;
  YAML::Emitter e;
  e << root;
  return "# Generated by tripodal fleet from " + std::filesystem::absolute(profile).string() + "\n" + e.c_str() + "\n";
}

// Robot `k`'s copy of the world for a shared world: the same map and regions (absolute paths),
// starting where the sim-server puts robot k, so that its localizer starts where its body is.
std::string fleet_world(const std::filesystem::path& world, const Pose2D& start) {
  YAML::Node root = YAML::LoadFile(world.string());
  const std::filesystem::path dir = std::filesystem::absolute(world).parent_path();
  absolutize(root, dir);
  for (const char* key : {"map", "regions"}) {  // plain file names, which absolutize leaves
    if (root[key] && root[key].IsScalar() && std::filesystem::path(root[key].Scalar()).is_relative()) {
      root[key] = std::filesystem::weakly_canonical(dir / root[key].Scalar()).string();
    }
  }
  YAML::Node pose(YAML::NodeType::Sequence);
  pose.SetStyle(YAML::EmitterStyle::Flow);
  pose.push_back(start.x_m);
  pose.push_back(start.y_m);
  pose.push_back(start.theta_rad);
  root["start_pose"] = pose;
  YAML::Emitter e;
  e << root;
  return "# Generated by tripodal fleet --shared-world from " + std::filesystem::absolute(world).string() + "\n" + e.c_str() +
         "\n";
}

// "gyro, bumpers" or "none", for people.
std::string sensors_text(std::string list) {
  if (list.empty()) return "none";
  for (std::size_t at = list.find(','); at != std::string::npos; at = list.find(',', at + 2)) list.insert(at + 1, " ");
  return list;
}

// The server's closing line ("... robot-robot contacts: N; closest approach between robots: X m"),
// or empty.
std::string shared_world_summary(const std::filesystem::path& log) {
  std::ifstream f(log);
  std::string found;
  for (std::string l; std::getline(f, l);) {
    if (l.rfind("sim-server ended:", 0) == 0) found = l;
  }
  return found;
}

// A launcher's words (split on spaces; no quoting).
std::vector<std::string> words_of_command(const std::string& text) {
  std::istringstream s(text);
  std::vector<std::string> out;
  for (std::string w; s >> w;) out.push_back(w);
  return out;
}

// The robots' processes: stopped (SIGTERM, then SIGKILL) and reaped when the fleet ends, however.
class Children {
 public:
  struct Child {
    std::string name;
    pid_t pid = -1;
    bool exited = false;
    int status = 0;
  };
  ~Children() { stop(); }
  Children() = default;
  Children(const Children&) = delete;
  Children& operator=(const Children&) = delete;

  /// `launcher`: words put before argv, "{name}" in them replaced by `name` (empty: none).
  void spawn(const std::string& name, std::vector<std::string> argv, const std::filesystem::path& log,
             const std::string& launcher = {}) {
    if (!launcher.empty()) {
      std::vector<std::string> pre = words_of_command(launcher);
      for (std::string& w : pre) {
        for (std::size_t at = w.find("{name}"); at != std::string::npos; at = w.find("{name}")) w.replace(at, 6, name);
      }
      argv.insert(argv.begin(), pre.begin(), pre.end());
    }
    posix_spawn_file_actions_t fa;
    posix_spawn_file_actions_init(&fa);
    posix_spawn_file_actions_addopen(&fa, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&fa, 1, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&fa, 1, 2);
    std::vector<char*> args;
    args.reserve(argv.size() + 1);
    for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    pid_t pid = -1;
    const int rc = posix_spawnp(&pid, args[0], &fa, nullptr, args.data(), environ);
    posix_spawn_file_actions_destroy(&fa);
    if (rc != 0) throw std::runtime_error("cannot start " + name + " (" + argv[0] + "): " + std::strerror(rc));
    children_.push_back({name, pid});
  }

  struct Ended {
    std::string name, how;  // "robot2", "killed by signal 9"
  };
  /// Reaps those that ended.
  std::vector<Ended> reap() {
    std::vector<Ended> out;
    for (Child& c : children_) {
      if (c.exited) continue;
      int st = 0;
      if (waitpid(c.pid, &st, WNOHANG) == c.pid) {
        c.exited = true;
        c.status = st;
        out.push_back({c.name, describe(st)});
      }
    }
    return out;
  }

  void kill_one(std::size_t i) {
    if (i < children_.size() && !children_[i].exited) ::kill(children_[i].pid, SIGKILL);
  }

  void stop() {
    for (const Child& c : children_) {
      if (!c.exited) ::kill(c.pid, SIGTERM);
    }
    const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(5);
    while (std::chrono::steady_clock::now() < until && !all_exited()) {
      reap();
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    for (Child& c : children_) {
      if (c.exited) continue;
      ::kill(c.pid, SIGKILL);
      waitpid(c.pid, &c.status, 0);
      c.exited = true;
    }
  }

 private:
  static std::string describe(int st) {
    if (WIFEXITED(st)) return "exit code " + std::to_string(WEXITSTATUS(st));
    if (WIFSIGNALED(st)) return "killed by signal " + std::to_string(WTERMSIG(st));
    return "status " + std::to_string(st);
  }
  [[nodiscard]] bool all_exited() const {
    return std::all_of(children_.begin(), children_.end(), [](const Child& c) { return c.exited; });
  }
  std::vector<Child> children_;
};

// The end of a robot's log, for a robot that failed before it could say anything on DDS.
std::vector<std::string> last_lines(const std::filesystem::path& file, std::size_t n) {
  std::ifstream f(file);
  std::vector<std::string> lines;
  for (std::string l; std::getline(f, l);) {
    if (!l.empty()) lines.push_back(l);
  }
  if (lines.size() > n) lines.erase(lines.begin(), lines.end() - static_cast<std::ptrdiff_t>(n));
  return lines;
}


int run(const Args& a, std::ostream& out, std::ostream& err) {
  if ((a.robots > 0) == !a.fleet.empty()) {
    err << "tripodal fleet: give the robots either as --robots N (of one profile, --robot) or as a fleet file (--fleet FILE)\n";
    return kUsage;
  }
  if (a.kill_robot.has_value() != a.kill_after_s.has_value()) {
    err << "tripodal fleet: --kill-robot and --kill-after-s go together\n";
    return kUsage;
  }
  if (a.kill_robot && a.robots > 0 && (*a.kill_robot < 1 || *a.kill_robot > a.robots)) {
    err << "tripodal fleet: --kill-robot " << *a.kill_robot << ": expected a robot from 1 to " << a.robots << "\n";
    return kUsage;
  }
  const std::filesystem::path robot =
      a.robot.empty() ? std::filesystem::absolute(a.world).parent_path().parent_path() / "robots" / "psr2.yaml" : a.robot;
  for (const auto& f : {a.world, a.fleet.empty() ? robot : a.fleet}) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(f, ec)) {
      err << "tripodal fleet: cannot read '" << f.string() << "'" << (a.robot.empty() && f == robot ? " (the default --robot)" : "")
          << "\n";
      return kIoError;
    }
  }
  const unsigned sim_domain = a.sim_domain.value_or(a.domain + 1);
  if (a.shared_world && sim_domain > 232) {
    err << "tripodal fleet: --domain " << a.domain << " with --shared-world: the simulator's domain would be " << sim_domain
        << ", beyond 232; give --sim-domain ID\n";
    return kUsage;
  }
  std::filesystem::path dir = a.out;
  bool temporary = false;
  try {
    const std::vector<FleetMember> members = a.fleet.empty() ? numbered_fleet(a.robots, robot) : load_fleet_file(a.fleet);
    if (a.kill_robot && (*a.kill_robot < 1 || *a.kill_robot > static_cast<int>(members.size()))) {
      err << "tripodal fleet: --kill-robot " << *a.kill_robot << ": expected a robot from 1 to " << members.size() << "\n";
      return kUsage;
    }
    const sim::World world = sim::load_world(a.world);
    const std::vector<dds::FleetUnit> units = units_of(a.task, world, load_robot_profile(members.front().profile));
    // Every robot splits the room with its own profile's splitter: the fleet's units must be
    // every robot's sections, or "clean the section B" would mean another floor to each.
    for (const FleetMember& m : members) {
      if (m.profile == members.front().profile) continue;
      const std::vector<dds::FleetUnit> own = units_of(a.task, world, load_robot_profile(m.profile));
      const bool same =
          own.size() == units.size() && std::equal(own.begin(), own.end(), units.begin(), [](const auto& x, const auto& y) {
            return x.name == y.name && std::abs(x.area_m2 - y.area_m2) < 1e-6;
          });
      if (!same) {
        throw ConfigError(m.where, "robot '" + m.name + "': its profile " + m.profile.string() + " divides \"" + a.task +
                                       "\" into other units than robot '" + members.front().name +
                                       "''s: the robots of a fleet must split rooms alike (their SectionSplitter parameters)");
      }
    }

    if (dir.empty()) {
      std::string tmpl = (std::filesystem::temp_directory_path() / "tripodal-fleet-XXXXXX").string();
      if (::mkdtemp(tmpl.data()) == nullptr) throw std::runtime_error("cannot create a temporary folder: " + std::string(std::strerror(errno)));
      dir = tmpl;
      temporary = true;
    }
    std::filesystem::create_directories(dir);
    struct RemoveTemporary {
      const std::filesystem::path& dir;
      bool on;
      ~RemoveTemporary() {
        std::error_code ec;
        if (on) std::filesystem::remove_all(dir, ec);
      }
    } remove_temporary{dir, temporary};

    std::vector<dds::FleetRobot> robots;
    std::vector<Pose2D> starts;
    if (a.shared_world) {
      starts = fleet_starts(world, members);
    } else {  // each robot in a world of its own: its given start pose, or the world's
      for (const FleetMember& m : members) starts.push_back(m.start.value_or(world.start_pose));
    }
    for (std::size_t k = 0; k < members.size(); ++k)
      robots.push_back({members[k].name, starts[k].x_m, starts[k].y_m, members[k].ns});
    std::vector<std::string> names;
    names.reserve(units.size());
    for (const dds::FleetUnit& u : units) names.push_back(u.name + " (" + app::fixed(u.area_m2, 1) + " m2)");
    out << "tripodal fleet: " << members.size() << " robots, world " << a.world.string() << ", task \"" << a.task
        << "\": " << units.size() << " units:";
    for (const std::string& n : names) out << " " << n;
    out << "\n";
    if (units.size() < robots.size()) {
      const std::size_t idle = robots.size() - units.size();
      out << "(" << idle << (idle == 1 ? " robot gets" : " robots get") << " no unit at first: more robots than units)\n";
    }
    if (!a.fleet.empty()) {
      for (std::size_t k = 0; k < members.size(); ++k) {
        out << "  " << members[k].name << ": " << members[k].profile.filename().string() << ", namespace " << members[k].ns
            << ", starts at (" << app::fixed(starts[k].x_m, 2) << ", " << app::fixed(starts[k].y_m, 2) << ", "
            << app::fixed(starts[k].theta_rad, 3) << ")";
        if (a.shared_world) out << ", sensors " << sensors_text(members[k].sensors.value_or(world_sensors(world)));
        out << "\n";
      }
    } else if (a.shared_world) {
      out << "sensors of each robot's body besides the laser: " << sensors_text(world_sensors(world))
          << " (the world's robot, as hardware sim gives them)\n";
    }
    out.flush();

    // Secured: every identity's files are there before anything starts (a robot without its
    // certificate would only be seen silent, its reason in its log).
    std::optional<dds::SecurityFiles> security;
    if (!a.keys.empty()) {
      try {
        security = dds::fleet_identity(a.keys, a.identity);
      } catch (const dds::DdsError& e) {
        throw std::invalid_argument("--keys " + a.keys.string() + " --identity " + a.identity + ": " + e.what());
      }
      for (const FleetMember& m : members) {
        try {
          (void)dds::fleet_identity(a.keys, m.name);
        } catch (const dds::DdsError& e) {
          throw ConfigError(m.where, "robot '" + m.name + "' has no identity in " + a.keys.string() + ": " + e.what() +
                                         " (tripodal fleet-keys --out " + a.keys.string() + " --robot " + m.name + ")");
        }
      }
      out << "secured: DDS Security with the keys in " << a.keys.string() << ", the fleet as '" << a.identity
          << "', each robot as its name\n";
    }

    SteadyClock clock;
    dds::FleetOptions fo;
    fo.silence_grace = std::chrono::duration_cast<Duration>(std::chrono::duration<double>(a.grace_s));
    dds::FleetPlanner planner(robots, units, clock, fo);
    dds::DdsFleet fleet(
        planner, robots,
        dds::DdsFleetOptions{.domain_id = a.domain,
                             .network = a.system_network ? dds::Network::system : dds::Network::loopback,
                             .participant_lease = std::chrono::milliseconds(static_cast<long>(a.lease_s * 1000.0)),
                             .security = security});

    const std::string exe = std::filesystem::read_symlink("/proc/self/exe").string();
    Children children;
    for (const dds::FleetRobot& r : robots) {
      const FleetMember& m = members[static_cast<std::size_t>(&r - robots.data())];
      const std::filesystem::path p = dir / (r.name + ".yaml");
      std::ofstream f(p);
      f << fleet_profile(m.profile, m.ns, a.domain, a.lease_s, !a.system_network, a.keys, m.name);
      if (!f) throw std::runtime_error("cannot write '" + p.string() + "'");
      f.close();
      std::filesystem::path world_file = std::filesystem::absolute(a.world);
      if (a.shared_world || m.start) {  // its localizer starts where its body is
        world_file = dir / (r.name + "_world.yaml");
        std::ofstream w(world_file);
        w << fleet_world(a.world, starts[static_cast<std::size_t>(&r - robots.data())]);
        if (!w) throw std::runtime_error("cannot write '" + world_file.string() + "'");
      }
      std::vector<std::string> argv{exe,
                                    "run",
                                    "--robot",
                                    p.string(),
                                    "--world",
                                    world_file.string(),
                                    "--realtime",
                                    app::fixed(a.speed, 3),
                                    "--max-duration-s",
                                    app::fixed(a.timeout_s * a.speed + 60.0, 1)};
      if (a.seed) argv.insert(argv.end(), {"--seed", std::to_string(*a.seed)});
      if (a.shared_world) {
        // The body is the server's; its DDS domain is another than the fleet's, so that a network
        // fault between a robot and the fleet (scripts/netns_fleet.sh) is not one of its physics.
        argv.insert(argv.end(), {"--hardware", "dds", "--hardware-param", "namespace=" + m.ns, "--hardware-param",
                                 "domain_id=" + std::to_string(sim_domain), "--hardware-param",
                                 "loopback=" + std::string(a.sim_loopback ? "true" : "false")});
        const std::string sensors = m.sensors.value_or(world_sensors(world));
        if (!sensors.empty()) argv.insert(argv.end(), {"--hardware-param", "sensors=" + sensors});
      }
      children.spawn(r.name, argv, dir / (r.name + ".log"), a.launcher);
    }
    if (a.shared_world) {
      // The server reads who stands where from the fleet's own file, so that the two agree.
      const std::filesystem::path fleet_yaml = dir / "fleet.yaml";
      std::ofstream ff(fleet_yaml);
      ff << fleet_file_text(members, starts);
      if (!ff) throw std::runtime_error("cannot write '" + fleet_yaml.string() + "'");
      ff.close();
      std::vector<std::string> argv{exe,        "sim-server",
                                    "--fleet",  fleet_yaml.string(),
                                    "--world",  std::filesystem::absolute(a.world).string(),
                                    "--domain", std::to_string(sim_domain)};
      if (a.seed) argv.insert(argv.end(), {"--seed", std::to_string(*a.seed)});
      if (!a.sim_loopback) argv.emplace_back("--system-network");
      children.spawn("sim-server", argv, dir / "sim_server.log", a.launcher);
      out << "shared world: tripodal sim-server for " << members.size() << " robots on domain " << sim_domain
          << " (sim_server.log)\n";
    }

    // Every way the fleet may be told to end stops its robots first: a closed output (`| head`,
    // SIGPIPE) or a closed terminal (SIGHUP) too, which would otherwise end the fleet and leave
    // its robots running to their own limit.
    for (const int sig : {SIGINT, SIGTERM, SIGPIPE, SIGHUP}) std::signal(sig, on_fleet_stop_signal);
    bool killed = false, timed_out = false;
    auto print = [&](const std::vector<std::string>& lines) {
      for (const std::string& l : lines) out << l << '\n';
      out.flush();
    };
    while (!planner.finished() && g_stop == 0) {
      fleet.update();
      print(planner.take_log());
      if (a.kill_robot && !killed) {
        const std::string& victim = robots[static_cast<std::size_t>(*a.kill_robot - 1)].name;
        if (const auto since = planner.busy_since_s(victim); since && planner.elapsed_s() - *since >= *a.kill_after_s) {
          children.kill_one(static_cast<std::size_t>(*a.kill_robot - 1));
          killed = true;
          out << app::fixed(planner.elapsed_s(), 1) << " s  killed " << victim << " (SIGKILL), " << app::fixed(*a.kill_after_s, 1)
              << " s into its unit\n";
        }
      }
      for (const Children::Ended& e : children.reap()) {
        out << app::fixed(planner.elapsed_s(), 1) << " s  " << e.name << " ended: " << e.how << '\n';
        planner.robot_gone(e.name);
        // One that never came on DDS will not: no need to wait for the startup timeout. (A robot
        // that was on DDS is declared silent by its lost liveliness, the fleet's DDS path.)
        if (!planner.ready(e.name)) {
          planner.robot_silent(e.name, "its process ended before it was on DDS: " + e.how);
          for (const std::string& l : last_lines(dir / (e.name + ".log"), 3)) out << "    " << e.name << ".log: " << l << '\n';
        }
      }
      if (planner.elapsed_s() >= a.timeout_s) {
        timed_out = true;
        break;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    fleet.update();
    print(planner.take_log());
    dds::FleetResult result = planner.result();
    if (timed_out) result.reason += (result.reason.empty() ? "" : "; ") + std::string("timed out after ") + app::fixed(a.timeout_s, 1) + " s";
    if (g_stop != 0) result.reason += (result.reason.empty() ? "" : "; ") + std::string("stopped");
    if (timed_out || g_stop != 0) result.succeeded = false;
    children.stop();
    out << result.text();
    out << "fleet figures: " << app::fixed(result.duration_s, 1) << " s, " << result.reassignments.size() << " reassignments, "
        << result.done_twice << " units done twice, " << result.cancelled << " cancelled mid-way, " << result.silent.size()
        << " silences, " << result.back.size() << " back\n";
    if (a.shared_world) {
      const std::string summary = shared_world_summary(dir / "sim_server.log");
      out << "shared world: " << (summary.empty() ? "the sim-server printed no summary (see sim_server.log)" : summary) << "\n";
    }
    if (!temporary) {
      std::ofstream(dir / "fleet.json") << result.json();
      std::ofstream(dir / "fleet.txt") << result.text();
      out << "wrote " << (dir / "fleet.json").string() << ", fleet.txt, robotK.yaml and robotK.log\n";
    }
    return result.succeeded ? kOk : kFleetFailed;
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  } catch (const YAML::Exception& e) {
    err << "tripodal fleet: " << robot.string() << ": " << e.what() << '\n';
    return kBadInput;
  } catch (const std::invalid_argument& e) {
    err << "tripodal fleet: " << e.what() << '\n';
    return kBadInput;
  } catch (const std::exception& e) {  // files, processes, DDS
    err << "tripodal fleet: " << e.what() << '\n';
    return kIoError;
  }
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  auto* robots = cmd.add_option("--robots", a->robots, "N: how many robots (processes), 1 to 16")->check(CLI::Range(1, 16));
  cmd.add_option("--world", a->world, "WORLD.yaml: the world every robot runs in (its own copy, or one with --shared-world)")
      ->required();
  cmd.add_option("--task", a->task, "\"COMMAND\": \"clean the room 3211\" (by sections) or \"clean the rooms 2111 and 2133\"")->required();
  cmd.add_option("--robot", a->robot, "ROBOT.yaml: the robots' profile (default: robots/psr2.yaml beside the world's folder)");
  cmd.add_option("--fleet", a->fleet,
                 "FILE: the robots by name, each with its profile, namespace and start pose (a fleet file, "
                 "docs/distribution.md), instead of --robots N of one --robot profile")
      ->excludes(robots)
      ->excludes("--robot");
  cmd.add_option("--out", a->out, "DIR: fleet.json, fleet.txt, the robots' profiles and logs")->check(cli::writable_folder());
  cmd.add_option("--speed", a->speed, "X: the robots run at X times real time")->check(cli::positive_number())->capture_default_str();
  cmd.add_option("--domain", a->domain, "ID: the DDS domain (ROS_DOMAIN_ID)")->check(CLI::Range(0, 232))->capture_default_str();
  cmd.add_option("--lease-s", a->lease_s, "S: the robots' participant lease: a dead robot is seen silent after S")
      ->check(cli::positive_number())
      ->capture_default_str();
  cmd.add_option("--grace-s", a->grace_s,
                 "S: a silent robot keeps its units S more seconds before they go to the others (a network partition "
                 "shorter than that changes nothing); a robot back later is used again, keeping the unit it had in hand")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd.add_option("--timeout-s", a->timeout_s, "S: wall time after which the fleet gives up")->check(cli::positive_number())->capture_default_str();
  cmd.add_option("--seed", a->seed, "N: the simulators' seed (default: the world's)")->check(cli::whole_number());
  cmd.add_option("--kill-robot", a->kill_robot, "K: kill robot K (1..N) with SIGKILL, with --kill-after-s");
  cmd.add_option("--kill-after-s", a->kill_after_s, "S: that many seconds after robot K was given its first unit")
      ->check(CLI::NonNegativeNumber);
  cmd.add_flag("--shared-world", a->shared_world,
               "one world for the whole fleet: a tripodal sim-server --robots N steps it, each robot on hardware dds in "
               "lock-step, seeing the others in its laser (robot-robot contacts counted)");
  cmd.add_option("--sim-domain", a->sim_domain, "ID: with --shared-world, the DDS domain of the simulator (default --domain + 1)")
      ->check(CLI::Range(0, 232));
  cmd.add_flag("!--sim-system-network", a->sim_loopback,
               "with --shared-world, the simulator's link on Cyclone DDS's own network configuration, not loopback");
  cmd.add_flag("--system-network", a->system_network,
               "the fleet's and the robots' DDS on Cyclone DDS's own configuration (CYCLONEDDS_URI), not loopback: "
               "for robots on other hosts or network namespaces");
  cmd.add_option("--keys", a->keys,
                 "DIR: DDS Security on the fleet's domain with the keys tripodal fleet-keys made: the fleet tool as "
                 "--identity, each robot as its name (its profile's dds: security); the simulator's link stays unsecured")
      ->check(CLI::ExistingDirectory);
  cmd.add_option("--identity", a->identity, "NAME: with --keys, the fleet tool's identity in them")->capture_default_str();
  cmd.add_option("--launcher", a->launcher,
                 "\"CMD\": words put before each process's command line, {name} replaced by robotK or sim-server "
                 "(\"ip netns exec tfleet_{name}\": each in its own network namespace)");
  return [a](std::ostream& out, std::ostream& err) { return run(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "fleet", "run a fleet of robot processes on DDS sharing a task (clean the room 3211)", kDescription, kExitCodes,
                     &setup);

}  // namespace tripodal::tool
