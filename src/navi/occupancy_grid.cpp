#include "tripodal/navi/occupancy_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace tripodal::navi {

OccupancyGrid::OccupancyGrid(int width, int height, double resolution_m, Pose2D origin, Occupancy fill)
    : width_(width), height_(height), resolution_m_(resolution_m), origin_(origin),
      cos_yaw_(std::cos(origin.theta_rad)), sin_yaw_(std::sin(origin.theta_rad)) {
  if (width < 0 || height < 0) {
    throw std::invalid_argument("OccupancyGrid: size must not be negative, got " + std::to_string(width) + " x " +
                                std::to_string(height));
  }
  if (!(resolution_m > 0.0) || !std::isfinite(resolution_m)) {
    throw std::invalid_argument("OccupancyGrid: resolution must be positive and finite, got " +
                                std::to_string(resolution_m));
  }
  values_.assign(static_cast<std::size_t>(width) * static_cast<std::size_t>(height), value_of(fill));
}

Occupancy OccupancyGrid::state(CellIndex c) const noexcept {
  if (!contains(c)) return Occupancy::unknown;
  return state_of(values_[index(c)]);
}

void OccupancyGrid::set_value(CellIndex c, std::int8_t v) noexcept {
  values_[index(c)] = (v < 0 || v > kOccupiedValue) ? kUnknownValue : v;
}

std::size_t OccupancyGrid::count(Occupancy s) const noexcept {
  return static_cast<std::size_t>(
      std::count_if(values_.begin(), values_.end(), [s](std::int8_t v) { return state_of(v) == s; }));
}

Point2D OccupancyGrid::to_grid_frame(Point2D p) const noexcept {
  const double dx = p.x_m - origin_.x_m;
  const double dy = p.y_m - origin_.y_m;
  return {cos_yaw_ * dx + sin_yaw_ * dy, -sin_yaw_ * dx + cos_yaw_ * dy};
}

Point2D OccupancyGrid::from_grid_frame(Point2D g) const noexcept {
  return {origin_.x_m + cos_yaw_ * g.x_m - sin_yaw_ * g.y_m, origin_.y_m + sin_yaw_ * g.x_m + cos_yaw_ * g.y_m};
}

Point2D OccupancyGrid::cell_center(CellIndex c) const noexcept {
  return from_grid_frame({(c.x + 0.5) * resolution_m_, (c.y + 0.5) * resolution_m_});
}

CellIndex OccupancyGrid::cell_at(Point2D p) const noexcept {
  // A non-finite point maps to a cell that is outside every grid.
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m)) return {-1, -1};
  const Point2D g = to_grid_frame(p);
  // Clamp before the integer conversion so a far-away point cannot overflow int.
  const double limit = 1e9;
  const double gx = std::clamp(std::floor(g.x_m / resolution_m_), -limit, limit);
  const double gy = std::clamp(std::floor(g.y_m / resolution_m_), -limit, limit);
  return {static_cast<int>(gx), static_cast<int>(gy)};
}

std::optional<CellIndex> OccupancyGrid::world_to_cell(Point2D p) const noexcept {
  if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m)) return std::nullopt;
  const CellIndex c = cell_at(p);
  if (!contains(c)) return std::nullopt;
  return c;
}

}  // namespace tripodal::navi
