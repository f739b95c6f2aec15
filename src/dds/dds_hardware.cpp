// The hardware type "dds": a base and its laser behind DDS, in lock-step with a simulator or not.
#include "tripodal/dds/dds_hardware.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <utility>

#include "tripodal/robot/robot_profile.hpp"

namespace tripodal::dds {

BaseTopics::BaseTopics(const std::string& ns)
    : cmd_vel(ros_topic("cmd_vel", ns)),
      joint_states(ros_topic("joint_states", ns)),
      scan(ros_topic("scan", ns)),
      clock(ros_topic("clock")),  // ROS 2 nodes follow /clock, whatever their namespace
      sim_step(ros_topic("tripodal/sim_step", ns)),
      sim_state(ros_topic("tripodal/sim_state", ns)) {}

const ModuleManifest& DdsHardware::static_manifest() {
  static const ModuleManifest m = hardware_manifest(
      "dds",
      "a base and its laser behind DDS (ROS 2 topics cmd_vel, joint_states, scan): tripodal sim-server or a "
      "base driver",
      // What it may give, as the simulator's type lists it: the sensors beyond the laser are those
      // its parameter `sensors` names (a profile's BatteryMonitor reads "battery" from it), the
      // joints those of the world it is given (BhNeckGesture reads "joint_state").
      {"laser_scan", "yaw_rate", "bumpers", "cliff", "battery", "joint_state"},
      {parameter::text("namespace", "", "ROS 2 namespace of the base's topics (the sim-server's --namespace); empty: none"),
       parameter::number("domain_id", 0.0, "", "DDS domain (ROS_DOMAIN_ID)", 0.0, 232.0),
       parameter::flag("loopback", true, "stay on 127.0.0.1 (false: Cyclone DDS's own network configuration)"),
       parameter::flag("lock_step", true,
                       "the base is a simulator (tripodal sim-server) that advances with the robot's clock; "
                       "false: a real "
                       "base on its own time"),
       parameter::number("step_timeout_s", 5.0, "s", "lock-step: the longest wait for the simulator's answer (wall time)", 0.001,
                         3600.0),
       parameter::number("connect_timeout_s", 10.0, "s", "lock-step: the longest wait for the simulator at the start (wall time)",
                         0.001, 3600.0),
       parameter::text("sensors", "",
                       "the simulator's sensors the robot has besides the laser, comma-separated: gyro, bumpers, "
                       "cliff, battery (resources of those names; empty: none)")});
  return m;
}

namespace {

// Checks what the manifest cannot: the base, and the namespace as ROS 2 would take it.
const ControllerConfig& base_of(const HardwareConfig& c) {
  Diagnostics d;
  if (c.base == nullptr)
    d.error(c.where, "hardware '" + c.type + "' needs the robot's base controller (its wheel geometry)");
  std::string sensors = c.parameters.string("sensors");
  std::replace(sensors.begin(), sensors.end(), ',', ' ');
  std::istringstream words(sensors);
  for (std::string w; words >> w;) {
    if (w != "gyro" && w != "bumpers" && w != "cliff" && w != "battery") {
      d.error(c.where,
              "hardware '" + c.type + "' sensors: unknown sensor '" + w + "'; expected some of gyro, bumpers, cliff, battery");
    }
  }
  const std::string& ns = c.parameters.string("namespace");
  if (!is_ros_namespace(ns)) {
    d.error(c.where, "hardware '" + c.type + "' namespace '" + ns +
                         "' is not a ROS 2 namespace: names of letters, digits and '_', not starting with a "
                         "digit, separated by '/'");
  }
  if (d.has_errors()) throw ConfigError(std::move(d));
  return *c.base;
}

SimTruth truth_of(const msg::SimState& s) {
  return {tripodal_time(s.stamp), Pose2D{s.x, s.y, s.theta}, s.distance, s.collisions};
}

std::chrono::milliseconds millis(double seconds) {
  return std::chrono::milliseconds(static_cast<std::int64_t>(std::ceil(seconds * 1000.0)));
}

}  // namespace

DdsHardware::DdsHardware(const HardwareConfig& config, std::vector<DdsJoint> joints)
    : kinematics_(base_of(config)),
      topics_(config.parameters.string("namespace")),
      lock_step_(config.parameters.boolean("lock_step")),
      step_timeout_(millis(config.parameters.number("step_timeout_s"))),
      connect_timeout_(millis(config.parameters.number("connect_timeout_s"))),
      command_(kinematics_.wheel_count(), 0.0),
      wheel_position_(kinematics_.wheel_count(), 0.0),
      wheel_velocity_(kinematics_.wheel_count(), 0.0) {
  ParticipantOptions po;
  po.domain_id = static_cast<std::uint32_t>(config.parameters.number("domain_id"));
  if (!config.parameters.boolean("loopback")) po.network = Network::system;
  participant_ = std::make_unique<Participant>(po);

  DdsLaserOptions lo;
  lo.binding = {topics_.scan, po};
  lo.max_age = std::chrono::milliseconds(500);
  lo.lock_step = lock_step_;
  lo.on_scan = [this] {
    std::lock_guard lock(mutex_);  // a waiter checks the count under the lock: no lost wake-up
    cv_.notify_all();
  };
  laser_ = std::make_unique<DdsLaserResource>("laser", std::move(lo));
  const std::string& sensors = config.parameters.string("sensors");
  const auto named = [&](std::string_view n) {
    std::string padded = "," + sensors + ",";
    padded.erase(std::remove(padded.begin(), padded.end(), ' '), padded.end());
    return padded.find("," + std::string(n) + ",") != std::string::npos;
  };
  const Duration sensor_age = std::chrono::milliseconds(500);  // as the laser's
  if (named("gyro")) gyro_ = std::make_unique<GyroResource>("gyro", sensor_age);
  if (named("bumpers")) bumpers_ = std::make_unique<BumperResource>("bumpers", sensor_age);
  if (named("cliff")) cliff_ = std::make_unique<InfraredResource>("cliff", sensor_age);
  if (named("battery")) battery_ = std::make_unique<BatteryResource>("battery", sensor_age);
  // The joints: a position channel each, held where it was last sent (a servo stays), from where
  // it starts, as the simulator's own hardware exports them.
  joints_ = std::move(joints);
  for (const DdsJoint& j : joints_) {
    if (!(j.min_rad < j.max_rad) || !(j.rate_hz > 0.0)) {
      throw ConfigError(config.where,
                        "hardware '" + config.type + "' joint '" + j.name + "': expected min_rad < max_rad and rate_hz > 0");
    }
    joint_resources_.push_back(std::make_unique<JointResource>(j.name, 3 * from_seconds(1.0 / j.rate_hz)));
    const double start = std::clamp(j.initial_rad, j.min_rad, j.max_rad);
    export_channel(ChannelSpec{j.name, ChannelType::joint_position, ChannelValue::of(start), true, Duration{0}, j.min_rad,
                               j.max_rad, "rad", "the position joint " + j.name + " goes to"});
    joint_sent_.push_back(start);
  }

  // A simulator (or base driver) that goes away is the hardware's fault.
  auto on_status = [this](const StatusEvent& e) {
    const bool gone = (e.kind == StatusKind::liveliness_lost || e.kind == StatusKind::publication_matched) &&
                      e.current_count == 0 && e.total_count > 0;
    if (!gone) return;
    std::lock_guard lock(mutex_);
    if (simulator_silent_) return;
    simulator_silent_ = true;
    silent_why_ = "the publisher of " + e.topic + " is gone (DDS " + std::string(to_string(e.kind)) +
                  ", no publisher left: its process died, its lease ran out or it stopped)";
    cv_.notify_all();
  };
  joint_states_ = std::make_unique<Subscriber<msg::JointState>>(
      *participant_, topics_.joint_states,
      EndpointOptions{.kind = TopicKind::state, .on_status = lock_step_ ? StatusCallback{} : on_status},
      [this](const msg::JointState& m) {
        std::lock_guard lock(mutex_);
        ++joint_states_received_;
        if (m.position.size() == wheel_position_.size() && m.velocity.size() == wheel_velocity_.size()) {
          std::copy(m.position.begin(), m.position.end(), wheel_position_.begin());
          std::copy(m.velocity.begin(), m.velocity.end(), wheel_velocity_.begin());
          has_wheels_ = true;
        } else {
          has_wheels_ = false;  // no values (a dead encoder) or another base: the read fails
        }
        cv_.notify_all();
      });
  cmd_vel_ = std::make_unique<Publisher<msg::Twist>>(*participant_, topics_.cmd_vel,
                                                     EndpointOptions{.kind = TopicKind::command});
  if (lock_step_) {
    // One request at a time, each answered before the next: keep the last one only.
    Qos step_qos = qos_for(TopicKind::state, Role::publisher);
    step_qos.depth = 1;
    sim_step_ = std::make_unique<Publisher<msg::SimStep>>(
        *participant_, topics_.sim_step, EndpointOptions{.kind = TopicKind::state, .qos = step_qos});
  }
  // Without lock-step, a free-running sim-server's state is the run's ground truth all the same (a
  // real base has none).
  sim_state_ = std::make_unique<Subscriber<msg::SimState>>(
      *participant_, topics_.sim_state,
      EndpointOptions{.kind = TopicKind::state, .on_status = lock_step_ ? on_status : StatusCallback{}},
      [this](const msg::SimState& s) {
        std::lock_guard lock(mutex_);
        state_ = s;
        cv_.notify_all();
      });
}

// The endpoints go first: their callbacks use the members below them.
DdsHardware::~DdsHardware() {
  sim_state_.reset();
  joint_states_.reset();
  laser_.reset();
}

void DdsHardware::on_add_resources(ResourceTable& table) {
  table.add(*laser_);
  if (gyro_) table.add(*gyro_);
  if (bumpers_) table.add(*bumpers_);
  if (cliff_) table.add(*cliff_);
  if (battery_) table.add(*battery_);
  for (auto& j : joint_resources_) table.add(*j);
}

// The answer's sensors into the resources the profile asked for; one the simulator's world does
// not give is the hardware's fault (a profile that counts on bumpers must not run without them).
void DdsHardware::take_sensors(const msg::SimState& s) {
  const Time t = tripodal_time(s.stamp);
  const auto missing = [&](const char* name) {
    fail(std::string("the simulator gives no ") + name + " (its world has none); the hardware's sensors parameter names it");
  };
  if (gyro_) {
    if ((s.sensors & msg::kSimGyro) == 0) return missing("gyro");
    GyroReading& r = gyro_->edit();
    r.stamp = t;
    r.yaw_rate_rad_s = s.gyro_yaw_rate;
    r.yaw_rad = s.gyro_yaw;
    gyro_->commit();
  }
  if (bumpers_) {
    if ((s.sensors & msg::kSimBumpers) == 0) return missing("bumpers");
    BumperReading& r = bumpers_->edit();
    r.stamp = t;
    r.count = s.bumper_count;
    r.pressed_mask = s.bumpers_pressed;
    bumpers_->commit();
  }
  if (cliff_) {
    if ((s.sensors & msg::kSimCliff) == 0) return missing("cliff sensors");
    InfraredReading& r = cliff_->edit();
    r.stamp = t;
    r.cliff.assign(s.cliff.begin(), s.cliff.end());  // within the capacity after the first step
    cliff_->commit();
  }
  if (battery_) {
    if ((s.sensors & msg::kSimBattery) == 0) return missing("battery");
    BatteryReading& r = battery_->edit();
    r = {t, s.battery_voltage, s.battery_current, s.battery_percentage, s.battery_charging};
    battery_->commit();
  }
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const DdsJoint& j = joints_[i];
    if (i >= s.joint_names.size() || s.joint_names[i] != j.name || i >= s.joint_position.size() || i >= s.joint_velocity.size() ||
        i >= s.joint_target.size()) {
      return fail("the simulator gives no joint '" + j.name + "' as its joint " + std::to_string(i + 1) +
                  " (its world's joints are another list)");
    }
    joint_resources_[i]->edit() = {t, s.joint_position[i], s.joint_velocity[i], s.joint_target[i], j.min_rad, j.max_rad};
    joint_resources_[i]->commit();
  }
  presses_.insert(presses_.end(), s.button_presses.begin(), s.button_presses.end());
}

// The joints' targets when a command channel changed since the last step (the simulator keeps
// them otherwise), in the world's joint order, which the simulator's is (take_sensors checks the
// names); empty: nothing to send.
std::vector<double> DdsHardware::joint_targets() {
  if (joints_.empty()) return {};
  const CommandChannels& commands = command_channels();
  bool changed = false;
  for (std::size_t i = 0; i < joints_.size(); ++i) {
    const double v = commands.value(i).number;
    if (v != joint_sent_[i]) changed = true;
    joint_sent_[i] = v;
  }
  return changed ? joint_sent_ : std::vector<double>{};
}

Twist2D DdsHardware::commanded_twist() const noexcept {
  return kinematics_.forward(command_);
}

bool DdsHardware::write_wheel_velocities(std::span<const double> wheel_rad_s) noexcept {
  if (wheel_rad_s.size() != command_.size() || lost_) return false;
  for (const double w : wheel_rad_s) {
    if (!std::isfinite(w)) return false;
  }
  std::copy(wheel_rad_s.begin(), wheel_rad_s.end(), command_.begin());
  const Twist2D t = commanded_twist();
  try {
    // For ROS 2 tools and a real base; a lock-step simulator takes the command with the step.
    cmd_vel_->publish({{t.vx_m_s, t.vy_m_s, 0.0}, {0.0, 0.0, t.wz_rad_s}});
  } catch (...) {
    return false;  // Cyclone refused the write (out of resources, deleted entity)
  }
  return true;
}

bool DdsHardware::read_wheel_states(std::span<double> velocity_rad_s,
                                    std::span<double> position_rad) noexcept {
  if (velocity_rad_s.size() != command_.size() || position_rad.size() != command_.size() || lost_)
    return false;
  std::lock_guard lock(mutex_);
  if (!has_wheels_) return false;
  std::copy(wheel_velocity_.begin(), wheel_velocity_.end(), velocity_rad_s.begin());
  std::copy(wheel_position_.begin(), wheel_position_.end(), position_rad.begin());
  return true;
}

void DdsHardware::fail(std::string why) noexcept {
  if (lost_) return;
  lost_ = true;
  try {
    faults_.report(std::move(why));
  } catch (...) {  // out of memory: the link is down all the same
  }
}

// Waits for the simulator's step topic and state topic to match both ways.
bool DdsHardware::connect() noexcept {
  try {
    const auto until = std::chrono::steady_clock::now() + connect_timeout_;
    const bool ok = sim_step_->wait_for_subscribers(1, connect_timeout_) &&
                    sim_state_->wait_for_publishers(1, std::chrono::duration_cast<std::chrono::milliseconds>(
                                                           until - std::chrono::steady_clock::now())) &&
                    laser_->matched_publishers() > 0 && joint_states_->matched_publishers() > 0;
    if (!ok) {
      fail("no simulator answers on " + topics_.sim_step + " within " +
           std::to_string(connect_timeout_.count()) +
           " ms (is `tripodal sim-server` running with this namespace and domain?)");
      return false;
    }
  } catch (const std::exception& e) {
    fail(std::string("DDS failed: ") + e.what());
    return false;
  }
  connected_ = true;
  return true;
}

void DdsHardware::on_advance_to(Time now) noexcept {
  try {
    advance(now);
  } catch (...) {  // out of memory building a message: the link is down all the same
    lost_ = true;
  }
}

void DdsHardware::advance(Time now) {
  if (!lock_step_) {
    std::lock_guard lock(mutex_);
    if (simulator_silent_ && !lost_) fail(silent_why_);
    if (state_) {
      truth_ = truth_of(*state_);
      take_sensors(*state_);
    }
    return;
  }
  if (lost_ || (!connected_ && !connect())) return;
  const Twist2D t = commanded_twist();
  const std::uint32_t step = ++step_;
  try {
    sim_step_->publish(msg::SimStep{ros_time(now), {{t.vx_m_s, t.vy_m_s, 0.0}, {0.0, 0.0, t.wz_rad_s}}, step, joint_targets()});
  } catch (const std::exception& e) {
    fail(std::string("the step request could not be sent: ") + e.what());
    return;
  }
  std::unique_lock lock(mutex_);
  const auto answered = [&] {
    return simulator_silent_ || (state_ && state_->step >= step && laser_->received() >= state_->scans &&
                                 joint_states_received_ >= state_->joint_states);
  };
  if (!cv_.wait_for(lock, step_timeout_, answered)) {
    lock.unlock();
    fail("the simulator did not answer step " + std::to_string(step) + " (to " +
         std::to_string(to_seconds(now)) + " s) within " + std::to_string(step_timeout_.count()) + " ms");
    return;
  }
  if (simulator_silent_) {
    const std::string why = silent_why_;
    lock.unlock();
    fail(why);
    return;
  }
  truth_ = truth_of(*state_);
  take_sensors(*state_);
}

void register_dds_hardware(HardwareRegistry& registry) {
  registry.add(DdsHardware::static_manifest(), [](const HardwareConfig& c) -> std::unique_ptr<CHardware> {
    return std::make_unique<DdsHardware>(c);
  });
}

}  // namespace tripodal::dds
