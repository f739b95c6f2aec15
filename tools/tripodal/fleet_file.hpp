// A fleet file: the robots of a fleet by name, each with its profile, DDS namespace and start pose
// (docs/distribution.md, "A fleet file"). Read by `tripodal fleet --fleet FILE` and `tripodal
// sim-server --fleet FILE`, which must agree on who stands where; `tripodal fleet` writes one for
// its sim-server whichever way its robots were given.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/geometry.hpp"

namespace tripodal::sim {
struct World;
}

namespace tripodal::tool {

/// One robot of a fleet.
struct FleetMember {
  std::string name;               ///< unique; the robot's process, log and profile copy are named after it
  std::string ns;                 ///< its DDS namespace (default: the name), unique
  std::filesystem::path profile;  ///< absolute
  std::optional<Pose2D> start;    ///< where its body starts in a shared world (default: fleet_start_poses)
  /// In a shared world, the hardware dds's sensors ("gyro,bumpers"; "" none); not given: the
  /// world's (world_sensors), as the in-process simulator gives them.
  std::optional<std::string> sensors;
  SourceLocation where;           ///< the file's entry, for errors found later (a start pose not free)
};

/// The robots a fleet file names, in its order. Every problem of the file (not a list, unknown
/// keys, a name or namespace given twice or not a ROS 2 name, a profile that cannot be read, a
/// start pose that is not three numbers, a sensor the hardware dds does not know) is a ConfigError located at FILE:LINE:COL, all
/// at once.
[[nodiscard]] std::vector<FleetMember> load_fleet_file(const std::filesystem::path& file);

/// `n` robots robot1..robotN (namespace prefix + k) of one profile, no start pose of their own.
[[nodiscard]] std::vector<FleetMember> numbered_fleet(int n, const std::filesystem::path& profile,
                                                      const std::string& prefix = "robot");

/// The start poses in `world`: a member's own, the others on sim::fleet_start_poses' grid with
/// kFleetStartGap_m between bodies, skipping places the given poses take. A given pose off the
/// free floor, or closer than two radii plus 0.1 m to another robot, is a ConfigError at its entry.
[[nodiscard]] std::vector<Pose2D> fleet_starts(const sim::World& world, const std::vector<FleetMember>& members);

/// The gap between two robots' bodies at the start: wide enough that a robot's laser still sees
/// the walls past the robots around it (with 0.4 m, five to eight of eight PSR-2s in a 3 x 3 block
/// lost the map 10.9 s into their sections; docs/distribution.md, "Eight robots in one world").
inline constexpr double kFleetStartGap_m = 1.1;

/// The sensors a robot's body in `world` has besides the laser, as the hardware dds names them
/// ("gyro,bumpers,cliff,battery", those the world's `robot:` enables): what the in-process simulator
/// (hardware sim) gives a robot of that world, so what a fleet's robot on a shared world gets unless
/// its fleet file entry names its own — a profile that runs on `sim` finds the same resources.
[[nodiscard]] std::string world_sensors(const sim::World& world);

/// The members as a fleet file, their start poses given (what `tripodal fleet` hands its
/// sim-server).
[[nodiscard]] std::string fleet_file_text(const std::vector<FleetMember>& members, const std::vector<Pose2D>& starts);

}  // namespace tripodal::tool
