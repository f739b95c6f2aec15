// DdsHardware, the hardware type "dds" of a robot profile's hardware slot: a base and its laser
// behind DDS, on ROS 2 topics under a namespace — `tripodal sim-server` (the simulator in another
// process, in lock-step with the robot's clock) or a real base driver (cmd_vel out, joint_states
// and scan in). Sits below the reactive layer like the simulator's "sim" (docs/distribution.md).
#pragma once

#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tripodal/controllers/base_kinematics.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/dds/robot_modules.hpp"
#include "tripodal/hardware/buttons.hpp"
#include "tripodal/hardware/hardware.hpp"
#include "tripodal/resources/resource.hpp"
#include "tripodal/resources/resource_faults.hpp"

namespace tripodal::dds {

// The topics of a base on DDS under namespace `ns` (shared by DdsHardware and the sim-server);
// `clock` is ROS 2's /clock, which no namespace changes.
struct BaseTopics {
  std::string cmd_vel, joint_states, scan, clock, sim_step, sim_state;
  explicit BaseTopics(const std::string& ns);
};

// The simulator's ground truth (tripodal_msgs/SimState), for a run's measures.
struct SimTruth {
  Time stamp{};
  Pose2D map_from_base;
  double distance_m = 0.0;
  std::uint32_t collisions = 0;
};

// A joint of the robot's body behind DDS (a neck), as the simulator's world declares it: a
// position command channel and a JointResource of its name (docs/distribution.md).
struct DdsJoint {
  std::string name;
  double min_rad = -1.0, max_rad = 1.0;
  double initial_rad = 0.0;
  double rate_hz = 50.0;  // its state's rate: the resource goes stale after three periods
};

// Wheels: the controller's wheel velocities become a body twist by the base's forward kinematics
// (HardwareConfig::base) and go out as geometry_msgs/Twist on cmd_vel; the wheel states are the
// latest sensor_msgs/JointState of joint_states (names in the base's wheel order). Sensors: a
// laser resource "laser" fed by sensor_msgs/LaserScan on scan (DdsLaserResource), and those the
// parameter `sensors` names ("gyro,bumpers,cliff,battery", default none) as resources of those
// names, fed by the simulator's answer (SimState's sensor fields, after every step); a sensor the
// simulator's world does not give is a fault of the hardware. Joints (given at construction, the
// world's: `tripodal run` passes them): a position command channel and a JointResource each,
// the targets sent with the step when a command changed, the states from the answer; a joint the
// simulator does not report is a fault. Buttons (ButtonPanel): the presses the answer carries.
//
// Lock-step (parameter lock_step, default true: the other side is `tripodal sim-server`):
// advance_to(t) sends tripodal_msgs/SimStep {t, the twist} and waits until the simulator answers
// with a SimState whose step is this one and every scan and joint state it counts has arrived, so
// the robot sees at t what an in-process simulator gives at t, whatever the machine's load. A wait
// beyond step_timeout_s, the simulator's liveliness lost, or no simulator within
// connect_timeout_s is a fault of the hardware (ResourceFaultSource: the robot reports it as the
// module fault "<hardware>.fault"); from then on the link is down: advance_to returns at once and
// the wheel states read false (the controller's hardware fault), so a robot never hangs on it.
// Without lock-step, time is the base's own: commands go out as written, states come as they come.
//
// Not final: the `tripodal run` tool adds the world's map to it (navi::MapSource).
class DdsHardware : public CHardware, public HardwareInterface, public ResourceFaultSource, public ButtonPanel {
 public:
  // Parameters: namespace, domain_id, loopback, lock_step, step_timeout_s, connect_timeout_s, sensors.
  static const ModuleManifest& static_manifest();
  // Throws ConfigError (located at the entry) without a base controller or with a joint whose
  // limits are not min < max; DdsError when DDS fails.
  explicit DdsHardware(const HardwareConfig& config, std::vector<DdsJoint> joints = {});
  ~DdsHardware() override;

  [[nodiscard]] const BaseTopics& topics() const noexcept { return topics_; }
  [[nodiscard]] bool lock_step() const noexcept { return lock_step_; }
  // False once the link to the simulator is down (a fault was reported).
  [[nodiscard]] bool link_up() const noexcept { return !lost_; }
  // The simulator's ground truth after the last step (without lock-step: the latest a free-running
  // sim-server sent); nullopt before the first, or on a real base.
  [[nodiscard]] const std::optional<SimTruth>& truth() const noexcept { return truth_; }
  [[nodiscard]] std::uint32_t steps() const noexcept { return step_; }

  // HardwareInterface (the base controller's side, on the reactive loop's thread).
  [[nodiscard]] std::size_t wheel_count() const noexcept override { return kinematics_.wheel_count(); }
  bool write_wheel_velocities(std::span<const double> wheel_rad_s) noexcept override;
  bool read_wheel_states(std::span<double> velocity_rad_s, std::span<double> position_rad) noexcept override;

  [[nodiscard]] std::vector<std::string> take_faults() override { return faults_.take(); }
  // ButtonPanel: the LED buttons pressed on the simulator since the last call, oldest first.
  [[nodiscard]] std::vector<std::string> take_button_presses() override { return std::exchange(presses_, {}); }

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  [[nodiscard]] HardwareInterface& do_wheels() noexcept override { return *this; }
  void on_add_resources(ResourceTable& table) override;
  void on_advance_to(Time now) noexcept override;

 private:
  void advance(Time now);
  void take_sensors(const msg::SimState& s);  // under mutex_
  void fail(std::string why) noexcept;
  bool connect() noexcept;
  [[nodiscard]] Twist2D commanded_twist() const noexcept;
  [[nodiscard]] std::vector<double> joint_targets();

  BaseKinematics kinematics_;
  BaseTopics topics_;
  bool lock_step_ = true;
  std::chrono::milliseconds step_timeout_{5000}, connect_timeout_{10000};
  ResourceFaultQueue faults_;
  std::vector<double> command_;  // the last wheel velocities written (rad/s)
  std::uint32_t step_ = 0;
  bool connected_ = false;
  bool lost_ = false;
  std::optional<SimTruth> truth_;
  std::vector<DdsJoint> joints_;
  std::vector<std::unique_ptr<JointResource>> joint_resources_;
  std::vector<double> joint_sent_;  // the targets last sent (rad), the channels' values in joint order
  std::vector<std::string> presses_;

  // Written on Cyclone DDS threads, read on the loop's: guarded by mutex_, changes signalled on cv_.
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<msg::SimState> state_;
  std::vector<double> wheel_position_, wheel_velocity_;
  bool has_wheels_ = false;
  std::uint64_t joint_states_received_ = 0;
  bool simulator_silent_ = false;
  std::string silent_why_;

  std::unique_ptr<Participant> participant_;
  std::unique_ptr<DdsLaserResource> laser_;
  std::unique_ptr<GyroResource> gyro_;  // those the parameter sensors names, else null
  std::unique_ptr<BumperResource> bumpers_;
  std::unique_ptr<InfraredResource> cliff_;
  std::unique_ptr<BatteryResource> battery_;
  std::unique_ptr<Publisher<msg::Twist>> cmd_vel_;
  std::unique_ptr<Publisher<msg::SimStep>> sim_step_;
  std::unique_ptr<Subscriber<msg::JointState>> joint_states_;
  std::unique_ptr<Subscriber<msg::SimState>> sim_state_;
};

// Registers the hardware type "dds" (a robot program on a real base names its map in GridMaps).
void register_dds_hardware(HardwareRegistry& registry);

}  // namespace tripodal::dds
