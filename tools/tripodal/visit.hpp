// The guide demo (docs/guide.md): a scripted visit of the exhibit hall. A visit file lists what a
// visitor types, says or presses, in sequence or at times; `tripodal run --visit FILE` puts Jinny
// (configs/robots/jinny.yaml) in the hall among walking visitors, hands each request to its HRI,
// and prints the dialogue and the task and process life cycle, the collisions and the figures;
// with --out it writes the audio of the answers (voice built) and a report. Application layer,
// part of the `tripodal` tool, not installed.
#pragma once

#include <csignal>
#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"

namespace tripodal::app {

/// One thing the visitor does.
struct VisitStep {
  enum class Kind { typed, spoken, button };
  Kind kind = Kind::typed;
  std::string text;  ///< the request, or the button's name
  /// Not before this simulated time (s); otherwise after_s after the previous step is over (its
  /// answer given and the task it started ended).
  std::optional<double> at_s;
  double after_s = 1.0;
  /// What should happen, checked and reported (empty: anything): the HRI's reply kind
  /// ("answered", "task_started", ...), the RKMS entry, the task started, and how it ends.
  std::string expect_outcome, expect_entry, expect_task, expect_task_end;
  SourceLocation where;
};

struct Visit {
  std::filesystem::path file;
  std::string name;
  double max_duration_s = 900.0;  ///< the visit is cut off after this much simulated time
  std::vector<VisitStep> steps;
};

[[nodiscard]] std::string_view to_string(VisitStep::Kind kind) noexcept;

/// Parses a visit file's text (`file` names it in messages). Every problem is collected and thrown
/// as one ConfigError, FILE:LINE:COL each: unknown keys, a step with none or two of type / say /
/// press, an empty request, a negative time, an unknown expected outcome or task end.
[[nodiscard]] Visit parse_visit(std::string_view text, const std::filesystem::path& file);
[[nodiscard]] Visit load_visit(const std::filesystem::path& file);

struct VisitOptions {
  std::filesystem::path robot, world;
  std::vector<std::filesystem::path> plugins;  ///< shared-library plugins (`--plugin`)
  std::filesystem::path visit;        ///< the visit file; empty: none (the monitor's visitors only)
  std::optional<std::uint64_t> seed;  ///< default: the world's
  std::filesystem::path out;          ///< dialogue.txt, report.json, answers' WAV files (empty: none)
  bool voice = true;                  ///< false: treat spoken requests as typed even if voice is built
  /// Live audio (`--audio DEVICE`, visit_audio.hpp): an ALSA PCM the robot hears the room through
  /// and answers on, besides the visit file's steps; empty: none. `audio_config`: an ALSA
  /// configuration file defining it (`--audio-config`; empty: the system's).
  std::string audio_device;
  std::filesystem::path audio_config;
  /// Overrides every visitor's give_way_m (world file, docs/simulator.md): 0 makes walkers that do
  /// not yield (they stop only at contact). Empty: the world's.
  std::optional<double> visitors_give_way_m;
  std::ostream* log = nullptr;        ///< the dialogue and the life cycle as they happen
  /// The monitor (docs/monitor.md, docs/guide.md): "[ADDR:]PORT" to serve the page, the robot's
  /// RKMS (/rkms) and its touch screen (/touch) while the visit runs, paced to real time; the run
  /// then goes on after the visit until `stop` is set (a signal) or max_duration_s. Empty: none.
  std::optional<std::string> monitor;
  std::filesystem::path monitor_token_file;  ///< the token, read from this file (default: generated)
  bool monitor_read_open = false;            ///< read-only streams without the token
  std::vector<std::string> monitor_allowed_hosts;    ///< Host names served besides loopback and addresses
  std::vector<std::string> monitor_allowed_origins;  ///< Origins served besides the page's own
  bool start_paused = false;                 ///< hold the run until the operator resumes it
  double realtime_speed = 1.0;               ///< with the monitor: SPEED times real time
  /// Simulated time limit of a monitored run without a visit file (a visit file has its own).
  double max_duration_s = 4.0 * 3600.0;
  const volatile std::sig_atomic_t* stop = nullptr;
};

/// One exchange of the dialogue.
struct VisitExchange {
  std::size_t step = 0;  ///< of the visit file, from 0
  double time_s = 0.0;
  std::string kind;    ///< typed, spoken, button
  std::string request; ///< as typed, the words heard, or the button
  std::string heard;   ///< spoken: the recognizer's words ("" otherwise)
  std::string reply_kind, entry, task, reply;
  std::string task_end;  ///< how the task it started ended ("" when none)
  std::string wav;       ///< the answer's audio file ("" without voice or --out)
  /// When the task ended: how far the visitor following the robot (World visitor follow_robot)
  /// stood from it, centre to centre (m; negative when nobody follows).
  double follower_distance_m = -1.0;
  bool as_expected = true;
  std::string mismatch;  ///< what differed from the visit file's expect
};

struct VisitResult {
  std::string visit;
  std::uint64_t seed = 0;
  bool voice = false;
  bool completed = false;        ///< every step ran within max_duration_s
  std::string stopped_by;        ///< "interrupted by SIGTERM" when a signal ended the run, else ""
  std::vector<double> base_command_at_end_rad_s;  ///< the wheels' last command, the base brought to rest
  bool base_at_rest = false;
  double duration_s = 0.0;       ///< simulated
  double distance_m = 0.0;       ///< ground truth
  std::uint64_t collisions = 0;  ///< of the robot's footprint (walls, exhibits, visitors)
  std::uint64_t visitor_collisions = 0;
  double min_visitor_clearance_m = 0.0;
  std::size_t visitor_waits = 0;  ///< times a walking visitor stopped to let the robot pass
  /// Time the robot stood still on its way (BhAutoMove active) with a visitor within 1.2 m: it
  /// waited for a visitor (sampled every 50 ms).
  double robot_waited_s = 0.0;
  std::vector<VisitExchange> exchanges;
  std::vector<std::string> processes;  ///< "12.300-40.100 X0 PrAutoMove(goal=node1) succeeded"
  std::size_t mismatches = 0;
  [[nodiscard]] std::string json() const;
};

/// Runs the visit (and serves the monitor when asked). Throws ConfigError for a bad profile, world
/// or visit file (located), std::invalid_argument for a bad monitor address or token file, or for
/// neither a visit nor a monitor.
[[nodiscard]] VisitResult run_visit(const VisitOptions& options);

}  // namespace tripodal::app
