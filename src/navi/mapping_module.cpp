#include "tripodal/navi/mapping_module.hpp"

#include <algorithm>
#include <cmath>

#include "tripodal/navi/map_io.hpp"

namespace tripodal::navi {

CMapBuilder::CMapBuilder(MappingOptions options) : options_(options) {}

CMapBuilder::~CMapBuilder() = default;

const ModuleManifest& CMapBuilder::static_manifest() {
  const MappingOptions d;
  static const ModuleManifest m = navi_manifest(
      "MapBuilder",
      "live mapping while the robot is driven by hand: each new laser scan matched against the map made so far and "
      "inserted (log-odds grid); the operator begins it, ends it and saves the map as a map_server map",
      {"laser_scan", "odometry"}, {"built_map"},
      {ParameterSpec{"laser", ValueType::string, Value{std::string()}, "", "laser resource (empty: the first)", {}, {}},
       ParameterSpec{"odometry", ValueType::string, Value{std::string()}, "", "odometry resource (empty: the first)", {}, {}},
       ParameterSpec{"laser_x_m", ValueType::number, Value{0.0}, "m", "scanner position on the base, forward", {}, {}},
       ParameterSpec{"laser_y_m", ValueType::number, Value{0.0}, "m", "scanner position on the base, leftward", {}, {}},
       ParameterSpec{"laser_yaw_rad", ValueType::number, Value{0.0}, "rad", "scanner heading on the base", {}, {}},
       ParameterSpec{"resolution_m", ValueType::number, Value{d.builder.resolution_m}, "m", "cell size of the map", 0.01, 1.0},
       ParameterSpec{"size_m", ValueType::number, Value{d.size_m}, "m",
                     "side of the square the map may cover, centred where mapping begins", 1.0, 500.0},
       ParameterSpec{"max_range_m", ValueType::number, Value{d.builder.max_range_m}, "m",
                     "beams beyond this are not inserted", 0.5, 100.0},
       ParameterSpec{"begin_at_start", ValueType::boolean, Value{d.begin_at_start}, "",
                     "map from the first period (else when the operator asks)", {}, {}},
       ParameterSpec{"loop_closure", ValueType::boolean, Value{d.builder.loop.enabled}, "",
                     "close loops while mapping (each attempt holds the sequencing loop for 50-250 ms)", {}, {}}});
  return m;
}

void CMapBuilder::on_configure(const ParameterSet& params) {
  MappingOptions o = options_;
  o.base_from_laser = {params.number("laser_x_m"), params.number("laser_y_m"), params.number("laser_yaw_rad")};
  o.builder.resolution_m = params.number("resolution_m");
  o.builder.max_range_m = params.number("max_range_m");
  o.size_m = params.number("size_m");
  o.begin_at_start = params.boolean("begin_at_start");
  o.builder.loop.enabled = params.boolean("loop_closure");
  const double cells = o.size_m / o.builder.resolution_m;
  if (cells * cells > static_cast<double>(kMaxPgmPixels)) {
    throw ConfigError(where(), "MapBuilder: size_m / resolution_m gives a map of " + std::to_string(static_cast<long long>(cells)) +
                                   " cells a side, more than a map image may hold");
  }
  laser_name_ = params.string("laser");
  odometry_name_ = params.string("odometry");
  options_ = o;
}

void CMapBuilder::on_start(ModuleContext& context) {
  laser_ = &sensor_of<LaserScan>(context, laser_name_, "MapBuilder", "a laser scanner", "laser", where());
  odometry_ = &sensor_of<OdometryReading>(context, odometry_name_, "MapBuilder", "odometry", "odometry", where());
  if (options_.begin_at_start) begin();
}

void CMapBuilder::on_update(ModuleContext& /*context*/) {
  if (laser_ == nullptr || odometry_ == nullptr || !laser_->has_reading() || !odometry_->has_reading()) return;
  const LaserScan& scan = laser_->latest();
  if (has_scan_ && scan.stamp == last_scan_stamp_) return;
  has_scan_ = true;
  last_scan_stamp_ = scan.stamp;
  add(scan, odometry_->latest().pose);
}

void CMapBuilder::begin(const Pose2D& start) {
  const double half = options_.size_m / 2.0;
  auto builder = std::make_unique<MapBuilder>(Point2D{start.x_m - half, start.y_m - half},
                                              Point2D{start.x_m + half, start.y_m + half}, options_.builder);
  const std::lock_guard lock(mutex_);
  builder_ = std::move(builder);
  mapping_ = true;
  start_ = start;
  pose_ = start;
  scans_ = 0;
}

void CMapBuilder::end() noexcept {
  const std::lock_guard lock(mutex_);
  mapping_ = false;
}

bool CMapBuilder::mapping() const noexcept {
  const std::lock_guard lock(mutex_);
  return mapping_;
}

std::size_t CMapBuilder::scans() const noexcept {
  const std::lock_guard lock(mutex_);
  return scans_;
}

Pose2D CMapBuilder::pose() const noexcept {
  const std::lock_guard lock(mutex_);
  return pose_;
}

double CMapBuilder::last_quality() const noexcept {
  const std::lock_guard lock(mutex_);
  return builder_ ? builder_->last_quality() : 0.0;
}

void CMapBuilder::add(const LaserScan& scan, const Pose2D& odom_from_base) {
  const std::lock_guard lock(mutex_);
  if (!mapping_ || !builder_) return;
  pose_ = builder_->add(scan, odom_from_base, start_, options_.base_from_laser);
  // the box the beams reached, for map(): a 60 m square is mostly unknown around a room
  const Pose2D laser = compose(pose_, options_.base_from_laser);
  const double reach = options_.builder.max_range_m;
  double lo_x = laser.x_m, lo_y = laser.y_m, hi_x = laser.x_m, hi_y = laser.y_m;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < scan.range_min_m) continue;
    const double a = laser.theta_rad + scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double d = std::min({r, reach, static_cast<double>(scan.range_max_m)});
    lo_x = std::min(lo_x, laser.x_m + d * std::cos(a));
    hi_x = std::max(hi_x, laser.x_m + d * std::cos(a));
    lo_y = std::min(lo_y, laser.y_m + d * std::sin(a));
    hi_y = std::max(hi_y, laser.y_m + d * std::sin(a));
  }
  if (scans_ == 0) {
    min_x_m_ = lo_x, min_y_m_ = lo_y, max_x_m_ = hi_x, max_y_m_ = hi_y;
  } else {
    min_x_m_ = std::min(min_x_m_, lo_x), min_y_m_ = std::min(min_y_m_, lo_y);
    max_x_m_ = std::max(max_x_m_, hi_x), max_y_m_ = std::max(max_y_m_, hi_y);
  }
  ++scans_;
}

std::optional<OccupancyGrid> CMapBuilder::map() const {
  const std::lock_guard lock(mutex_);
  if (!builder_ || scans_ == 0) return std::nullopt;
  // one cell of margin: the walls the beams ended on
  const double m = options_.builder.resolution_m;
  return builder_->grid_within({min_x_m_ - m, min_y_m_ - m}, {max_x_m_ + m, max_y_m_ + m});
}

void CMapBuilder::save(const std::filesystem::path& yaml_file) const {
  const std::optional<OccupancyGrid> grid = map();
  if (!grid) throw ConfigError(where(), "MapBuilder: no map to save yet (begin mapping and drive: each laser scan adds to it)");
  save_map(*grid, yaml_file);
}

}  // namespace tripodal::navi
