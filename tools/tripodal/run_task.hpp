// A whole robot in simulation: `tripodal run` assembles the robot of a profile (planner, process
// supervisor, nets, behaviors, modules), puts it on the embedded simulator (sim::Simulator as
// the controller's hardware and the sensor source, the localizer's ground truth), gives it a task
// in plain words and runs it to its end; then it measures the run (coverage of the reachable free
// area, path length, turns, faults, recoveries) and writes the picture, trajectory and report.
// Application layer: it sits above the deliberate layer, like a robot program's main(); part of
// the `tripodal` tool (tools/tripodal), not of the installed library.
#pragma once

#include <csignal>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "tripodal/board/board_link.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/dose_planner.hpp"
#include "tripodal/navi/localizer.hpp"
#include "tripodal/robot/robot.hpp"

namespace tripodal {
struct RobotPlugins;
struct RobotProfile;
}
namespace tripodal::sim {
struct World;
}

namespace tripodal::app {

/// Fills `plugins` (empty) with the types every command of the `tripodal` tool knows: `run`,
/// `run --visit`, `describe` and `sim-server` call this one function, so that a profile `describe`
/// accepts is one `run` can assemble. The built-in areas' types (register_all: the simulator's
/// hardware "sim" and "board" in `world`, the board's modules and actuator behaviors, gestures,
/// navigation, the HRI module Hri); "dds" (the simulator in another process); with
/// the dds area, its resource and controller types (DdsLaser, DdsOdometry, DdsImu, DdsPose,
/// dds_cmd_vel) — without it a profile naming them is refused as naming an unknown type. `world`
/// may be null where no robot is built (describe reads the types' manifests only); hardware
/// created from it then refuses to start.
void register_tool_plugins(RobotPlugins& plugins, const std::shared_ptr<const sim::World>& world);
/// register_tool_plugins, then the shared-library plugins `libraries` (the command line's) and
/// the profile's `plugins:`: the one plugin set a command builds for `profile`. Throws ConfigError
/// for a library refused (robot/plugin_library.hpp).
void register_tool_plugins(RobotPlugins& plugins, const std::shared_ptr<const sim::World>& world, const RobotProfile& profile,
                           const std::vector<std::filesystem::path>& libraries);

struct RunOptions {
  std::filesystem::path robot;  ///< robot profile (YAML)
  std::filesystem::path world;  ///< world file (sim::load_world)
  /// Shared-library plugins (`--plugin`, docs/plugins.md), loaded before the profile's `plugins:`.
  std::vector<std::filesystem::path> plugins;
  std::string task;             ///< the command in plain words
  /// Overrides the type of the profile's hardware slot (its parameters then start empty): "dds",
  /// the simulator in another process (`tripodal sim-server`, docs/distribution.md). Empty: the
  /// profile's own.
  std::string hardware;
  /// Parameters of the hardware slot (KEY, VALUE), over the profile's: "namespace", "psr2".
  std::vector<std::pair<std::string, std::string>> hardware_parameters;
  std::optional<std::uint64_t> seed;  ///< default: the world's seed
  /// Run on wall-clock time, SPEED times real time: the robot on its own threads (Robot::start: a
  /// thread per loop, deadlines watched, report.json "realtime"); with a monitor or DDS the
  /// simulation is stepped on one thread paced to wall time instead.
  bool realtime = false;
  double realtime_speed = 1.0;
  std::filesystem::path out;    ///< folder for map.png, trajectory.csv, report.json (empty: none)
  /// An MCAP file (docs/rosbag.md) the run records into: every resource's readings the trace format
  /// carries (laser, odometry, gyro ...), the base's commands, and the task and process life cycle
  /// (with every firing of the nets) as events. Empty: none.
  std::filesystem::path record;
  /// Extra localization losses ("10-20; 35-40", seconds), added to the world's fault schedule.
  std::vector<navi::LocalizationFault> faults;
  /// The CoveragePlanner's pattern (hybrid, balloon, boustrophedon); empty: the profile's.
  std::string pattern;
  double max_duration_s = 4.0 * 3600.0;  ///< the task is cancelled after this much simulated time
  /// On hardware "board": what carries the simulated board's bytes, "in_process" or "pty" (a
  /// kernel pseudo-terminal); empty: the profile's choice.
  std::string board_line;
  /// The UV dose a cell of the floor must receive to count as disinfected (J/m^2; 10 = 1 mJ/cm^2);
  /// only for a robot on the control board. Default kDefaultUvTargetDose.
  std::optional<double> uv_target_dose_j_m2;
  /// A dose-planned disinfection (the CoveragePlanner's dose_target_j_m2) whose plan needs longer
  /// than this (s) is refused before it starts. nullopt: the battery alone bounds it.
  std::optional<double> time_limit_s;
  /// false: the CoveragePlanner's lanes as without a dose target (dose_target_j_m2 0), the dose
  /// still measured: the behaviour before dose planning, kept measurable.
  bool dose_plan = true;
  /// The monitor (docs/monitor.md): serve the page, the topics and the operator console on
  /// ADDRESS:PORT while the run goes on. With a monitor the run is paced to real time (default
  /// speed 1), the task may come from the console instead of `task`, and the run goes on after
  /// the task until the monitor is asked to stop (`stop`, set from a signal handler) or
  /// max_duration_s of simulated time.
  std::optional<std::string> monitor;  ///< "[ADDR:]PORT"
  std::filesystem::path monitor_token_file;  ///< the token, read from this file (default: generated)
  bool monitor_read_open = false;    ///< read-only streams without the token
  std::vector<std::string> monitor_allowed_hosts;    ///< Host names served besides loopback and addresses
  std::vector<std::string> monitor_allowed_origins;  ///< Origins served besides the page's own
  bool start_paused = false;         ///< hold the run until the operator resumes it
  /// Set (by a signal handler) to the signal's number to stop the run: the task is cancelled, the
  /// base brought to rest and the outputs written, naming it ("interrupted by SIGTERM").
  const volatile std::sig_atomic_t* stop = nullptr;
  std::ostream* log = nullptr;       ///< task and process life cycle, as it happens
  std::ostream* progress = nullptr;  ///< progress bar
  bool progress_is_terminal = false; ///< redraw the bar in place ('\r') instead of new lines
};

/// Figures of a coverage path (executed or planned).
struct PathFigures {
  double length_m = 0.0;
  std::size_t turns = 0;       ///< heading changes over 30 degrees of the simplified path
  double rotation_rad = 0.0;   ///< of the robot's body (executed paths only)
};

struct SectionFigures {
  std::string name;
  double area_m2 = 0.0;
  navi::PathStats hybrid;         ///< the planned hybrid path (a wall round, then lanes)
  navi::PathStats balloon;        ///< the planned balloon (wall-following) path
  navi::PathStats boustrophedon;  ///< the plough path over the same section, grid and width
  double hybrid_coverage = 0.0;
  double balloon_coverage = 0.0;
  double boustrophedon_coverage = 0.0;
};

inline constexpr double kDefaultUvTargetDose = 10.0;  ///< J/m^2 (1 mJ/cm^2)

/// What a run on the simulated control board adds (hardware "board"): the UV dose on the floor,
/// the disinfectant, and the link.
struct DisinfectionFigures {
  std::string line;             ///< "in_process", or "pty /dev/pts/N"
  double uv_target_dose_j_m2 = 0.0;
  double dose_coverage = 0.0;   ///< of the reachable cells, those that received the target dose
  double median_dose_j_m2 = 0.0;  ///< over the reachable cells
  double lamp_on_s = 0.0;
  double disinfectant_used_l = 0.0;
  double disinfectant_left_l = 0.0;
  /// With a dose plan: the floor the lamp can dose at all (within the plan's reach_m of where the
  /// robot can stand) and the share of it at the target; dose_coverage stays the share of the
  /// cleaning footprint's reachable floor.
  std::optional<navi::DosePlan> plan;
  double lamp_floor_m2 = 0.0;
  double lamp_floor_dose_coverage = 0.0;
  double estimate_s = 0.0;       ///< the up-front estimate of the run's time
  double estimate_ah = 0.0;      ///< and of its charge
  double battery_used_ah = 0.0;  ///< the board's state of charge, start to end, x capacity
  double lamp_energy_wh = 0.0;   ///< electrical: the lamp's current at the battery's voltage, while on
  double uvc_energy_j = 0.0;     ///< radiant UVC emitted: the lamp's UVC power x time on
  board::LinkStats link;        ///< the host's side
  std::uint64_t decoder_errors = 0;  ///< host and board decoders together
  std::uint64_t board_requests = 0;  ///< answered by the firmware
  std::uint64_t watchdog_trips = 0;
  std::uint64_t bytes_to_board = 0, bytes_to_host = 0, bytes_lost = 0;
};

struct RunResult {
  bool succeeded = false;
  std::string state;            ///< "succeeded", "failed", "timed out", "refused", "interrupted"
  /// "interrupted by SIGTERM" when a signal ended the run (the task, if one was running, is then
  /// "interrupted"); "" when it ended by itself.
  std::string stopped_by;
  /// The wheel velocities the base was commanded last (rad/s), after the run brought it to rest.
  std::vector<double> base_command_at_end_rad_s;
  bool base_at_rest = false;
  std::string reason;
  std::string robot, task;
  std::string coverage_pattern;  ///< "hybrid", "balloon" or "boustrophedon"
  std::uint64_t seed = 0;
  double duration_s = 0.0;      ///< simulated, or wall-clock time when wall_clock
  bool wall_clock = false;      ///< devices on ttys (run_devices): the run was timed by the wall clock
  double coverage = 0.0;        ///< of the reachable free area of the room, from the true path
  std::size_t reachable_cells = 0, cleaned_cells = 0;
  double reachable_area_m2 = 0.0;
  PathFigures total;            ///< the whole run
  PathFigures cleaning;         ///< while a cleaning behavior was active
  std::vector<SectionFigures> sections;
  std::vector<std::string> processes;  ///< "12.300 X1 PrCleaning(section=A) succeeded"
  std::vector<std::string> recoveries;
  std::vector<std::string> faults;     ///< injected faults and what happened (simulator events)
  std::size_t collisions = 0;
  std::size_t robot_steps = 0;
  /// --realtime SPEED on the robot's own threads: the speed, and each thread's deadline record
  /// (report.json "loops": period error p50/p99/max, overruns, deadline faults).
  double realtime_speed = 0.0;
  std::vector<LoopTimingReport> loops;
  std::optional<DisinfectionFigures> disinfection;  ///< on hardware "board" only
  double dose_estimate_s = 0.0;                     ///< a dose-planned disinfection's up-front time estimate
  double dose_estimate_ah = 0.0;                    ///< and its charge
  std::string charging;                             ///< the charges at the dock (charging_summary), empty: none
  [[nodiscard]] std::string json() const;
};

/// Runs the task; throws ConfigError for a bad profile or world (located), std::runtime_error
/// when an output file cannot be written. A task that fails is a result, not an exception.
[[nodiscard]] RunResult run_task(const RunOptions& options);

/// Length and turns of a path as the report counts them: simplified with Douglas-Peucker at
/// tolerance_m, then navi::path_stats with the 30-degree threshold.
[[nodiscard]] PathFigures path_figures(const std::vector<navi::Point2D>& path, double tolerance_m = 0.0375);

}  // namespace tripodal::app
