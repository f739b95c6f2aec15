// map.png of `tripodal run`: the room's map with its sections, the cleaned and missed cells, the
// virtual walls and the true path.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>

#include "run_outputs.hpp"

namespace tripodal::app {

namespace {

constexpr std::array<std::array<std::uint8_t, 3>, 8> kSectionColours{{
    {{255, 236, 179}}, {{200, 230, 255}}, {{225, 210, 255}}, {{255, 215, 215}},
    {{215, 245, 215}}, {{255, 225, 190}}, {{210, 240, 240}}, {{240, 240, 200}},
}};

}  // namespace

RgbImage draw_map(const Navigation& nav, const navi::CleanedCells& cleaned, const std::vector<char>& reachable,
                  const std::vector<TrajectorySample>& traj) {
  constexpr int kScale = 2;
  const navi::OccupancyGrid& g = nav.maps->grid();
  RgbImage img(g.width() * kScale, g.height() * kScale);
  auto fill_cell = [&](navi::CellIndex c, std::array<std::uint8_t, 3> rgb, double alpha) {
    for (int dy = 0; dy < kScale; ++dy) {
      for (int dx = 0; dx < kScale; ++dx) {
        img.blend(c.x * kScale + dx, (g.height() - 1 - c.y) * kScale + dy, rgb[0], rgb[1], rgb[2], alpha);
      }
    }
  };
  // The sections and virtual walls of a robot that cleans (one without a SectionSplitter has none).
  static const std::vector<int> no_labels, no_walls;
  const auto& label = nav.splitter != nullptr ? nav.splitter->sections().label : no_labels;
  for (std::size_t i = 0; i < g.size(); ++i) {
    const navi::CellIndex c = g.cell(i);
    switch (g.state(i)) {
      case navi::Occupancy::occupied: fill_cell(c, {0, 0, 0}, 1.0); continue;
      case navi::Occupancy::unknown: fill_cell(c, {170, 170, 170}, 1.0); continue;
      case navi::Occupancy::free: break;
    }
    if (i < label.size() && label[i] >= 0) fill_cell(c, kSectionColours[static_cast<std::size_t>(label[i]) % kSectionColours.size()], 1.0);
    if (cleaned.cleaned(i)) fill_cell(c, {60, 170, 60}, 0.45);
    else if (i < reachable.size() && reachable[i] != 0) fill_cell(c, {230, 40, 40}, 0.6);
  }
  for (const int row : nav.splitter != nullptr ? nav.splitter->sections().virtual_wall_rows : no_walls) {
    const int y = (g.height() - 1 - row) * kScale;  // the edge between rows row and row + 1
    for (int x = 0; x < img.width; ++x) {
      if ((x / 6) % 2 == 0) img.set(x, y, 220, 0, 0);
    }
  }
  auto to_px = [&](Pose2D p, double& px, double& py) {
    const Point2D gf = g.to_grid_frame({p.x_m, p.y_m});
    px = gf.x_m / g.resolution_m() * kScale;
    py = (g.height() - gf.y_m / g.resolution_m()) * kScale;
  };
  for (std::size_t k = 1; k < traj.size(); ++k) {
    double x0, y0, x1, y1;
    to_px(traj[k - 1].truth, x0, y0);
    to_px(traj[k].truth, x1, y1);
    const int n = std::max(1, static_cast<int>(std::ceil(std::hypot(x1 - x0, y1 - y0))));
    for (int s = 0; s <= n; ++s) {
      const double t = static_cast<double>(s) / n;
      img.blend(static_cast<int>(std::floor(x0 + t * (x1 - x0))), static_cast<int>(std::floor(y0 + t * (y1 - y0))), 20, 40, 140, 0.85);
    }
  }
  auto marker = [&](Pose2D p, std::array<std::uint8_t, 3> rgb) {
    double px, py;
    to_px(p, px, py);
    for (int dy = -4; dy <= 4; ++dy) {
      for (int dx = -4; dx <= 4; ++dx) {
        if (dx * dx + dy * dy <= 16) img.set(static_cast<int>(px) + dx, static_cast<int>(py) + dy, rgb[0], rgb[1], rgb[2]);
      }
    }
  };
  if (!traj.empty()) {
    marker(traj.front().truth, {0, 120, 255});
    marker(traj.back().truth, {255, 140, 0});
  }
  return img;
}

}  // namespace tripodal::app
