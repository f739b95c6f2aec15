// The robot profile: a YAML file that says what a robot is made of — controllers and loops,
// resources, navigation modules, HRI and application modules, behaviors, processes, task templates
// and recovery rules. Loaded once into typed structs with every error located (FILE:LINE:COL);
// reference in docs/processes.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/geometry.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/petri_net.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/reactive/periodic_runner.hpp"

namespace tripodal {

/// One module instance of the profile (controller, resource, navigation, hri, other module, or
/// behavior). The type names a registered manifest; a type that is not registered may be
/// *declared* in the profile with layer/inputs/outputs, so a robot can be designed and described
/// before its modules exist (it cannot be started until they are registered).
struct ModuleEntry {
  ModuleKind kind = ModuleKind::other;  ///< from the section it is listed in
  std::string name;                     ///< instance name, unique in the robot
  std::string type;                     ///< registered type; defaults to the name
  std::optional<Layer> layer;           ///< declared layer (must agree with a registered manifest)
  std::optional<std::vector<std::string>> inputs;   ///< replace the manifest's inputs
  std::optional<std::vector<std::string>> outputs;  ///< replace the manifest's outputs
  /// `from: {odometry: base}`: which module provides an input that several provide (the control
  /// board's and the base controller's odometry); input information name -> provider's name.
  std::map<std::string, std::string, std::less<>> from;
  std::string description;
  std::map<std::string, std::string, std::less<>> parameters;
  std::optional<Duration> watchdog_timeout;  ///< supervisor watchdog on the module's heartbeat
  std::string watchdog_event;                ///< posted on silence; default "<name>.fault"
  /// Behaviors only (`safety: true`): a safety input of the behavior loop's coordinator, active
  /// from the robot's start and never activated by a net; its envelope restricts whatever command
  /// wins (BhAvoidObstacle: no motion toward an obstacle the laser sees, whoever drives).
  bool safety = false;
  SourceLocation where;
};

/// A control loop: a sampling period, the controller it drives, and how its thread runs on the
/// wall-clock runtime (Robot::start): `realtime_priority` (SCHED_FIFO 1..99), `cpu` (pinning),
/// `lock_memory` (mlockall), `budget_s` (a cycle ending later than its deadline + budget is an
/// overrun; default the period) and `deadline_overruns` (that many overruns in a row post
/// "<loop>.deadline" as a fault; default 0: counted only).
struct LoopEntry {
  std::string name;
  Duration period{0};
  std::string controller;
  LoopTimingOptions timing;
  SourceLocation where;
};

struct ProcessEntry {
  std::string name;
  std::string type = "net";                 ///< process factory type
  std::filesystem::path net;                ///< resolved against the profile's directory
  std::filesystem::path module;             ///< optional: its process module net (high-level, Fig. 2)
  std::vector<BindingParam> parameters;     ///< configured values, located
  std::filesystem::path recovery;           ///< optional: this process's own recovery rules
  SourceLocation where;
  SourceLocation net_where;
  SourceLocation module_where;
};

/// The topics a robot on DDS can publish (its `dds: publish:` list), in the order the profile
/// reference lists them (docs/distribution.md).
inline constexpr std::string_view kDdsTopics[] = {"odom", "pose", "map", "events", "markings", "tf", "clock"};

/// A sensor's frame for tf_static: where it sits on the base (base_from_frame: x_m, y_m, theta_rad).
struct DdsFrame {
  std::string name;
  Pose2D base_from_frame;
  SourceLocation where;
};

/// Whether ROS 2 takes `ns` as a namespace: names of letters, digits and '_', not starting with a
/// digit, separated by '/' (a leading '/' allowed); empty is none.
[[nodiscard]] bool is_ros_namespace(std::string_view ns);

/// The robot on DDS: `dds: {domain_id, namespace, loopback, participant_lease_s, period_s, publish,
/// tasks}`. Plain data read by the dds area's RobotBridge (docs/distribution.md); the robot itself
/// does not use it, so the core builds and runs without DDS.
struct DdsSection {
  std::uint32_t domain_id = 0;       ///< ROS 2's ROS_DOMAIN_ID, 0..232
  std::string ros_namespace;         ///< of every topic ("rt/<ns>/odom"); default: the robot's name
  bool loopback = true;              ///< 127.0.0.1 only; false: Cyclone DDS's own configuration
  std::optional<Duration> participant_lease;  ///< how long peers wait for this process; default Cyclone's 10 s
  Duration period{std::chrono::milliseconds(100)};  ///< odometry, pose and markings at most this often
  std::vector<std::string> publish;  ///< of kDdsTopics; default: all of them
  bool tasks = true;                 ///< take tripodal_msgs/TaskCommand on tripodal/task
  /// `frames: {laser: [x_m, y_m, theta_rad]}`: the sensors' mounts on tf_static (laser resources
  /// not listed go there at the base's origin).
  std::vector<DdsFrame> frames;
  /// `security: {keys: DIR, identity: NAME}`: DDS Security with the identity NAME of the fleet's
  /// keys in DIR (made by `tripodal fleet-keys`; relative to the profile). Empty: not secured.
  std::filesystem::path security_keys;
  std::string security_identity;
  SourceLocation where;
  [[nodiscard]] bool publishes(std::string_view topic) const noexcept {
    for (const std::string& t : publish) {
      if (t == topic) return true;
    }
    return false;
  }
};

/// One entry of a profile's `plugins:` list: the library's path (made absolute against the
/// profile's folder) and where it was written.
struct PluginEntry {
  std::filesystem::path path;
  SourceLocation where;
};

struct RobotProfile {
  std::string name;
  std::string description;
  std::filesystem::path file;
  std::filesystem::path dir;  ///< what relative paths in the profile (and its modules' parameters) are relative to
  SourceLocation where;
  /// Period of the sequencing loop (navigation modules, process supervisor, planner).
  Duration sequencing_period{std::chrono::milliseconds(50)};
  /// The sequencing loop's thread (`robot: {sequencing_loop: {...}}`, the keys of a loop's timing).
  LoopTimingOptions sequencing_timing;
  /// The hardware slot: `hardware: {type: sim, parameters: {...}}`; none: the robot has no
  /// hardware (a description, or a test that drives the loops itself).
  std::optional<ModuleEntry> hardware;
  std::vector<ModuleEntry> controllers;
  std::vector<LoopEntry> loops;
  std::vector<ModuleEntry> resources;
  std::vector<ModuleEntry> navigation;
  std::vector<ModuleEntry> hri;
  std::vector<ModuleEntry> modules;  ///< other application modules
  std::vector<ModuleEntry> behaviors;
  std::vector<ProcessEntry> processes;
  std::filesystem::path tasks;     ///< task templates (empty: none)
  std::filesystem::path recovery;  ///< recovery rules (empty: none)
  SourceLocation tasks_where;
  SourceLocation recovery_where;
  /// The robot on DDS; none: the robot speaks no DDS.
  std::optional<DdsSection> dds;
  /// `external_facts: [door_open, ...]`: facts the nets read that come from outside the robot's
  /// modules (set through the supervisor by the application); the check warns instead of refusing
  /// when no module lists one among its outputs.
  std::vector<std::string> external_facts;
  SourceLocation external_facts_where;
  /// Shared-library plugins the profile's types come from (`plugins: [lib/libpatrol.so]`, relative
  /// to the profile): whoever builds the plugin set for this profile loads them first
  /// (load_profile_plugins, robot/plugin_library.hpp), as `tripodal run` and `describe` do.
  std::vector<PluginEntry> plugins;

  /// Every module entry, in profile order: controllers, resources, navigation, hri, modules, behaviors.
  [[nodiscard]] std::vector<const ModuleEntry*> all_modules() const;
};

/// Loads a profile; throws ConfigError listing every error (unknown keys, wrong kinds of values,
/// duplicate names, bad periods, a loop naming an unknown controller, missing files).
[[nodiscard]] RobotProfile load_robot_profile(const std::filesystem::path& file);
/// As above from text; relative paths resolve against `base_dir`.
[[nodiscard]] RobotProfile load_robot_profile_from_string(std::string_view yaml, std::string_view name,
                                                          const std::filesystem::path& base_dir);

}  // namespace tripodal
