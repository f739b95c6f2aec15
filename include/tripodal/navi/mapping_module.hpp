// CMapBuilder, live mapping as a navigation module (sequencing layer): the thesis's mapping run,
// in which the robot is driven by hand (the monitor's console) while each new laser scan is matched
// and inserted into a growing occupancy grid (navi::MapBuilder); save() writes the map so far as a
// map_server map the robot is later localized on. Idle until begin(): a robot may carry it always.
#pragma once

#include <cstddef>
#include <filesystem>
#include <memory>
#include <mutex>
#include <optional>
#include <string>

#include "tripodal/navi/map_builder.hpp"
#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal::navi {

struct MappingOptions {
  /// Loop closure is off unless the profile asks for it (loop_closure): an attempt (a local map
  /// and a global search) takes 50-250 ms, several sequencing periods, and the module runs in the
  /// sequencing loop (`tripodal map build --loop-closure` closes loops on a recorded trace).
  MapBuilderOptions builder{.loop = {.enabled = false}};
  /// The map covers a square this wide centred on the pose mapping begins at (the grid is
  /// allocated at begin(), so the side bounds its memory: 60 m at 5 cm is 1.44 M cells).
  double size_m = 60.0;
  Pose2D base_from_laser;  ///< the scanner's mounting on the base
  bool begin_at_start = false;  ///< map from the robot's first period, no operator request needed
};

/// Type "MapBuilder". Takes the laser and the odometry from the robot's resources (the first of
/// each kind unless named). While mapping, every scan with a new stamp is added; the map's frame
/// is the robot's pose when mapping began (the origin, heading along x) unless begin() is given
/// another start. Its methods may be called from the thread that runs the robot's sequencing
/// loop and from another one (the monitor's): a mutex guards the map.
class CMapBuilder final : public CNaviModules {
 public:
  explicit CMapBuilder(MappingOptions options = {});
  ~CMapBuilder() override;

  static const ModuleManifest& static_manifest();

  /// Starts a new map (dropping any map being made); the first scan is inserted at `start`.
  void begin(const Pose2D& start = {});
  /// Stops adding scans; the map made so far stays (save() still writes it).
  void end() noexcept;
  [[nodiscard]] bool mapping() const noexcept;
  /// Scans added since begin().
  [[nodiscard]] std::size_t scans() const noexcept;
  /// The pose of the last scan in the map being made, and the quality of its match.
  [[nodiscard]] Pose2D pose() const noexcept;
  [[nodiscard]] double last_quality() const noexcept;
  /// The map so far, cropped to the cells the scans reached; nullopt before the first scan.
  [[nodiscard]] std::optional<OccupancyGrid> map() const;
  /// Writes the map so far as FILE.yaml + FILE.pgm (map_server); ConfigError when no scan has
  /// been added yet, std::runtime_error when the files cannot be written.
  void save(const std::filesystem::path& yaml_file) const;

  /// One scan with the odometry pose (odom_from_base) read with it; ignored unless mapping.
  void add(const LaserScan& scan, const Pose2D& odom_from_base);

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  void on_start(ModuleContext& context) override;
  void on_update(ModuleContext& context) override;

 private:
  MappingOptions options_;
  std::string laser_name_, odometry_name_;
  const LaserResource* laser_ = nullptr;
  const OdometryResource* odometry_ = nullptr;
  Time last_scan_stamp_{};
  bool has_scan_ = false;

  mutable std::mutex mutex_;  // guards what follows
  std::unique_ptr<MapBuilder> builder_;
  bool mapping_ = false;
  Pose2D start_;
  Pose2D pose_;
  std::size_t scans_ = 0;
  // the cells the scans reached (grid cells of the builder's extent), for cropping
  double min_x_m_ = 0.0, min_y_m_ = 0.0, max_x_m_ = 0.0, max_y_m_ = 0.0;
};

}  // namespace tripodal::navi
