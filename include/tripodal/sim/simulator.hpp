// The embedded 2D simulator, the default "hardware" of tripodal: it sits below the reactive layer
// as the controllers' HardwareInterface (wheel velocities in, wheel states out), moves the base on
// the world's grid, publishes the sensor resources (laser, bumpers, cliff, gyro, battery, encoder
// odometry) and is the navi localizer's ground truth. Deterministic: the same world, base and
// seed give a bit-identical run. Time advances only by step(); a Robot on it (hardware type "sim")
// steps it together with its loops on a SimClock, and RealtimePacer slows that to wall time for
// --realtime.
#pragma once

#include <cstdint>
#include <limits>
#include <string_view>
#include <memory>
#include <optional>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "tripodal/controllers/base_kinematics.hpp"
#include "tripodal/controllers/controller.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/reactive/control_loop.hpp"
#include "tripodal/resources/resource.hpp"
#include "tripodal/sim/ray_caster.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::sim {

/// Something that happened to the simulated robot or world, for the run's report.
struct SimEvent {
  enum class Kind : std::uint8_t {
    collision,          ///< the footprint touched an occupied cell: the base stopped
    obstacle_appeared,  ///< a DynamicObstacle appeared (blocked path)
    obstacle_removed,
    sensor_dead,  ///< a SensorOutage started
    sensor_restored,
    localization_loss_start,  ///< a localization loss window started: the laser is blinded
    localization_loss_end,
    kidnapped,  ///< the world moved the robot (detail: "to (x, y, theta)")
    fell,       ///< the robot's centre or a wheel entered a drop area (detail: which)
    battery_empty,
    button_pressed,  ///< an LED button was pressed (detail: its name)
    docked,          ///< the robot's contacts touch a dock's (detail: its name): charging
    undocked,        ///< they no longer touch (detail: the dock's name)
  };
  Kind kind = Kind::collision;
  Time stamp{};
  std::string detail;  ///< obstacle or sensor name; "at (x, y)" of a collision
};
[[nodiscard]] std::string_view to_string(SimEvent::Kind kind) noexcept;

/// Where a visitor (World::visitors) is now.
struct VisitorState {
  navi::Point2D position;
  double speed_m_s = 0.0;  ///< of the leg it walks (0 while paused, waiting or giving way)
  bool giving_way = false; ///< it would come closer to the robot than give_way_m: it waits
};

/// Another robot of a shared world (`tripodal sim-server --robots N` steps one Simulator per robot
/// and tells each where the others are): a disc its laser sees and its footprint and bumpers touch.
struct OtherBody {
  navi::Point2D position;
  double radius_m = 0.0;
  std::uint32_t id = 0;  ///< the server's robot number, named in a collision's detail ("robot 2")
};

/// A simulated joint (World robot.joints) now.
struct JointState {
  double position_rad = 0.0;
  double target_rad = 0.0;     ///< the last command, clamped to the limits
  double velocity_rad_s = 0.0;
  bool at_limit = false;       ///< the last command was beyond a limit (clamped)
};

/// The simulator. Threading: one thread calls everything (Robot::run_until's caller).
class Simulator final : public HardwareInterface, public navi::GroundTruthSource {
 public:
  /// `base` gives the wheel geometry: type "differential" (wheels [left, right]), "omni" or
  /// "mecanum" (wheels in configuration order), exactly as the controller driving this simulator
  /// is configured. `seed` drives every noise source (one independent stream per sensor). Time
  /// starts at `start`, the robot at world.start_pose, and every sensor publishes a first reading
  /// at `start`. Throws ConfigError (at base.where) for an invalid base configuration.
  Simulator(World world, const ControllerConfig& base, std::uint64_t seed, Time start = Time{});
  ~Simulator() override;
  Simulator(const Simulator&) = delete;
  Simulator& operator=(const Simulator&) = delete;

  // --- HardwareInterface (the controller's side) -----------------------------------------
  [[nodiscard]] std::size_t wheel_count() const noexcept override { return wheels_; }
  /// Stores the commanded wheel velocities; applied from now until the next write. Refused
  /// (false) for a wrong count or non-finite values.
  bool write_wheel_velocities(std::span<const double> wheel_rad_s) noexcept override;
  /// The wheel velocities last commanded (rad/s, configuration order): what the base is told to
  /// do now, e.g. to check that a run stopping left its motors at zero.
  [[nodiscard]] std::span<const double> wheel_commands() const noexcept { return wheel_cmd_; }
  /// The wheels' actual velocities (zero while blocked) and encoder positions (with the
  /// odometry noise). False for wrong sizes or while the odometry sensor is dead.
  bool read_wheel_states(std::span<double> velocity_rad_s, std::span<double> position_rad) noexcept override;

  // --- GroundTruthSource (the navi localizer's side) -------------------------------------
  /// The true map_from_base (whatever `now`: the simulator's current pose).
  [[nodiscard]] std::optional<Pose2D> true_pose(Time now) const override;

  // --- stepping --------------------------------------------------------------------------
  /// Advances by dt (ignored when <= 0): the base moves in substeps of at most
  /// robot.max_substep, each sensor samples when its period falls due (at the end of the substep
  /// that reaches it), and scheduled faults start and end. Never throws or allocates in steady
  /// state.
  void step(Duration dt) noexcept;
  /// Advances to `t` (nothing when t <= now()).
  void step_until(Time t) noexcept { step(t - now_); }
  [[nodiscard]] Time now() const noexcept { return now_; }

  // --- commands for tests and tools (bypassing a controller) -----------------------------
  /// Writes the wheel velocities that realise body twist `twist` (inverse kinematics).
  void command_twist(const Twist2D& twist) noexcept;
  /// Wheel velocities of a twist and the twist of wheel velocities for this base (least
  /// squares for more than three holonomic wheels). Spans have wheel_count() entries.
  void inverse_kinematics(const Twist2D& twist, std::span<double> wheel_rad_s) const noexcept;
  [[nodiscard]] Twist2D forward_kinematics(std::span<const double> wheel_rad_s) const noexcept;

  // --- state -----------------------------------------------------------------------------
  [[nodiscard]] const Pose2D& pose() const noexcept { return pose_; }
  /// Moves the robot (e.g. a test, or a kidnapping); returns false and stays when the footprint
  /// would overlap a solid cell.
  bool set_pose(const Pose2D& map_from_base) noexcept;
  /// Body twist over the last substep (zero while blocked).
  [[nodiscard]] const Twist2D& velocity() const noexcept { return velocity_; }
  /// True while the last substep was stopped by a solid cell.
  [[nodiscard]] bool blocked() const noexcept { return blocked_; }
  [[nodiscard]] std::uint64_t collisions() const noexcept { return collisions_; }
  [[nodiscard]] bool fallen() const noexcept { return fallen_; }
  /// Contacts (counted in collisions() too) whose footprint touched a sonar-only obstacle.
  [[nodiscard]] std::uint64_t sonar_only_collisions() const noexcept { return sonar_only_collisions_; }
  /// How far the floor under cliff sensor `index` (robot.cliff.positions) lies below the floor the
  /// robot stands on: 0 over floor, the drop's depth_m over a drop; a stuck sensor (faults.
  /// stuck_cliff) reads 0 or +infinity whatever is under it. 0 for an unknown index.
  [[nodiscard]] double cliff_depth_m(std::size_t index) const noexcept;
  /// Ground-truth distance driven (m) and rotation (rad, absolute).
  [[nodiscard]] double distance_m() const noexcept { return distance_m_; }
  [[nodiscard]] double rotation_rad() const noexcept { return rotation_rad_; }
  [[nodiscard]] double battery_charge() const noexcept { return soc_; }
  /// A charger plugged in by hand (a test, a tool): charges wherever the robot is.
  void set_charging(bool charging) noexcept { charging_ = charging; }
  /// Charging: plugged in by hand, or on the contacts of a dock with power (World::docks).
  [[nodiscard]] bool charging() const noexcept { return charging_ || dock_powered_; }
  /// The dock whose contacts the robot touches (index into World::docks), -1 for none.
  [[nodiscard]] int dock() const noexcept { return dock_; }
  /// An extra load on the battery (a UV lamp, a pump), as a fraction of the capacity per second,
  /// until changed; a device of the hardware sets it while it runs.
  void set_extra_drain_per_s(double fraction_per_s) noexcept { extra_drain_per_s_ = fraction_per_s > 0.0 ? fraction_per_s : 0.0; }
  /// Whether `sensor` is silenced by the fault schedule at time t.
  [[nodiscard]] bool sensor_dead(SensorKind sensor, Time t) const noexcept;
  /// Whether a localization loss window covers t (the laser returns nothing then).
  [[nodiscard]] bool localization_lost(Time t) const noexcept override;

  [[nodiscard]] const World& world() const noexcept { return world_; }
  /// What stops the body, the bumpers and the ultrasonic cones: the static map, the sonar-only
  /// obstacles and the boxes present now.
  [[nodiscard]] const SolidMap& solid_map() const noexcept { return solid_; }
  /// What the laser sees: solid_map() without the sonar-only obstacles.
  [[nodiscard]] const SolidMap& laser_map() const noexcept { return sonar_only_.empty() ? solid_ : laser_solid_; }
  /// The visitors now, in World::visitors order.
  [[nodiscard]] const std::vector<VisitorState>& visitors() const noexcept { return visitors_; }
  /// Contacts of the robot's footprint with a visitor (counted in collisions() too).
  [[nodiscard]] std::uint64_t visitor_collisions() const noexcept { return visitor_collisions_; }
  /// The smallest distance between the robot's footprint and a visitor's disc so far (m; +inf
  /// without visitors).
  [[nodiscard]] double min_visitor_clearance_m() const noexcept { return min_visitor_clearance_m_; }

  /// The other robots of a shared world where they are now, until the next call (copied; once the
  /// storage has grown to the fleet's size no call allocates). They stop this robot as walls do,
  /// show in its scans and press its bumpers; they do not move by this robot's pushing.
  void set_other_bodies(std::span<const OtherBody> bodies);
  /// Contacts of the footprint with another robot (counted in collisions() too).
  [[nodiscard]] std::uint64_t robot_collisions() const noexcept { return robot_collisions_; }
  /// The smallest gap between this robot's footprint and another robot's so far (m; +inf alone).
  [[nodiscard]] double min_robot_clearance_m() const noexcept { return min_robot_clearance_m_; }

  /// The joints now, in World robot.joints order; index_of_joint(name) or nullopt.
  [[nodiscard]] const std::vector<JointState>& joints() const noexcept { return joints_; }
  [[nodiscard]] std::optional<std::size_t> joint_index(std::string_view name) const noexcept;
  /// Commands joint `index` toward `target_rad`, clamped to its limits (false when clamped or
  /// when there is no such joint or the target is not finite: then nothing changes).
  bool command_joint(std::size_t index, double target_rad) noexcept;

  /// Presses LED button `name` now (a visitor's finger; tests and the visit script): logged as a
  /// button_pressed event and queued for take_button_presses(). False for an unknown button.
  bool press_button(std::string_view name);
  /// The presses since the last call (button names, in order).
  [[nodiscard]] std::vector<std::string> take_button_presses();
  /// Lights or darkens a button's LED; false for an unknown button.
  bool set_led(std::string_view name, bool on) noexcept;
  [[nodiscard]] bool led(std::string_view name) const noexcept;

  /// What happened so far, in time order.
  [[nodiscard]] const std::vector<SimEvent>& events() const noexcept { return events_; }

  // --- sensor resources ------------------------------------------------------------------
  [[nodiscard]] LaserResource& laser() noexcept { return laser_; }
  [[nodiscard]] OdometryResource& odometry() noexcept { return odometry_; }
  [[nodiscard]] GyroResource& gyro() noexcept { return gyro_; }
  [[nodiscard]] BumperResource& bumpers() noexcept { return bumpers_; }
  [[nodiscard]] InfraredResource& cliff() noexcept { return cliff_; }
  [[nodiscard]] BatteryResource& battery() noexcept { return battery_; }
  /// Adds the enabled sensors' resources (laser, gyro, bumpers, cliff, battery) to a control
  /// loop's table. The encoder odometry resource is added only when `with_odometry` (a loop whose
  /// controller publishes odometry usually has its own).
  void add_resources(ResourceTable& table, bool with_odometry = false);

 private:
  struct Schedule {
    Duration period{0};
    Time next{};
  };
  void substep(Duration dt) noexcept;
  void update_faults() noexcept;
  void sample_sensors() noexcept;
  void update_bumpers() noexcept;
  void set_obstacle(std::size_t index, bool present) noexcept;  // marks it, restores its cells
  void lay_obstacles() noexcept;  // every present obstacle on the solid map, the ray jumps refreshed
  void copy_laser_map() noexcept;  // laser_solid_ = solid_ without the sonar-only cells
  [[nodiscard]] bool touches_sonar_only(const Pose2D& p) const noexcept;
  [[nodiscard]] double drop_depth_at(double x_m, double y_m) const noexcept;
  void move_visitors(double h) noexcept;
  void move_joints(double h) noexcept;
  void add_visitors_to_scan(LaserScan& scan) const noexcept;
  void add_disc_to_scan(LaserScan& scan, navi::Point2D origin, double heading, navi::Point2D centre,
                        double radius_m) const noexcept;
  [[nodiscard]] std::optional<std::size_t> other_hit(const Pose2D& p) const noexcept;
  [[nodiscard]] bool footprint_blocked(const Pose2D& p) const noexcept;
  [[nodiscard]] std::optional<std::size_t> visitor_hit(const Pose2D& p) const noexcept;
  struct VisitorWalk {
    std::mt19937_64 rng;
    std::size_t next = 0;  // waypoint walked to
    int direction = 1;     // along the path (+1) or back (-1)
    Time pause_until{};
  };
  void next_leg(std::size_t index) noexcept;
  void log(SimEvent::Kind kind, std::string_view detail) noexcept;
  [[nodiscard]] bool due(Schedule& s) const noexcept;

  World world_;
  BaseKinematics kinematics_;
  std::size_t wheels_ = 0;
  SolidMap solid_;
  std::vector<std::uint8_t> static_solid_;
  std::vector<float> drop_depth_;            // per cell: 0 floor, > 0 a drop's depth_m
  std::vector<std::uint8_t> sonar_only_;     // per cell: 1 inside a sonar-only obstacle; empty when none
  SolidMap laser_solid_;                     // solid_ without the sonar-only cells (when there are some)
  std::vector<navi::Point2D> wheel_points_;  // body frame: the wheels' contact points
  std::uint64_t sonar_only_collisions_ = 0;
  std::vector<std::vector<std::size_t>> obstacle_cells_;
  std::vector<std::uint8_t> obstacle_present_;
  std::vector<std::uint8_t> outage_active_;
  std::vector<std::uint8_t> loss_active_;
  std::size_t next_kidnapping_ = 0;

  Time now_{};
  Pose2D pose_;
  Twist2D velocity_;
  std::vector<double> wheel_cmd_, wheel_vel_, wheel_pos_, wheel_scale_;
  Pose2D odom_pose_;
  Twist2D odom_twist_;
  double gyro_yaw_ = 0.0;
  bool blocked_ = false;
  bool fallen_ = false;
  bool charging_ = false;
  int dock_ = -1;
  bool dock_powered_ = false;  ///< dock_ names a dock whose charger gives current
  double extra_drain_per_s_ = 0.0;
  bool battery_empty_ = false;
  std::uint64_t collisions_ = 0;
  double distance_m_ = 0.0;
  double rotation_rad_ = 0.0;
  double soc_ = 1.0;
  double soc_rate_ = 0.0;  // fraction per second over the last substep, for the current

  LaserModel laser_model_;
  std::mt19937_64 odom_rng_, gyro_rng_;
  std::normal_distribution<double> unit_normal_;
  std::normal_distribution<double> gyro_normal_;

  Schedule laser_due_, odom_due_, gyro_due_, bumper_due_, cliff_due_, battery_due_;
  LaserResource laser_;
  OdometryResource odometry_;
  GyroResource gyro_;
  BumperResource bumpers_;
  InfraredResource cliff_;
  BatteryResource battery_;
  std::vector<SimEvent> events_;

  std::vector<VisitorState> visitors_;
  // The robot's trail for visitors following it: a point every kTrailStepM, oldest dropped first
  // when full (fixed capacity: no allocation while stepping); each follower's next point in it.
  std::vector<navi::Point2D> trail_;
  std::size_t trail_head_ = 0, trail_size_ = 0;
  std::uint64_t trail_count_ = 0;              // points ever laid
  std::vector<std::uint64_t> follower_next_;   // per visitor: the trail point (by count) walked to
  std::vector<VisitorWalk> walks_;
  std::uint64_t visitor_collisions_ = 0;
  double min_visitor_clearance_m_ = std::numeric_limits<double>::infinity();
  std::vector<OtherBody> others_;
  std::uint64_t robot_collisions_ = 0;
  double min_robot_clearance_m_ = std::numeric_limits<double>::infinity();
  std::vector<JointState> joints_;
  std::vector<std::uint8_t> leds_;
  std::vector<std::string> presses_;
};

/// Where n robots of one shared world start: robot 1 at world.start_pose, the others on a grid of
/// spacing 2 radius + gap_m around it, nearest first, each on free floor with gap_m / 2 to spare
/// from the static map, all with the start pose's heading. `tripodal sim-server --robots N` and
/// `tripodal fleet --shared-world` compute the same poses from the same world. Throws ConfigError
/// (at the world file) when the map has no room for n.
[[nodiscard]] std::vector<Pose2D> fleet_start_poses(const World& world, std::size_t n, double gap_m = 0.4);

/// Paces a simulation to wall time (for --realtime): pace(t) sleeps on `wall` until the wall
/// time elapsed since the first call is (t - t_first) / speed. Uses only the Clock interface.
class RealtimePacer final {
 public:
  explicit RealtimePacer(const Clock& wall, double speed = 1.0) noexcept : wall_(wall), speed_(speed > 0.0 ? speed : 1.0) {}
  void pace(Time sim_now) noexcept;
  [[nodiscard]] double speed() const noexcept { return speed_; }

 private:
  const Clock& wall_;
  double speed_;
  bool started_ = false;
  Time sim_start_{};
  Time wall_start_{};
};

}  // namespace tripodal::sim
