// Robot modules on DDS (tripodal::dds area): a laser resource fed by a sensor_msgs/LaserScan topic
// and a controller type that publishes its limited command as geometry_msgs/Twist on cmd_vel for a
// base driven by another process (ROS 2 or tripodal); both registered by name like any plugin.
#pragma once

#include <array>
#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/resources/readings.hpp"
#include "tripodal/resources/resource.hpp"
#include "tripodal/resources/resource_faults.hpp"

namespace tripodal::dds {

// Where a module's topic is: read from the parameters `topic`, `namespace`, `domain_id`,
// `loopback` that both module types declare.
struct TopicBinding {
  std::string topic;  // the DDS topic name, "rt/<namespace>/<topic>"
  ParticipantOptions participant;
};
TopicBinding topic_binding(const ParameterSet& parameters, std::string_view default_topic);

// How a DdsLaserResource reads its topic, when built in code rather than from a profile's entry
// (the laser of DdsHardware).
struct DdsLaserOptions {
  TopicBinding binding;
  Duration max_age{};       // older than this the scan is stale; 0: never
  Duration deadline{};      // a fault when no scan comes within this; 0: none
  // Lock-step co-simulation: every scan must arrive (a reliable reader, which matches only reliable
  // publishers) and its stamp is the robot's own time (the simulator's clock is the robot's).
  bool lock_step = false;
  // A reliable reader (matches only reliable publishers, as rplidar_ros's default QoS is): a lost
  // sample is repaired, the first one too. Best effort (the default, ROS 2's sensor-data profile)
  // matches every publisher but loses for good the samples a publisher writes before this
  // reader's discovery of it completes (docs/distribution.md, "First samples").
  bool reliable = false;
  std::function<void()> on_scan;  // after a scan was received (on a Cyclone DDS thread)
};

// Type "DdsLaser": the latest sensor_msgs/LaserScan of a topic as a laser resource. Scans arrive on
// a Cyclone DDS thread and are handed to the control loop in poll(), stamped with the loop's time
// of that poll (the sender's stamp is on another clock), so max_age_s measures how long ago the
// robot last heard of the laser. A silent laser is also a fault of the resource (ResourceFaultSource,
// so the robot posts "<name>.fault" and the planner's recovery runs): when the last alive publisher
// loses its liveliness (its process died, its lease ran out, it was deleted), and, with deadline_s,
// when no scan came within it.
class DdsLaserResource final : public LaserResource, public ResourceFaultSource {
 public:
  static const ModuleManifest& static_manifest();
  // `parameters` resolved against static_manifest() (a robot profile's resource entry).
  DdsLaserResource(std::string name, const ParameterSet& parameters);
  DdsLaserResource(std::string name, DdsLaserOptions options);
  ~DdsLaserResource() override;
  DdsLaserResource(const DdsLaserResource&) = delete;
  DdsLaserResource& operator=(const DdsLaserResource&) = delete;

  const std::string& topic() const noexcept;
  std::size_t matched_publishers() const;
  // Scans received so far (any thread).
  std::uint64_t received() const noexcept { return received_.load(std::memory_order_acquire); }
  [[nodiscard]] std::vector<std::string> take_faults() override { return faults_.take(); }

 private:
  void on_poll(Time now) noexcept override;
  void on_status(const StatusEvent& e);

  ResourceFaultQueue faults_;
  std::unique_ptr<Participant> participant_;
  std::mutex mutex_;  // guards pending_ between the DDS thread and the loop
  LaserScan pending_;
  std::atomic<bool> has_pending_{false};
  std::atomic<bool> silent_{false};  // a fault was reported and no scan came since
  std::atomic<std::uint64_t> received_{0};
  bool sender_stamp_ = false;
  Time pending_stamp_{};
  std::function<void()> on_scan_;
  std::unique_ptr<Subscriber<msg::LaserScan>> subscriber_;
};

// A planar pose estimate of another process's localizer (a ROS 2 AMCL's amcl_pose), as DdsPose
// holds it: map_from_base and its (x, y, theta) covariance, row-major 3 x 3.
struct PoseEstimate {
  Time stamp{};
  Pose2D map_from_base;
  std::array<double, 9> covariance{};
  friend bool operator==(const PoseEstimate&, const PoseEstimate&) = default;
};

// The latest message of a topic as a typed resource: "DdsOdometry" (nav_msgs/Odometry on odom, an
// odometry reading), "DdsImu" (sensor_msgs/Imu on imu, a gyro reading: the yaw rate and the yaw of
// the orientation), "DdsPose" (geometry_msgs/PoseWithCovarianceStamped on amcl_pose, a
// PoseEstimate). As DdsLaser: received on a Cyclone DDS thread, handed over in poll() stamped with
// the loop's time; a publisher that loses its liveliness is the resource's fault.
template <class Reading, class Msg>
class DdsReadingResource final : public TypedResource<Reading>, public ResourceFaultSource {
 public:
  static const ModuleManifest& static_manifest();
  DdsReadingResource(std::string name, const ParameterSet& parameters);
  ~DdsReadingResource() override;
  DdsReadingResource(const DdsReadingResource&) = delete;
  DdsReadingResource& operator=(const DdsReadingResource&) = delete;

  const std::string& topic() const noexcept;
  std::size_t matched_publishers() const;
  std::uint64_t received() const noexcept { return received_.load(std::memory_order_acquire); }
  [[nodiscard]] std::vector<std::string> take_faults() override { return faults_.take(); }

 private:
  void on_poll(Time now) noexcept override;

  ResourceFaultQueue faults_;
  std::unique_ptr<Participant> participant_;
  std::mutex mutex_;
  Reading pending_{};
  std::atomic<bool> has_pending_{false};
  std::atomic<std::uint64_t> received_{0};
  std::unique_ptr<Subscriber<Msg>> subscriber_;
};
using DdsOdometryResource = DdsReadingResource<OdometryReading, msg::Odometry>;
using DdsImuResource = DdsReadingResource<GyroReading, msg::Imu>;
using DdsPoseResource = DdsReadingResource<PoseEstimate, msg::PoseWithCovarianceStamped>;
extern template class DdsReadingResource<OdometryReading, msg::Odometry>;
extern template class DdsReadingResource<GyroReading, msg::Imu>;
extern template class DdsReadingResource<PoseEstimate, msg::PoseWithCovarianceStamped>;

// Type "dds_cmd_vel": a controller for a base that another process drives. Each period it limits
// the command like every controller and publishes it as geometry_msgs/Twist (linear x, y; angular
// z) with the command QoS. It has no wheels: its odometry integrates what it commanded (dead
// reckoning, no feedback), and a write that fails reports hardware_fault. Publishing goes through
// Cyclone DDS, which allocates: unlike the wheel controllers, update() is not allocation-free.
class DdsCmdVelController final : public CController {
 public:
  static const ModuleManifest& static_manifest();
  // The hardware interface is not used (no wheels here); config.parameters may be empty (defaults).
  DdsCmdVelController(const ControllerConfig& config, HardwareInterface& hardware);
  ~DdsCmdVelController() override;
  DdsCmdVelController(const DdsCmdVelController&) = delete;
  DdsCmdVelController& operator=(const DdsCmdVelController&) = delete;

  const std::string& topic() const noexcept;
  std::size_t matched_subscribers() const;

 private:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  BaseCapabilities do_capabilities() const noexcept override;
  std::span<const double> do_wheel_commands() const noexcept override { return {}; }
  ControlStatus on_update(Time now, Duration period, const Twist2D& command, bool timed_out, Twist2D& limited,
                          OdometryReading& odometry) noexcept override;
  Duration command_timeout() const noexcept override { return config_.cmd_timeout; }

  ControllerConfig config_;
  bool holonomic_ = false;
  TwistLimiter limiter_;
  std::unique_ptr<Participant> participant_;
  std::unique_ptr<Publisher<msg::Twist>> publisher_;
};

// Adds "DdsLaser", "DdsOdometry", "DdsImu" and "DdsPose" to a robot's resource registry
// (RobotPlugins::resources) and "dds_cmd_vel" to its controller registry. A template over the
// resource registry: any registry whose factories take a config with a name and parameters will do
// (the area links robot publicly all the same, for RobotBridge: src/dds/CMakeLists.txt).
template <class ResourceRegistry>
void register_dds_modules(ResourceRegistry& resources, ControllerRegistry& controllers) {
  resources.add(DdsLaserResource::static_manifest(), [](const auto& config) -> std::unique_ptr<CResource> {
    return std::make_unique<DdsLaserResource>(config.name, config.parameters);
  });
  resources.add(DdsOdometryResource::static_manifest(), [](const auto& config) -> std::unique_ptr<CResource> {
    return std::make_unique<DdsOdometryResource>(config.name, config.parameters);
  });
  resources.add(DdsImuResource::static_manifest(), [](const auto& config) -> std::unique_ptr<CResource> {
    return std::make_unique<DdsImuResource>(config.name, config.parameters);
  });
  resources.add(DdsPoseResource::static_manifest(), [](const auto& config) -> std::unique_ptr<CResource> {
    return std::make_unique<DdsPoseResource>(config.name, config.parameters);
  });
  controllers.template add<DdsCmdVelController>();
}

}  // namespace tripodal::dds
