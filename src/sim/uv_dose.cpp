#include "tripodal/sim/uv_dose.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace tripodal::sim {

UvDoseMap::UvDoseMap(const navi::OccupancyGrid& grid, UvLamp lamp) : grid_(grid), lamp_(lamp), dose_(grid.size(), 0.0) {
  validate(lamp_);
}

void UvDoseMap::expose(Point2D lamp_xy, Duration dt) noexcept {
  if (dt <= Duration::zero() || !std::isfinite(lamp_xy.x_m) || !std::isfinite(lamp_xy.y_m)) return;
  lamp_on_ += dt;
  const double seconds = to_seconds(dt);
  const double res = grid_.resolution_m();
  const navi::CellIndex c = grid_.cell_at(lamp_xy);
  const int reach = static_cast<int>(std::ceil(lamp_.radius_m / res)) + 1;
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      const navi::CellIndex n{c.x + dx, c.y + dy};
      if (!grid_.contains(n)) continue;
      const Point2D centre = grid_.cell_center(n);
      const double e = uv_irradiance_w_m2(lamp_, std::hypot(centre.x_m - lamp_xy.x_m, centre.y_m - lamp_xy.y_m));
      if (e > 0.0) dose_[grid_.index(n)] += e * seconds;
    }
  }
}

double UvDoseMap::dose_at_j_m2(Point2D p) const noexcept {
  const std::optional<navi::CellIndex> c = grid_.world_to_cell(p);
  return c ? dose_[grid_.index(*c)] : 0.0;
}

}  // namespace tripodal::sim
