#include "tripodal/navi/distance_field.hpp"

#include <cmath>
#include <limits>
#include <stdexcept>

namespace tripodal::navi {

namespace {

// 1-D squared distance transform of f (Felzenszwalb & Huttenlocher 2012) into d; v and z are
// scratch buffers of size n and n + 1.
void edt_1d(const double* f, double* d, int n, int* v, double* z) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  int k = 0;
  v[0] = 0;
  z[0] = -kInf;
  z[1] = kInf;
  for (int q = 1; q < n; ++q) {
    if (f[q] == kInf) continue;  // an infinite parabola never enters the envelope
    if (f[v[k]] == kInf) {       // the envelope so far is only an infinite one: replace it
      v[k] = q;
      z[k] = -kInf;
      z[k + 1] = kInf;
      continue;
    }
    double s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k]);
    while (s <= z[k]) {
      --k;
      s = ((f[q] + q * q) - (f[v[k]] + v[k] * v[k])) / (2.0 * q - 2.0 * v[k]);
    }
    ++k;
    v[k] = q;
    z[k] = s;
    z[k + 1] = kInf;
  }
  k = 0;
  for (int q = 0; q < n; ++q) {
    while (z[k + 1] < q) ++k;
    const double dq = q - v[k];
    d[q] = f[v[k]] == kInf ? kInf : dq * dq + f[v[k]];
  }
}

}  // namespace

DistanceField::DistanceField(const OccupancyGrid& grid, bool unknown_is_obstacle)
    : width_(grid.width()), height_(grid.height()), resolution_m_(grid.resolution_m()) {
  std::vector<bool> obstacle(grid.size());
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const Occupancy s = grid.state(i);
    obstacle[i] = s == Occupancy::occupied || (unknown_is_obstacle && s == Occupancy::unknown);
  }
  compute(obstacle, true);
}

DistanceField::DistanceField(int width, int height, double resolution_m, const std::vector<bool>& obstacle,
                             bool outside_is_obstacle)
    : width_(width), height_(height), resolution_m_(resolution_m) {
  if (width < 0 || height < 0 ||
      obstacle.size() != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw std::invalid_argument("DistanceField: obstacle mask size does not match the grid");
  }
  compute(obstacle, outside_is_obstacle);
}

void DistanceField::compute(const std::vector<bool>& obstacle, bool outside_is_obstacle) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  // Pad by one ring of obstacle cells so the outside of the grid counts as obstacle.
  const int w = width_ + 2;
  const int h = height_ + 2;
  std::vector<double> sq(static_cast<std::size_t>(w) * static_cast<std::size_t>(h), kInf);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool border = x == 0 || y == 0 || x == w - 1 || y == h - 1;
      const bool obs = border ? outside_is_obstacle : obstacle[static_cast<std::size_t>(y - 1) * static_cast<std::size_t>(width_) +
                                          static_cast<std::size_t>(x - 1)];
      if (obs) sq[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] = 0.0;
    }
  }
  const int n = w > h ? w : h;
  std::vector<double> f(static_cast<std::size_t>(n)), d(static_cast<std::size_t>(n));
  std::vector<int> v(static_cast<std::size_t>(n));
  std::vector<double> z(static_cast<std::size_t>(n) + 1);
  // Index arithmetic in size_t: an int product could overflow before it is widened.
  const auto at = [w](int x, int y) { return static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x); };
  for (int x = 0; x < w; ++x) {  // columns
    for (int y = 0; y < h; ++y) f[static_cast<std::size_t>(y)] = sq[at(x, y)];
    edt_1d(f.data(), d.data(), h, v.data(), z.data());
    for (int y = 0; y < h; ++y) sq[at(x, y)] = d[static_cast<std::size_t>(y)];
  }
  for (int y = 0; y < h; ++y) {  // rows
    double* row = &sq[at(0, y)];
    for (int x = 0; x < w; ++x) f[static_cast<std::size_t>(x)] = row[x];
    edt_1d(f.data(), row, w, v.data(), z.data());
  }
  distance_m_.assign(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_), 0.0F);
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      distance_m_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)] =
          static_cast<float>(std::sqrt(sq[at(x + 1, y + 1)]) * resolution_m_);
    }
  }
}

}  // namespace tripodal::navi
