// Robot modules on DDS (tripodal::dds area): a laser resource fed by a sensor_msgs/LaserScan topic
// and a controller type that publishes its limited command as geometry_msgs/Twist on cmd_vel for a
// base driven by another process (ROS 2 or tripodal); both registered by name like any plugin.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <memory>
#include <mutex>
#include <string>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/dds/endpoint.hpp"
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

// Adds "DdsLaser" to a robot's resource registry (RobotPlugins::resources) and "dds_cmd_vel" to its
// controller registry. A template over the resource registry so that this area needs not link the
// robot's, whose ResourceConfig is read for its name and parameters only.
template <class ResourceRegistry>
void register_dds_modules(ResourceRegistry& resources, ControllerRegistry& controllers) {
  resources.add(DdsLaserResource::static_manifest(), [](const auto& config) -> std::unique_ptr<CResource> {
    return std::make_unique<DdsLaserResource>(config.name, config.parameters);
  });
  controllers.template add<DdsCmdVelController>();
}

}  // namespace tripodal::dds
