// `tripodal sim-server --robot ROBOT.yaml --world WORLD.yaml`: the embedded simulator in a process
// of its own, serving the robot's base and laser over DDS (docs/distribution.md, "The simulator in
// another process") to a robot whose hardware is of type "dds" (`tripodal run --hardware dds`), in
// lock-step with the robot's clock. Built only with the dds area.
#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <csignal>
#include <deque>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <ostream>
#include <string>

#include "cli_tool.hpp"
#include "run_outputs.hpp"
#include "run_task.hpp"
#include "sim_server_shared.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/dds/dds_hardware.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::tool {
namespace {

using namespace cli;

constexpr int kNoRobot = 4;

constexpr std::string_view kDescription =
    "Runs the embedded simulator of a world with the base of a robot profile (its base\n"
    "controller's wheels) in a process of its own and serves it over DDS under --namespace: the\n"
    "laser on scan (sensor_msgs/LaserScan), the wheels on joint_states (sensor_msgs/JointState),\n"
    "and, in lock-step with the robot's clock, each step the robot asks for on tripodal/sim_step\n"
    "(tripodal_msgs/SimStep: advance to t with this cmd_vel) answered on tripodal/sim_state. The\n"
    "robot is the same profile with its hardware of type dds: `tripodal run --robot ROBOT.yaml\n"
    "--world WORLD.yaml --hardware dds --hardware-param namespace=NS ...`. Serves one robot until\n"
    "it leaves or the server is stopped (Ctrl-C, SIGTERM), then prints what the simulation measured:\n"
    "simulated time, distance, collisions and the world's events. With --realtime [SPEED] it runs on\n"
    "its own at SPEED times real time instead, driven by plain cmd_vel (geometry_msgs/Twist; none for\n"
    "0.5 s: the base stops) and publishing /clock (rosgraph_msgs/Clock), as ROS 2 tools expect,\n"
    "until stopped.";

constexpr std::string_view kExitCodes =
    "exit codes: 0 served until the robot left or the server was stopped, 1 bad profile/world, 2 bad\n"
    "            command line, 3 I/O error (a file, DDS), 4 no robot came within --wait-s.";

struct Args {
  std::filesystem::path robot, world;
  std::string ros_namespace;
  unsigned domain = 0;
  std::optional<std::uint64_t> seed;
  double lease_s = 2.0;
  double wait_s = 0.0;
  bool system_network = false;
  std::optional<int> robots;    // --robots N: one world for N lock-step robots
  std::filesystem::path fleet;  // --fleet FILE: one world for the robots it names
  double stall_s = 0.2;
  CLI::Option* realtime = nullptr;  // given at all (with or without SPEED)
  double realtime_speed = 0.0;      // 0: --realtime without SPEED
};

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_sim_server_stop_signal(int) {
  g_stop = 1;
}

// The step requests and the client's comings and goings, from Cyclone DDS threads.
struct Inbox {
  std::mutex mutex;
  std::optional<dds::msg::Twist> cmd_vel;  // --realtime: the latest, and when it came
  std::chrono::steady_clock::time_point cmd_vel_at;
  std::condition_variable cv;
  std::deque<dds::msg::SimStep> steps;
  bool had_client = false;
  bool client_left = false;
  std::string left_why;
};

std::vector<std::string> wheel_names(std::size_t n) {
  if (n == 2) return {"left_wheel", "right_wheel"};
  std::vector<std::string> names;
  for (std::size_t i = 1; i <= n; ++i) names.push_back("wheel_" + std::to_string(i));
  return names;
}

// --robots and --fleet: one world for lock-step robots (sim_server_shared.cpp).
int run_shared(const Args& a, std::ostream& out, std::ostream& err) {
  if (a.realtime->count() > 0) {
    err << "tripodal sim-server: --robots and --fleet serve lock-step robots; --realtime serves one\n";
    return kUsage;
  }
  return run_shared_world(SharedWorldArgs{.robot = a.robot,
                                          .world = a.world,
                                          .fleet = a.fleet,
                                          .robots = a.robots.value_or(0),
                                          .prefix = a.ros_namespace.empty() ? "robot" : a.ros_namespace,
                                          .domain = a.domain,
                                          .seed = a.seed,
                                          .lease_s = a.lease_s,
                                          .wait_s = a.wait_s,
                                          .stall_s = a.stall_s,
                                          .system_network = a.system_network},
                          out, err);
}

// The files to read and the namespace to serve under; kOk when they will do.
int check_single_args(const Args& a, std::ostream& err) {
  for (const auto& f : {a.robot, a.world}) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(f, ec)) {
      err << "tripodal sim-server: cannot read '" << f.string() << "'\n";
      return kIoError;
    }
  }
  if (!is_ros_namespace(a.ros_namespace)) {
    err << "tripodal sim-server: --namespace '" << a.ros_namespace
        << "' is not a ROS 2 namespace: names of letters, digits and '_', not starting with a digit, "
           "separated by '/'\n";
    return kUsage;
  }
  return kOk;
}

// What the robot sends: with --realtime its cmd_vel, else its step requests and its step writer's
// coming and going (its process ended or died).
struct Requests {
  std::optional<dds::Subscriber<dds::msg::SimStep>> steps;
  std::optional<dds::Subscriber<dds::msg::Twist>> cmd_vel;

  Requests(bool realtime, dds::Participant& participant, const dds::BaseTopics& topics, Inbox& inbox) {
    if (realtime) {
      cmd_vel.emplace(participant, topics.cmd_vel, dds::EndpointOptions{.kind = dds::TopicKind::command},
                      [&inbox](const dds::msg::Twist& t) {
                        std::lock_guard lock(inbox.mutex);
                        inbox.cmd_vel = t;
                        inbox.cmd_vel_at = std::chrono::steady_clock::now();
                      });
      return;
    }
    auto on_status = [&inbox](const dds::StatusEvent& e) {
      if (e.kind != dds::StatusKind::publication_matched && e.kind != dds::StatusKind::liveliness_lost)
        return;
      std::lock_guard lock(inbox.mutex);
      if (e.current_count > 0) {
        inbox.had_client = true;
      } else if (inbox.had_client && !inbox.client_left) {
        inbox.client_left = true;
        inbox.left_why =
            e.kind == dds::StatusKind::liveliness_lost ? "left or went silent (DDS liveliness lost)" : "left";
      }
      inbox.cv.notify_all();
    };
    steps.emplace(participant, topics.sim_step, dds::EndpointOptions{.kind = dds::TopicKind::state, .on_status = on_status},
                  [&inbox](const dds::msg::SimStep& s) {
                    std::lock_guard lock(inbox.mutex);
                    inbox.steps.push_back(s);
                    inbox.cv.notify_all();
                  });
  }
};

// The simulated robot as served: its sensors and state published after each step, lock-step or
// free-running.
class ServedRobot {
 public:
  ServedRobot(sim::Simulator& sim, dds::Participant& participant, const dds::BaseTopics& topics, bool realtime,
              const std::string& ros_namespace)
      : sim_(sim),
        clock_(realtime ? std::make_optional<dds::Publisher<dds::msg::Clock>>(participant, topics.clock,
                                                                              dds::EndpointOptions{.kind = dds::TopicKind::state})
                        : std::nullopt),
        scan_(participant, topics.scan, {.kind = dds::TopicKind::scan, .qos = reliable_scans()}),
        joints_(participant, topics.joint_states, {.kind = dds::TopicKind::state}),
        state_(participant, topics.sim_state, {.kind = dds::TopicKind::state}),
        buttons_(participant, ros_namespace),
        velocity_(sim.wheel_count()),
        position_(sim.wheel_count()) {
    js_.header.frame_id = "base_link";
    js_.name = wheel_names(sim.wheel_count());
    ls_.header.frame_id = "laser";
  }

  // Real time: a physics period at a time, paced to the wall clock, with the latest cmd_vel
  // (none within kCmdTimeout: the base stops, as a ROS 2 base driver does), until a signal.
  void run_realtime(const Args& a, Inbox& inbox);
  // Lock-step: serves the robot's step requests until it leaves, a signal, or none came within
  // --wait-s (kNoRobot); says why in `ended`.
  int run_lockstep(const Args& a, Inbox& inbox, std::chrono::steady_clock::time_point started, std::string& ended);
  [[nodiscard]] std::uint32_t last_step() const noexcept { return last_step_; }

 private:
  // Reliable scans: a lock-step robot counts on every one (ROS 2's best-effort readers match too).
  static dds::Qos reliable_scans() {
    dds::Qos qos = dds::qos_for(dds::TopicKind::scan, dds::Role::publisher);
    qos.reliability = dds::Reliability::reliable;
    return qos;
  }
  void publish(std::uint32_t step);
  void publish_scan();
  // Lock-step: the command over the step, the world advanced to its end, then what it gave.
  void serve(const dds::msg::SimStep& s) {
    sim_.command_twist(Twist2D{s.cmd_vel.linear.x, s.cmd_vel.linear.y, s.cmd_vel.angular.z});
    apply_joint_targets(s, sim_);
    buttons_.press_on(sim_);
    sim_.step_until(dds::tripodal_time(s.until));
    publish(s.step);
  }

  sim::Simulator& sim_;
  std::optional<dds::Publisher<dds::msg::Clock>> clock_;
  dds::Publisher<dds::msg::LaserScan> scan_;
  dds::Publisher<dds::msg::JointState> joints_;
  dds::Publisher<dds::msg::SimState> state_;
  ButtonInbox buttons_;
  dds::msg::JointState js_;
  dds::msg::LaserScan ls_;
  std::vector<double> velocity_, position_;
  std::uint32_t scans_ = 0, joint_states_ = 0, last_step_ = 0;
  std::size_t laser_seen_ = 0;
};

void ServedRobot::publish_scan() {
  const LaserResource& laser = sim_.laser();
  if (laser.sequence() == laser_seen_ || !laser.has_reading()) return;
  laser_seen_ = laser.sequence();
  const LaserScan& l = laser.latest();
  put_scan(l, ls_);
  scan_.publish(ls_);
  ++scans_;
}

// After a step: what the sensors gave, then the state (and with --realtime the clock).
void ServedRobot::publish(std::uint32_t step) {
  publish_scan();
  js_.header.stamp = dds::ros_time(sim_.now());
  if (sim_.read_wheel_states(velocity_, position_)) {
    js_.position = position_;
    js_.velocity = velocity_;
  } else {  // the odometry is dead: states without values, as the in-process read fails
    js_.position.clear();
    js_.velocity.clear();
  }
  joints_.publish(js_);
  ++joint_states_;
  last_step_ = step;
  const Pose2D& p = sim_.pose();
  dds::msg::SimState answer{dds::ros_time(sim_.now()),
                            p.x_m,
                            p.y_m,
                            p.theta_rad,
                            sim_.distance_m(),
                            last_step_,
                            scans_,
                            joint_states_,
                            static_cast<std::uint32_t>(sim_.collisions())};
  put_sensors(answer, sim_);
  state_.publish(answer);
  if (clock_) clock_->publish(dds::msg::Clock{dds::ros_time(sim_.now())});
}

void ServedRobot::run_realtime(const Args& a, Inbox& inbox) {
  constexpr auto kPeriod = std::chrono::milliseconds(10);
  constexpr auto kCmdTimeout = std::chrono::milliseconds(500);
  SteadyClock wall;
  sim::RealtimePacer pacer(wall, a.realtime_speed > 0.0 ? a.realtime_speed : 1.0);
  std::uint32_t periods = 0;
  publish(periods);
  while (g_stop == 0) {
    Twist2D command{};
    {
      std::lock_guard lock(inbox.mutex);
      if (inbox.cmd_vel && std::chrono::steady_clock::now() - inbox.cmd_vel_at < kCmdTimeout) {
        command = {inbox.cmd_vel->linear.x, inbox.cmd_vel->linear.y, inbox.cmd_vel->angular.z};
      }
    }
    sim_.command_twist(command);
    buttons_.press_on(sim_);
    sim_.step(kPeriod);
    publish(++periods);
    pacer.pace(sim_.now());
  }
}

int ServedRobot::run_lockstep(const Args& a, Inbox& inbox, std::chrono::steady_clock::time_point started, std::string& ended) {
  while (g_stop == 0) {
    std::unique_lock lock(inbox.mutex);
    // Wakes for a request or a departure, and every 100 ms to see a signal.
    inbox.cv.wait_for(lock, std::chrono::milliseconds(100), [&] { return !inbox.steps.empty() || inbox.client_left; });
    if (!inbox.steps.empty()) {
      const dds::msg::SimStep s = inbox.steps.front();
      inbox.steps.pop_front();
      lock.unlock();
      serve(s);
      continue;
    }
    if (inbox.client_left) {
      ended = "the robot " + inbox.left_why;
      return kOk;
    }
    if (!inbox.had_client && a.wait_s > 0.0 &&
        std::chrono::steady_clock::now() - started > std::chrono::duration<double>(a.wait_s)) {
      ended = "no robot came within " + app::fixed(a.wait_s, 1) + " s";
      return kNoRobot;
    }
  }
  return kOk;
}

// One robot's simulator served until it leaves or the server is stopped; the exit code.
int serve_one_robot(const Args& a, std::ostream& out) {
  const RobotProfile profile = load_robot_profile(a.robot);
  const ControllerConfig base = simulated_base(profile);
  sim::World world = sim::load_world(a.world);
  const std::uint64_t seed = a.seed.value_or(world.seed);
  sim::Simulator sim(std::move(world), base, seed);
  dds::Participant participant(served_participant(a.domain, a.system_network, a.lease_s));
  const dds::BaseTopics topics(a.ros_namespace);
  Inbox inbox;
  const bool realtime = a.realtime->count() > 0;
  const Requests requests(realtime, participant, topics, inbox);
  ServedRobot served(sim, participant, topics, realtime, a.ros_namespace);

  std::signal(SIGINT, on_sim_server_stop_signal);
  std::signal(SIGTERM, on_sim_server_stop_signal);
  out << "tripodal sim-server: robot " << profile.name << " (" << base.type << " base, " << sim.wheel_count()
      << " wheels), world " << a.world.string() << ", seed " << seed << "; domain " << a.domain << ", serving " << topics.scan
      << ", " << topics.joint_states << ", " << topics.sim_state
      << (realtime ? ", " + topics.clock + " at " + app::fixed(a.realtime_speed > 0.0 ? a.realtime_speed : 1.0, 1) +
                         " times real time; commands on " + topics.cmd_vel
                   : "; steps on " + topics.sim_step)
      << "\n";
  out.flush();

  const auto started = std::chrono::steady_clock::now();
  std::string ended = "stopped";
  int code = kOk;
  if (realtime)
    served.run_realtime(a, inbox);
  else
    code = served.run_lockstep(a, inbox, started, ended);
  out << "sim-server ended: " << ended << "; " << served.last_step() << (realtime ? " periods" : " steps served") << "; "
      << app::fixed(to_seconds(sim.now()), 2) << " s simulated; distance " << app::fixed(sim.distance_m(), 2) << " m; "
      << sim.collisions() << " collisions\n";
  for (const sim::SimEvent& e : sim.events()) {
    out << app::fixed(to_seconds(e.stamp), 3) << " s  simulator: " << sim::to_string(e.kind)
        << (e.detail.empty() ? "" : " " + e.detail) << '\n';
  }
  return code;
}

int run(const Args& a, std::ostream& out, std::ostream& err) {
  if (a.robot.empty() && a.fleet.empty()) {
    err << "tripodal sim-server: give the robot's profile (--robot ROBOT.yaml) or a fleet file (--fleet FILE)\n";
    return kUsage;
  }
  if (a.robots || !a.fleet.empty()) return run_shared(a, out, err);
  if (const int code = check_single_args(a, err); code != kOk) return code;
  try {
    return serve_one_robot(a, out);
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  } catch (const std::exception& e) {  // files, DDS
    err << "tripodal sim-server: " << e.what() << '\n';
    return kIoError;
  }
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  auto* robot = cmd.add_option("--robot", a->robot, "ROBOT.yaml: the robot profile whose base is simulated");
  cmd.add_option("--world", a->world, "WORLD.yaml: map, start pose, sensors and faults of the simulation")
      ->required();
  cmd.add_option("--namespace", a->ros_namespace,
                 "NS: the ROS 2 namespace of the topics (the robot's hardware parameter namespace)");
  cmd.add_option("--domain", a->domain, "ID: the DDS domain (ROS_DOMAIN_ID)")
      ->check(CLI::Range(0, 232))
      ->capture_default_str();
  cmd.add_option("--seed", a->seed, "N: the simulator's seed (default: the world's)")->check(cli::whole_number());
  cmd.add_option("--lease-s", a->lease_s, "S: the participant lease: a killed server is seen silent after S")
      ->check(cli::positive_number())
      ->capture_default_str();
  cmd.add_option("--wait-s", a->wait_s,
                 "S: give up (exit 4) when no robot came within S of wall time; 0: wait until stopped")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  // Without SPEED CLI11 hands the option an empty value, which leaves realtime_speed at 0.
  a->realtime = cmd.add_option("--realtime", a->realtime_speed,
                               "[SPEED]: free-running at SPEED times real time (default 1), driven by "
                               "cmd_vel, publishing clock "
                               "(for ROS 2 tools; no lock-step)")
                    ->expected(0, 1)
                    ->check(cli::positive_number() | CLI::IsMember({"", "true"}));
  cmd.add_option("--robots", a->robots,
                 "N: one world for N lock-step robots on namespaces NS1..NSN (NS: --namespace, default robot), each "
                 "seeing the others in its laser and stopped by them; robots come and go while it runs")
      ->check(CLI::Range(1, 16));
  cmd.add_option("--fleet", a->fleet,
                 "FILE: one world for the robots a fleet file names (name, profile, namespace, start pose each; "
                 "docs/distribution.md), in lock-step as with --robots")
      ->excludes(robot)
      ->excludes("--robots")
      ->excludes("--namespace");
  cmd.add_option("--stall-s", a->stall_s,
                 "S: with --robots, the wall time a round waits for a robot before stepping the others without it")
      ->check(cli::positive_number())
      ->capture_default_str();
  cmd.add_flag("--system-network", a->system_network,
               "Cyclone DDS's own network configuration instead of loopback only");
  return [a](std::ostream& out, std::ostream& err) { return run(*a, out, err); };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "sim-server",
                     "serve the simulator of a world to a robot over DDS (tripodal run --hardware dds)",
                     kDescription, kExitCodes, &setup);

}  // namespace tripodal::tool
