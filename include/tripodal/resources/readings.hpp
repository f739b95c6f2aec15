// Typed, timestamped sensor readings: what resources publish, behaviors read, traces record and
// the simulator produces. Plain value types with SI units; laser fields as ROS sensor_msgs/LaserScan.
#pragma once

#include <cstdint>
#include <vector>

#include "tripodal/core/geometry.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal {

/// Wheel odometry (or fused odometry): pose in the odom frame and body-frame twist.
struct OdometryReading {
  Time stamp{};
  Pose2D pose;    ///< odom_from_base
  Twist2D twist;  ///< body frame
  friend bool operator==(const OdometryReading&, const OdometryReading&) = default;
};

/// One revolution or sweep of a 2D laser scanner, as ROS sensor_msgs/LaserScan. Beam i points at
/// angle_min_rad + i * angle_increment_rad in the scanner frame; a range outside
/// [range_min_m, range_max_m] (or not finite) means no return.
struct LaserScan {
  Time stamp{};  ///< time of the first beam
  double angle_min_rad = 0.0;
  double angle_max_rad = 0.0;
  double angle_increment_rad = 0.0;
  double time_increment_s = 0.0;  ///< between beams
  double scan_time_s = 0.0;       ///< between scans
  double range_min_m = 0.0;
  double range_max_m = 0.0;
  std::vector<float> ranges_m;
  std::vector<float> intensities;  ///< empty when the device gives none
  friend bool operator==(const LaserScan&, const LaserScan&) = default;
};

/// A ring or row of ultrasonic range finders, one range per transducer.
struct SonarReading {
  Time stamp{};
  double field_of_view_rad = 0.0;
  double range_min_m = 0.0;
  double range_max_m = 0.0;
  std::vector<float> ranges_m;
  friend bool operator==(const SonarReading&, const SonarReading&) = default;
};

/// Infrared sensors: downward cliff detectors (true = no floor seen) and sideways wall ranges.
struct InfraredReading {
  Time stamp{};
  std::vector<std::uint8_t> cliff;  ///< 1 = cliff detected under that sensor
  std::vector<float> wall_ranges_m;
  friend bool operator==(const InfraredReading&, const InfraredReading&) = default;
};

/// Bumper switches; bit i of pressed_mask is bumper i.
struct BumperReading {
  Time stamp{};
  std::uint32_t count = 0;
  std::uint32_t pressed_mask = 0;
  [[nodiscard]] bool any() const noexcept { return pressed_mask != 0; }
  friend bool operator==(const BumperReading&, const BumperReading&) = default;
};

struct BatteryReading {
  Time stamp{};
  double voltage_v = 0.0;
  double current_a = 0.0;   ///< positive when charging
  double percentage = 0.0;  ///< state of charge, 0..1 (as ROS BatteryState)
  bool charging = false;
  friend bool operator==(const BatteryReading&, const BatteryReading&) = default;
};

/// A single-axis (yaw) rate gyro, as the optical-fibre gyros of the PSR robots.
struct GyroReading {
  Time stamp{};
  double yaw_rate_rad_s = 0.0;
  double yaw_rad = 0.0;  ///< integrated heading, if the device provides it
  friend bool operator==(const GyroReading&, const GyroReading&) = default;
};

/// A neck or arm joint's state: position and speed, the command it follows, its limits. Read only:
/// the joint moves through the position channel its hardware exports (core/command_channel.hpp).
struct JointReading {
  Time stamp{};
  double position_rad = 0.0;
  double velocity_rad_s = 0.0;
  double target_rad = 0.0;  ///< the command being followed (clamped to the limits)
  double min_rad = 0.0;
  double max_rad = 0.0;
  friend bool operator==(const JointReading&, const JointReading&) = default;
};

}  // namespace tripodal
