// Imports CARMEN robot logs (the text format of the classic public 2D laser data sets: Intel Research
// Lab, ACES, MIT CSAIL, ...) into a tripodal trace, so behaviors can be tested on real sensor data.
// Conventions (beam angles, time stamps, skipped messages) are documented in docs/trace-format.md.
#pragma once

#include <cstdint>
#include <filesystem>
#include <istream>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include "tripodal/trace/trace_writer.hpp"

namespace tripodal::trace {

struct CarmenImportOptions {
  std::string laser_channel = "front_laser";  ///< FLASER and ROBOTLASER1 scans
  std::string rear_laser_channel = "rear_laser";  ///< RLASER and ROBOTLASER2 scans
  std::string odometry_channel = "odom";  ///< ODOM messages
  /// The laser pose of each FLASER/ROBOTLASER (in the corrected logs: the SLAM-corrected pose) as an
  /// OdometryReading with zero twist; empty: not written.
  std::string laser_pose_channel = "laser_pose";
  /// The corrected logs re-anchor their odometry: after every scan comes an ODOM equal to that
  /// scan's corrected pose, and the following ODOMs add the wheel odometry travelled since. Read
  /// as it stands, that odometry never drifts (it is the reference, plus one scan's motion). With
  /// this on, such an echo is dropped and the odometry is chained again from the increments since
  /// each echo: the wheel odometry the robot had (docs/localization.md, "Honest inputs").
  bool recover_anchored_odometry = true;
};

/// What a log's odometry channel holds after the import.
enum class CarmenOdometry {
  kNone,       ///< no ODOM at all, or odometry that stays still while the laser poses move
  kRaw,        ///< the log's ODOMs as they are (no re-anchoring found)
  kRecovered,  ///< re-anchored in the log; the wheel odometry was chained again from its increments
  kAnchored,   ///< re-anchored in the log, and left so (recover_anchored_odometry off)
};

struct CarmenImportReport {
  std::uint64_t lines = 0;
  std::uint64_t laser_scans = 0;        ///< FLASER, RLASER, ROBOTLASER1/2
  std::uint64_t odometry_readings = 0;  ///< ODOM
  std::uint64_t laser_poses = 0;        ///< records on laser_pose_channel
  std::uint64_t comments = 0;
  std::uint64_t blank_lines = 0;
  /// Messages the importer does not convert (NEFF, SYNC, TRUEPOS, RAWLASER1, ...): type -> lines.
  std::map<std::string, std::uint64_t> skipped;
  /// PARAM name/value pairs, in file order (kept in the report, not in the trace).
  std::vector<std::pair<std::string, std::string>> params;
  /// Messages stamped earlier than the message before them; they were clamped to that earlier
  /// message's stamp so the trace is in time order.
  std::uint64_t backwards_steps = 0;
  Duration largest_backwards_step{0};
  Time first_stamp{};
  Time last_stamp{};
  /// ODOMs that echo the scan before them (equal to its laser pose: the re-anchoring); dropped
  /// from the trace when recover_anchored_odometry is on.
  std::uint64_t odometry_echoes = 0;
  /// Front scans whose laser pose moved (5 cm or 0.05 rad) since the previous scan, and those of
  /// them whose odometry (as written) did not move at all: odometry that repeats the previous pose.
  std::uint64_t moving_scans = 0;
  std::uint64_t still_odometry_scans = 0;
  CarmenOdometry odometry = CarmenOdometry::kNone;

  /// One line on the odometry, for the tools: what it is and whether it can be used.
  [[nodiscard]] std::string odometry_note() const;
};

/// The longest line the importer reads: a 1081-beam ROBOTLASER1 line with remissions is about
/// 20 kB, so 1 MiB leaves room for any real scanner. A longer line is reported as an error at its
/// column kCarmenMaxLineBytes + 1 and only that much of it is ever held in memory.
inline constexpr std::size_t kCarmenMaxLineBytes = std::size_t{1} << 20;

/// Imports the CARMEN log at `path` (plain text, or gzip-compressed: detected from the content).
/// Reads every line before reporting: throws ConfigError listing each malformed line as
/// "FILE:LINE:COL: error: ..." (records of the well-formed lines are then already written).
/// Throws TraceIoError when the log cannot be read.
CarmenImportReport import_carmen_log(const std::filesystem::path& path, TraceWriter& out,
                                     const CarmenImportOptions& options = {});

/// As above, reading text from `in`; `name` is the file name used in diagnostics.
CarmenImportReport import_carmen_log(std::istream& in, const std::string& name, TraceWriter& out,
                                     const CarmenImportOptions& options = {});

/// CARMEN's convention for the old FLASER/RLASER messages, which carry no scanner configuration:
/// start angle -pi/2; 1 degree between beams for 180 or 181 beams, 0.5 degree for 360 or 361,
/// 0.25 degree for 400 or 401, otherwise pi / (n - 1). Returns the angle increment in radians.
[[nodiscard]] double carmen_flaser_angle_increment(std::size_t beams) noexcept;

/// The maximum range CARMEN assumes for FLASER/RLASER scans (its SICK LMS default), in metres.
inline constexpr double kCarmenFlaserMaxRangeM = 80.0;

}  // namespace tripodal::trace
