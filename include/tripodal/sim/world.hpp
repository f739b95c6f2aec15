// The simulated world and robot as typed configuration: the grid map, the start pose, drop areas
// for the cliff sensors, boxes that appear during a run, the fault schedule, and the simulated
// robot's body and sensors. Loaded once from a world YAML file (docs/simulator.md); the embedded
// simulator (sim/simulator.hpp) runs on it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/navi/map_io.hpp"
#include "tripodal/navi/regions.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::sim {

/// A 2D laser scanner simulated by ray casting. Beam i points at angle_min_rad + i *
/// angle_increment() in the scanner frame; the scanner sits at `mount` (base_from_laser).
struct LaserConfig {
  std::string name = "front_laser";  ///< resource name
  bool enabled = true;
  double angle_min_rad = -std::numbers::pi;
  double angle_max_rad = std::numbers::pi;  ///< for a full turn, exclusive (the last beam stops short of it)
  std::uint32_t beams = 1450;
  double range_min_m = 0.15;
  double range_max_m = 12.0;
  double rate_hz = 5.5;
  double noise_stddev_m = 0.01;  ///< Gaussian range noise
  Pose2D mount;                  ///< base_from_laser

  /// Angle between beams: a full turn (span >= 2 pi) divides 2 pi by beams, a sector its span by
  /// beams - 1 so both ends are measured.
  [[nodiscard]] double angle_increment() const noexcept;
  /// The angle of the last beam (LaserScan::angle_max_rad).
  [[nodiscard]] double last_beam_angle() const noexcept { return angle_min_rad + angle_increment() * (beams - 1.0); }

  /// SLAMTEC RPLIDAR A1: 360 degrees, 12 m, about 1,450 points per turn at 5.5 Hz.
  [[nodiscard]] static LaserConfig rplidar_a1();
  /// A SICK LMS 200-like 180-degree scanner: 361 beams (0.5 degrees), 30 m, 37.5 Hz.
  [[nodiscard]] static LaserConfig sick_180();
};

/// Wheel encoders: each period's wheel rotation is read with a relative error drawn from
/// N(0, noise_ratio), so the odometry drift grows with the distance driven; plus a constant
/// per-wheel scale error drawn once from N(0, scale_error_stddev).
struct OdometryNoiseConfig {
  std::string name = "sim_odometry";  ///< resource of the simulator's own encoder odometry
  double noise_ratio = 0.01;
  double scale_error_stddev = 0.0;
  double rate_hz = 100.0;
};

struct GyroConfig {
  std::string name = "gyro";
  bool enabled = true;
  double noise_stddev_rad_s = 0.002;
  double bias_rad_s = 0.0;
  double rate_hz = 100.0;
};

/// Bumper ring split into equal sectors: sector 0 is centred on the robot's front (+x), the
/// others follow counter-clockwise. A sector is pressed while an occupied cell is within
/// contact_margin_m of the footprint in its direction.
struct BumperConfig {
  std::string name = "bumpers";
  bool enabled = true;
  std::uint32_t sectors = 4;  ///< 1..32
  double contact_margin_m = 0.005;
  double rate_hz = 50.0;
};

/// Downward infrared cliff detectors at body-frame positions; one sees a cliff over a drop cell.
struct CliffConfig {
  std::string name = "cliff";
  bool enabled = true;
  std::vector<navi::Point2D> positions = {{0.2, 0.0}, {0.1, 0.17}, {0.1, -0.17}};  ///< base frame
  double rate_hz = 50.0;
};

/// State of charge falls with time and distance and rises while charging; the voltage is linear
/// in the state of charge. An empty battery stops the wheels.
struct BatteryConfig {
  std::string name = "battery";
  bool enabled = true;
  double initial = 1.0;             ///< state of charge at the start, 0..1
  double capacity_ah = 20.0;
  double voltage_empty_v = 22.0;
  double voltage_full_v = 25.2;
  double drain_per_s = 2.0e-5;      ///< fraction of the capacity per second (electronics)
  double drain_per_m = 2.0e-4;      ///< fraction of the capacity per metre driven
  double charge_per_s = 5.0e-4;     ///< fraction of the capacity per second while charging (on a dock)
  double rate_hz = 1.0;
};

/// A joint of the robot's head or arm (Jinny's neck): it turns toward its commanded position at
/// speed_rad_s and never leaves [min_rad, max_rad]; a command beyond a limit is clamped to it.
struct JointConfig {
  std::string name;  ///< resource name of its state ("neck")
  double min_rad = -1.0;
  double max_rad = 1.0;
  double speed_rad_s = 1.0;
  double initial_rad = 0.0;
  double rate_hz = 50.0;  ///< state published at this rate
  SourceLocation where;
};

/// An LED button on the robot's body (Table 3's interaction elements): pressing it is an event;
/// its LED is lit by the robot.
struct ButtonConfig {
  std::string name;
  SourceLocation where;
};

/// The simulated robot: a round footprint, its sensors, and the physics step. The wheel geometry
/// is not here: it is the base controller's configuration (ControllerConfig), so the simulated
/// base and the controller always agree.
struct SimRobotConfig {
  double radius_m = 0.25;  ///< footprint radius
  LaserConfig laser;
  OdometryNoiseConfig odometry;
  GyroConfig gyro;
  BumperConfig bumpers;
  CliffConfig cliff;
  BatteryConfig battery;
  std::vector<JointConfig> joints;
  std::vector<ButtonConfig> buttons;
  /// Longest physics substep: a step(dt) is cut into equal substeps no longer than this.
  Duration max_substep{std::chrono::milliseconds(5)};
};

/// A box that appears in the world at `appear` (a blocked path) and, optionally, goes away at
/// `disappear`. Cells whose centre is inside become occupied for the ray casts and collisions
/// (not in the map the planner was given).
struct DynamicObstacle {
  std::string name;
  std::vector<navi::Point2D> polygon;  ///< map frame; a rectangle is stored as its 4 corners
  Time appear{};
  std::optional<Time> disappear;
  SourceLocation where;
};

/// A person walking in the world: a disc moving along its waypoints, seen by the laser and the
/// bumpers and stopping the robot's footprint like a wall. The run's seed draws where on its first
/// leg it starts, its speed on each leg within [speed_min, speed_max] and its pause at each
/// waypoint within [pause_min, pause_max]. A visitor gives way: it does not step closer than
/// `give_way_m` to the robot's footprint (it waits), so a contact is always the robot's doing.
struct Visitor {
  std::string name;
  double radius_m = 0.25;
  std::vector<navi::Point2D> path;  ///< map frame; one point: someone standing there
  bool loop = false;  ///< after the last point, on to the first; otherwise back along the path
  double speed_min_m_s = 0.5;
  double speed_max_m_s = 1.0;
  double pause_min_s = 0.0;
  double pause_max_s = 0.0;
  double give_way_m = 0.15;
  Time start{};  ///< stands at its starting point until then
  /// A visitor being guided: from its one waypoint it follows the robot along the robot's own
  /// trail (clear of the map for a body no wider than the robot's), at speed_max, and stops when
  /// it is follow_gap_m from the robot's footprint.
  bool follow_robot = false;
  double follow_gap_m = 0.8;
  SourceLocation where;
};

/// Floor that drops away (stairs, a loading edge): the cliff sensors see it; a robot whose centre
/// or a wheel's contact point enters it falls and cannot move any more. The laser does not see it
/// (it looks over it), so the map may show it as free floor.
struct DropArea {
  std::string name;
  std::vector<navi::Point2D> polygon;  ///< map frame
  SourceLocation where;
  double depth_m = 1.0;  ///< how far the floor falls: a cliff sensor over it reads this much farther
};

/// An obstacle only the ultrasonic sensors see: a glass wall (the laser's light goes through), a
/// low table (below the laser's plane). Invisible to the laser's ray casts, solid to the body, the
/// bumpers and the ultrasonic cones.
struct SonarOnlyObstacle {
  std::string name;
  std::vector<navi::Point2D> polygon;  ///< map frame
  SourceLocation where;
};

/// A cliff sensor whose output is stuck for the whole run: at the floor's reading (it never sees a
/// drop) or at a drop's (it always does). Index into robot.cliff.positions.
struct StuckCliffSensor {
  std::size_t index = 0;
  bool reads_drop = false;
  SourceLocation where;
};

/// A charging dock: its contacts touch the robot's while the robot's centre is within
/// contact_radius_m of `pose` and its heading within heading_tolerance_rad of pose.theta (a
/// tolerance of pi or more: a charging pad, any heading). While they touch the battery charges
/// at robot.battery.charge_per_s (BatteryReading::charging is true). A dock without power (its
/// charger broken or unplugged) touches the robot's contacts but charges nothing.
struct Dock {
  std::string name;
  Pose2D pose;  ///< map_from_base of the robot docked
  double contact_radius_m = 0.1;
  double heading_tolerance_rad = 0.35;
  SourceLocation where;
  // Last, so that the positional initialisers written before it existed keep their meaning.
  bool powered = true;  ///< false: the charger gives no current
};

/// Which simulated sensor a dead-sensor fault silences.
enum class SensorKind : std::uint8_t { laser, odometry, gyro, bumpers, cliff, battery };
[[nodiscard]] std::string_view to_string(SensorKind kind) noexcept;

/// A sensor that stops publishing from start (inclusive) to end (exclusive): its resource keeps
/// the last reading, whose age makes CResource::is_stale() true once past the max age.
struct SensorOutage {
  SensorKind sensor = SensorKind::laser;
  Time start{};
  Time end{};
  SourceLocation where;
};

/// A kidnapping: at `at` the world moves the robot to `to` (map_from_base) without a wheel
/// turning, so the odometry does not see it; the localizer must find out from its laser.
struct Kidnapping {
  Time at{};
  Pose2D to;
  SourceLocation where;
};

/// The faults injected in a run. A localization loss window blinds the laser (it keeps
/// publishing scans, with no return: the scanner dazzled), the physical cause a laser localizer
/// detects from its match quality; the windows are the navi localizer's own type
/// (navi::LocalizationFault), so the ground-truth test double CGroundTruthLocalizer can take them as flags
/// (CGroundTruthLocalizer::add_fault()). Blocked paths are World::obstacles with an appearance time.
struct FaultSchedule {
  std::vector<navi::LocalizationFault> localization_loss;
  std::vector<SensorOutage> dead_sensors;
  std::vector<Kidnapping> kidnappings;  ///< in time order
  std::vector<StuckCliffSensor> stuck_cliff;
};

/// A world file, loaded: everything the simulator needs.
struct World {
  std::filesystem::path file;          ///< the world YAML (empty when built in code)
  navi::OccupancyGrid grid;            ///< the static map
  std::filesystem::path map_file;      ///< map_server YAML it came from (may be empty)
  navi::RegionMap regions;             ///< rooms and nodes (empty when the world names none)
  std::filesystem::path regions_file;  ///< may be empty
  Pose2D start_pose;                   ///< map_from_base at time 0
  std::uint64_t seed = 1;              ///< default seed of a run (a command line may override)
  SimRobotConfig robot;
  std::vector<DropArea> drops;
  std::vector<SonarOnlyObstacle> sonar_only;
  std::vector<DynamicObstacle> obstacles;
  std::vector<Visitor> visitors;
  std::vector<Dock> docks;
  FaultSchedule faults;
};

/// Parses a world file's text. `file` names it in messages and is the folder that relative map
/// and regions paths are resolved against; the map (and regions) files are loaded. Every problem
/// of the world file (unknown key, missing map, wrong type, bad pose, bad window, unknown sensor
/// or region name, start pose not on a free cell) is collected and thrown as one ConfigError with
/// file:line:col per problem; errors inside the map or regions file are located in that file.
[[nodiscard]] World parse_world(std::string_view text, const std::filesystem::path& file);
/// Reads and parses a world file; ConfigError when it cannot be read.
[[nodiscard]] World load_world(const std::filesystem::path& file);

}  // namespace tripodal::sim
