// `tripodal sim-server --robots N`: one world, several lock-step robots (sim_server_shared.hpp).
//
// The world is one Simulator per robot on the same map, each at its own start pose
// (a fleet file's, or fleet_starts' grid), coupled every round by the others' bodies (Simulator::set_other_bodies):
// a robot's laser sees the others, its footprint stops against them and its bumpers feel them. A
// round steps every robot that asked for its next step; it waits for the robots it expects for at
// most --stall-s of wall time, after which a robot that has not asked (paused, or busy starting)
// stands still in the world, not stepped, until it asks again. Robots come (their step writer
// matched: a fresh body at the slot's start pose) and go (it left or went silent: the body is
// removed) while the others run.
#include "sim_server_shared.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <csignal>
#include <deque>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "cli_tool.hpp"
#include "fleet_file.hpp"
#include "run_outputs.hpp"
#include "run_task.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/dds/dds_hardware.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::tool {

dds::ParticipantOptions served_participant(unsigned domain, bool system_network, double lease_s) {
  dds::ParticipantOptions po;
  po.domain_id = domain;
  po.network = system_network ? dds::Network::system : dds::Network::loopback;
  po.participant_lease = std::chrono::milliseconds(static_cast<std::int64_t>(lease_s * 1000.0));
  return po;
}

void put_scan(const LaserScan& l, dds::msg::LaserScan& m) {
  m.header.stamp = dds::ros_time(l.stamp);
  m.angle_min = static_cast<float>(l.angle_min_rad);
  m.angle_max = static_cast<float>(l.angle_max_rad);
  m.angle_increment = static_cast<float>(l.angle_increment_rad);
  m.time_increment = static_cast<float>(l.time_increment_s);
  m.scan_time = static_cast<float>(l.scan_time_s);
  m.range_min = static_cast<float>(l.range_min_m);
  m.range_max = static_cast<float>(l.range_max_m);
  m.ranges = l.ranges_m;
  m.intensities = l.intensities;
}

// The base the profile's loop controls. The controller types `tripodal run` knows (the same
// registration), so that the base of any profile `run` takes is simulated here.
ControllerConfig simulated_base(const RobotProfile& profile) {
  RobotPlugins plugins;
  app::register_tool_plugins(plugins, nullptr, profile, {});
  const std::optional<ControllerConfig> base = base_controller_config(profile, plugins.controllers);
  if (!base)
    throw ConfigError(profile.where,
                      "tripodal sim-server simulates the robot's base: the profile needs a loop with a controller");
  return *base;
}

namespace {

using namespace cli;

constexpr int kNoRobot = 4;

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_shared_server_stop_signal(int) {
  g_stop = 1;
}

std::vector<std::string> wheel_names(std::size_t n) {
  if (n == 2) return {"left_wheel", "right_wheel"};
  std::vector<std::string> names;
  for (std::size_t i = 1; i <= n; ++i) names.push_back("wheel_" + std::to_string(i));
  return names;
}

// What Cyclone DDS threads hand the serving thread, per robot slot.
struct SlotInbox {
  std::deque<dds::msg::SimStep> steps;
  bool connected = false;  // its step writer is matched
  std::string left_why;    // set when it left, until the serving thread took it
  bool left = false;
};

// One robot of the world as the serving thread sees it.
struct Slot {
  std::string ns;
  Pose2D start;
  const std::pair<std::string, ControllerConfig>* base = nullptr;  // its profile's name and base
  std::unique_ptr<dds::Publisher<dds::msg::LaserScan>> scan;
  std::unique_ptr<dds::Publisher<dds::msg::JointState>> joints;
  std::unique_ptr<dds::Publisher<dds::msg::SimState>> state;
  std::unique_ptr<dds::Subscriber<dds::msg::SimStep>> steps;
  std::unique_ptr<ButtonInbox> buttons;
  std::unique_ptr<sim::Simulator> sim;  // while a robot is here
  bool expected = false;                // answered: its next request is awaited this round
  std::uint32_t scans = 0, joint_states = 0, last_step = 0;
  std::size_t laser_seen = 0;
  std::uint64_t steps_served = 0;
  dds::msg::JointState js;
  dds::msg::LaserScan ls;
  std::vector<double> velocity, position;
};

}  // namespace

void put_sensors(dds::msg::SimState& state, sim::Simulator& sim) {
  const sim::SimRobotConfig& rc = sim.world().robot;
  state.sensors = 0;
  if (rc.gyro.enabled && sim.gyro().has_reading()) {
    state.sensors |= dds::msg::kSimGyro;
    state.gyro_yaw_rate = sim.gyro().latest().yaw_rate_rad_s;
    state.gyro_yaw = sim.gyro().latest().yaw_rad;
  }
  if (rc.bumpers.enabled && sim.bumpers().has_reading()) {
    state.sensors |= dds::msg::kSimBumpers;
    state.bumpers_pressed = sim.bumpers().latest().pressed_mask;
    state.bumper_count = sim.bumpers().latest().count;
  }
  if (rc.cliff.enabled && sim.cliff().has_reading()) {
    state.sensors |= dds::msg::kSimCliff;
    state.cliff = sim.cliff().latest().cliff;
  }
  if (rc.battery.enabled && sim.battery().has_reading()) {
    state.sensors |= dds::msg::kSimBattery;
    const BatteryReading& b = sim.battery().latest();
    state.battery_voltage = b.voltage_v;
    state.battery_current = b.current_a;
    state.battery_percentage = b.percentage;
    state.battery_charging = b.charging;
  }
  const std::vector<sim::JointConfig>& joints = rc.joints;
  state.joint_names.resize(joints.size());
  state.joint_position.resize(joints.size());
  state.joint_velocity.resize(joints.size());
  state.joint_target.resize(joints.size());
  for (std::size_t i = 0; i < joints.size(); ++i) {
    const sim::JointState& j = sim.joints()[i];
    state.joint_names[i] = joints[i].name;
    state.joint_position[i] = j.position_rad;
    state.joint_velocity[i] = j.velocity_rad_s;
    state.joint_target[i] = j.target_rad;
  }
  state.button_presses = sim.take_button_presses();
}

void apply_joint_targets(const dds::msg::SimStep& step, sim::Simulator& sim) {
  if (step.joint_targets.size() != sim.world().robot.joints.size()) return;
  for (std::size_t i = 0; i < step.joint_targets.size(); ++i) {
    if (!std::isnan(step.joint_targets[i])) (void)sim.command_joint(i, step.joint_targets[i]);
  }
}

ButtonInbox::ButtonInbox(dds::Participant& participant, const std::string& ns)
    : subscriber_(std::make_unique<dds::Subscriber<dds::msg::String>>(participant, dds::ros_topic("tripodal/press_button", ns),
                                                                      dds::EndpointOptions{.kind = dds::TopicKind::event},
                                                                      [this](const dds::msg::String& m) {
                                                                        const std::lock_guard lock(mutex_);
                                                                        names_.push_back(m.data);
                                                                      })) {}

// The subscriber first: its callback uses the members.
ButtonInbox::~ButtonInbox() {
  subscriber_.reset();
}

void ButtonInbox::press_on(sim::Simulator& sim) {
  std::vector<std::string> names;
  {
    const std::lock_guard lock(mutex_);
    names.swap(names_);
  }
  for (const std::string& n : names) (void)sim.press_button(n);
}

namespace {

// The robots' inboxes and what guards them: Cyclone DDS threads fill them, the serving thread
// empties them.
struct Inboxes {
  explicit Inboxes(std::size_t n) : slots(n) {}
  std::mutex mutex;
  std::condition_variable cv;
  std::vector<SlotInbox> slots;
};

// What the serving thread took from the inboxes for one round, robot by robot.
struct Round {
  std::vector<std::optional<dds::msg::SimStep>> steps;  // the step it asked for
  std::vector<std::string> left;                        // why it left (empty: it did not)
  std::vector<char> joined;                             // it asked its first step
};

// The files to read, and the namespace the robots are numbered in; kOk when they will do.
int check_shared_args(const SharedWorldArgs& a, std::ostream& err) {
  for (const auto& f : {a.fleet.empty() ? a.robot : a.fleet, a.world}) {
    std::error_code ec;
    if (!std::filesystem::is_regular_file(f, ec)) {
      err << "tripodal sim-server: cannot read '" << f.string() << "'\n";
      return kIoError;
    }
  }
  if (a.fleet.empty() && !is_ros_namespace(a.prefix + "1")) {
    err << "tripodal sim-server: --namespace '" << a.prefix << "' with --robots: '" << a.prefix
        << "1' is not a ROS 2 namespace: names of letters, digits and '_', not starting with a digit, separated by '/'\n";
    return kUsage;
  }
  return kOk;
}

using Bases = std::map<std::filesystem::path, std::pair<std::string, ControllerConfig>>;

// Each robot's base is its own profile's (a fleet file may mix an omni PSR-2 and a differential
// robot); profiles read once each.
Bases load_bases(const std::vector<FleetMember>& members) {
  Bases bases;
  for (const FleetMember& m : members) {
    if (bases.count(m.profile) != 0) continue;
    const RobotProfile profile = load_robot_profile(m.profile);
    bases.emplace(m.profile, std::make_pair(profile.name, simulated_base(profile)));
  }
  return bases;
}

// Slot k's topics in its namespace: its sensors published, its step requests and its step
// writer's coming and going delivered into inbox k.
void open_slot(Slot& s, std::size_t k, dds::Participant& participant, Inboxes& inboxes) {
  dds::Qos scan_qos = dds::qos_for(dds::TopicKind::scan, dds::Role::publisher);
  scan_qos.reliability = dds::Reliability::reliable;  // a lock-step robot counts on every scan
  const dds::BaseTopics topics(s.ns);
  s.scan = std::make_unique<dds::Publisher<dds::msg::LaserScan>>(
      participant, topics.scan, dds::EndpointOptions{.kind = dds::TopicKind::scan, .qos = scan_qos});
  s.joints = std::make_unique<dds::Publisher<dds::msg::JointState>>(participant, topics.joint_states,
                                                                    dds::EndpointOptions{.kind = dds::TopicKind::state});
  s.state = std::make_unique<dds::Publisher<dds::msg::SimState>>(participant, topics.sim_state,
                                                                 dds::EndpointOptions{.kind = dds::TopicKind::state});
  s.buttons = std::make_unique<ButtonInbox>(participant, s.ns);
  auto on_status = [&inboxes, k](const dds::StatusEvent& e) {
    if (e.kind != dds::StatusKind::publication_matched && e.kind != dds::StatusKind::liveliness_lost) return;
    const std::lock_guard lock(inboxes.mutex);
    SlotInbox& in = inboxes.slots[k];
    if (e.current_count > 0) {
      in.connected = true;
    } else if (in.connected) {
      in.connected = false;
      in.left = true;
      in.left_why = e.kind == dds::StatusKind::liveliness_lost ? "left or went silent (DDS liveliness lost)" : "left";
    }
    inboxes.cv.notify_all();
  };
  s.steps = std::make_unique<dds::Subscriber<dds::msg::SimStep>>(
      participant, topics.sim_step, dds::EndpointOptions{.kind = dds::TopicKind::state, .on_status = on_status},
      [&inboxes, k](const dds::msg::SimStep& step) {
        const std::lock_guard lock(inboxes.mutex);
        inboxes.slots[k].steps.push_back(step);
        inboxes.cv.notify_all();
      });
}

void print_world(std::ostream& out, const SharedWorldArgs& a, const std::vector<Slot>& slots, std::uint64_t seed) {
  out << "tripodal sim-server: one world for " << slots.size() << " robots";
  if (a.fleet.empty()) out << " (" << slots.front().base->first << ", " << slots.front().base->second.type << " base)";
  out << ", world " << a.world.string() << ", seed " << seed << "; domain " << a.domain << ", namespaces " << slots.front().ns
      << " to " << slots.back().ns << "\n";
  for (const Slot& s : slots) {
    out << "  " << s.ns << " starts at (" << app::fixed(s.start.x_m, 2) << ", " << app::fixed(s.start.y_m, 2) << ", "
        << app::fixed(s.start.theta_rad, 3) << ")";
    if (!a.fleet.empty()) out << ": " << s.base->first << ", " << s.base->second.type << " base";
    out << "\n";
  }
  out.flush();
}

// Waits for a round's requests: the round starts with the first request and waits for every
// expected robot, at most `stall`. Takes one request per robot, and who left or joined.
void gather_round(Inboxes& inboxes, const std::vector<Slot>& slots, std::chrono::steady_clock::duration stall, Round& r) {
  const std::size_t n = slots.size();
  std::vector<SlotInbox>& inbox = inboxes.slots;
  std::unique_lock lock(inboxes.mutex);
  inboxes.cv.wait_for(lock, std::chrono::milliseconds(100), [&] {
    return std::any_of(inbox.begin(), inbox.end(), [](const SlotInbox& in) { return !in.steps.empty() || in.left; });
  });
  const auto round_start = std::chrono::steady_clock::now();
  auto complete = [&] {
    for (std::size_t k = 0; k < n; ++k) {
      if (inbox[k].left) return true;
      if (slots[k].expected && inbox[k].steps.empty()) return false;
    }
    return true;
  };
  if (std::any_of(inbox.begin(), inbox.end(), [](const SlotInbox& in) { return !in.steps.empty(); })) {
    inboxes.cv.wait_until(lock, round_start + stall, complete);
  }
  for (std::size_t k = 0; k < n; ++k) {
    SlotInbox& in = inbox[k];
    r.steps[k].reset();
    if (!in.steps.empty()) {
      r.steps[k] = in.steps.front();
      in.steps.pop_front();
    }
    if (in.left) {
      r.left[k] = in.left_why;
      in.left = false;
      in.steps.clear();
      r.steps[k].reset();
    } else if (r.steps[k] && !slots[k].sim) {
      r.joined[k] = 1;
    }
  }
}

// A robot's step writer is matched, or its requests wait.
bool anyone_connected(Inboxes& inboxes) {
  const std::lock_guard lock(inboxes.mutex);
  return std::any_of(inboxes.slots.begin(), inboxes.slots.end(),
                     [](const SlotInbox& in) { return in.connected || !in.steps.empty(); });
}

// The world as the serving thread runs it: the robots' bodies come, step and go; the figures of
// the whole run.
class SharedWorld {
 public:
  SharedWorld(const sim::World& world, std::uint64_t seed, std::vector<Slot>& slots, std::ostream& out)
      : world_(world), seed_(seed), slots_(slots), out_(out), began_(std::chrono::steady_clock::now()) {
    others_.reserve(slots.size());
  }

  // Rounds until a signal, every robot gone, or none came within `a.wait_s`; the exit code.
  int serve_rounds(const SharedWorldArgs& a, Inboxes& inboxes);
  void depart(Slot& s, const std::string& why);
  void print_end(std::ostream& out) const {
    out << "sim-server ended: " << ended_ << "; " << rounds_ << " rounds; robot-robot contacts: " << contacts_
        << "; closest approach between robots: "
        << (std::isfinite(min_clearance_m_) ? app::fixed(min_clearance_m_, 3) + " m" : std::string("none (never two robots)"))
        << "\n";
  }

 private:
  void arrive(Slot& s);
  void serve(Slot& s, const dds::msg::SimStep& step);
  void publish_scan(Slot& s);
  void publish_state(Slot& s);
  [[nodiscard]] std::string elapsed() const {
    return app::fixed(std::chrono::duration<double>(std::chrono::steady_clock::now() - began_).count(), 1) + " s  ";
  }

  const sim::World& world_;
  std::uint64_t seed_;
  std::vector<Slot>& slots_;
  std::ostream& out_;
  std::chrono::steady_clock::time_point began_;
  std::uint64_t contacts_ = 0, rounds_ = 0;
  double min_clearance_m_ = std::numeric_limits<double>::infinity();
  bool any_came_ = false;
  std::string ended_ = "stopped";
  std::vector<sim::OtherBody> others_;
};

// A robot that leaves: its figures, its body out of the world.
void SharedWorld::depart(Slot& s, const std::string& why) {
  if (!s.sim) return;
  contacts_ += s.sim->robot_collisions();
  min_clearance_m_ = std::min(min_clearance_m_, s.sim->min_robot_clearance_m());
  out_ << elapsed() << s.ns << " " << why << ": " << s.steps_served << " steps, " << app::fixed(to_seconds(s.sim->now()), 2)
       << " s simulated, distance " << app::fixed(s.sim->distance_m(), 2) << " m, " << s.sim->collisions() << " collisions ("
       << s.sim->robot_collisions() << " with robots)\n";
  for (const sim::SimEvent& e : s.sim->events()) {
    out_ << "    " << s.ns << " " << app::fixed(to_seconds(e.stamp), 3) << " s  simulator: " << sim::to_string(e.kind)
         << (e.detail.empty() ? "" : " " + e.detail) << '\n';
  }
  out_.flush();
  s.sim.reset();
  s.expected = false;
}

// A robot that asks its first step: a fresh body at its slot's start pose.
void SharedWorld::arrive(Slot& s) {
  s.sim = std::make_unique<sim::Simulator>(world_, s.base->second, seed_);
  if (!s.sim->set_pose(s.start)) throw std::runtime_error(s.ns + "'s start pose is not free");
  const std::size_t w = s.sim->wheel_count();
  s.js = {};
  s.js.header.frame_id = "base_link";
  s.js.name = wheel_names(w);
  s.ls = {};
  s.ls.header.frame_id = "laser";
  s.velocity.assign(w, 0.0);
  s.position.assign(w, 0.0);
  s.scans = s.joint_states = s.last_step = 0;
  s.laser_seen = 0;
  s.steps_served = 0;
  any_came_ = true;
  out_ << elapsed() << s.ns << " joined at (" << app::fixed(s.start.x_m, 2) << ", " << app::fixed(s.start.y_m, 2) << ")\n";
  out_.flush();
}

// Its laser's scan when there is a new one.
void SharedWorld::publish_scan(Slot& s) {
  const LaserResource& laser = s.sim->laser();
  if (laser.sequence() == s.laser_seen || !laser.has_reading()) return;
  s.laser_seen = laser.sequence();
  const LaserScan& l = laser.latest();
  put_scan(l, s.ls);
  s.scan->publish(s.ls);
  ++s.scans;
}

// Its wheels' joint states and the simulator's state (the true pose, the sensors).
void SharedWorld::publish_state(Slot& s) {
  sim::Simulator& sim = *s.sim;
  s.js.header.stamp = dds::ros_time(sim.now());
  if (sim.read_wheel_states(s.velocity, s.position)) {
    s.js.position = s.position;
    s.js.velocity = s.velocity;
  } else {
    s.js.position.clear();
    s.js.velocity.clear();
  }
  s.joints->publish(s.js);
  ++s.joint_states;
  const Pose2D& p = sim.pose();
  dds::msg::SimState state{dds::ros_time(sim.now()),
                           p.x_m,
                           p.y_m,
                           p.theta_rad,
                           sim.distance_m(),
                           s.last_step,
                           s.scans,
                           s.joint_states,
                           static_cast<std::uint32_t>(sim.collisions())};
  put_sensors(state, sim);
  s.state->publish(state);
}

// One robot's step, the others' bodies where they are now.
void SharedWorld::serve(Slot& s, const dds::msg::SimStep& step) {
  sim::Simulator& sim = *s.sim;
  others_.clear();
  for (std::size_t j = 0; j < slots_.size(); ++j) {
    if (&slots_[j] == &s || !slots_[j].sim) continue;
    const Pose2D& p = slots_[j].sim->pose();
    others_.push_back({{p.x_m, p.y_m}, slots_[j].sim->world().robot.radius_m, static_cast<std::uint32_t>(j + 1)});
  }
  sim.set_other_bodies(others_);
  sim.command_twist(Twist2D{step.cmd_vel.linear.x, step.cmd_vel.linear.y, step.cmd_vel.angular.z});
  apply_joint_targets(step, sim);
  s.buttons->press_on(sim);
  sim.step_until(dds::tripodal_time(step.until));
  publish_scan(s);
  s.last_step = step.step;
  ++s.steps_served;
  publish_state(s);
  s.expected = true;
}

int SharedWorld::serve_rounds(const SharedWorldArgs& a, Inboxes& inboxes) {
  const std::size_t n = slots_.size();
  const auto stall = std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(a.stall_s));
  Round r;
  r.steps.resize(n);
  while (g_stop == 0) {
    r.left.assign(n, std::string());
    r.joined.assign(n, 0);
    gather_round(inboxes, slots_, stall, r);
    for (std::size_t k = 0; k < n; ++k) {
      if (!r.left[k].empty()) depart(slots_[k], r.left[k]);
      if (r.joined[k] != 0) arrive(slots_[k]);
    }
    bool stepped = false;
    for (std::size_t k = 0; k < n; ++k) {
      Slot& s = slots_[k];
      if (r.steps[k] && s.sim) {
        serve(s, *r.steps[k]);
        stepped = true;
      } else if (s.expected) {
        s.expected = false;  // stalled: it stands still until it asks again
      }
    }
    if (stepped) ++rounds_;
    const bool anyone = std::any_of(slots_.begin(), slots_.end(), [](const Slot& s) { return s.sim != nullptr; });
    const bool connected = anyone_connected(inboxes);
    if (any_came_ && !anyone && !connected) {
      ended_ = "every robot left";
      return kOk;
    }
    if (!any_came_ && !connected && a.wait_s > 0.0 &&
        std::chrono::steady_clock::now() - began_ > std::chrono::duration<double>(a.wait_s)) {
      ended_ = "no robot came within " + app::fixed(a.wait_s, 1) + " s";
      return kNoRobot;
    }
  }
  return kOk;
}

}  // namespace

int run_shared_world(const SharedWorldArgs& a, std::ostream& out, std::ostream& err) {
  if (const int code = check_shared_args(a, err); code != kOk) return code;
  try {
    const std::vector<FleetMember> members =
        a.fleet.empty() ? numbered_fleet(a.robots, a.robot, a.prefix) : load_fleet_file(a.fleet);
    const Bases bases = load_bases(members);
    const sim::World world = sim::load_world(a.world);
    const std::uint64_t seed = a.seed.value_or(world.seed);
    const std::size_t n = members.size();
    const std::vector<Pose2D> starts = fleet_starts(world, members);

    dds::Participant participant(served_participant(a.domain, a.system_network, a.lease_s));
    Inboxes inboxes(n);
    std::vector<Slot> slots(n);
    for (std::size_t k = 0; k < n; ++k) {
      Slot& s = slots[k];
      s.ns = members[k].ns;
      s.start = starts[k];
      s.base = &bases.at(members[k].profile);
      open_slot(s, k, participant, inboxes);
    }

    std::signal(SIGINT, on_shared_server_stop_signal);
    std::signal(SIGTERM, on_shared_server_stop_signal);
    print_world(out, a, slots, seed);
    SharedWorld shared(world, seed, slots, out);
    const int code = shared.serve_rounds(a, inboxes);
    for (Slot& s : slots) shared.depart(s, "was here at the end");
    shared.print_end(out);
    return code;
  } catch (const ConfigError& e) {
    err << e.what() << '\n';
    return kBadInput;
  } catch (const std::exception& e) {
    err << "tripodal sim-server: " << e.what() << '\n';
    return kIoError;
  }
}

}  // namespace tripodal::tool
