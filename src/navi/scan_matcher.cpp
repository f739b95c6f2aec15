#include "tripodal/navi/scan_matcher.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <utility>

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "tripodal/navi/distance_field.hpp"

namespace tripodal::navi {

namespace {

// How sharply the covariance weights fall with the match quality: a pose whose quality is lower
// by this much than the best weighs 1/e. A one-cell shift on a wall costs about 0.05 of quality
// with sigma 0.1 m, so the covariance of a clear match is about a cell, and a corridor (that
// shifts without loss along its axis) stretches it along the axis as it should.
constexpr double kQualityScale = 0.05;
// How far (cells, heading steps) around the best pose the covariance looks: beyond a few cells
// the weights of a clear match are nil, and a corridor's spread shows within this reach.
constexpr int kCovarianceReach = 4;

bool positive_finite(double v) { return std::isfinite(v) && v > 0.0; }

// static_cast<int>(std::floor(v)) for v well within the range of int, without the floor's range
// and sign handling: the cast truncates towards zero, one too high for a negative non-integer.
int floor_int(double v) noexcept {
  const int t = static_cast<int>(v);
  return t - static_cast<int>(v < t);
}

}  // namespace

void validate(const ScanMatcherOptions& o, const SourceLocation& where) {
  Diagnostics d;
  auto need = [&](bool ok, const std::string& what) {
    if (!ok) d.error(where, "scan matcher: " + what);
  };
  need(positive_finite(o.sigma_m), "sigma_m must be a number > 0, got " + std::to_string(o.sigma_m));
  need(positive_finite(o.max_range_m), "max_range_m must be a number > 0, got " + std::to_string(o.max_range_m));
  need(o.max_points >= 3 && o.max_points <= 100000,
       "max_points must be 3..100000, got " + std::to_string(o.max_points));
  need(std::isfinite(o.search_xy_m) && o.search_xy_m >= 0.0 && o.search_xy_m <= 5.0,
       "search_xy_m must be 0..5 m, got " + std::to_string(o.search_xy_m));
  need(std::isfinite(o.search_theta_rad) && o.search_theta_rad >= 0.0 && o.search_theta_rad <= std::numbers::pi,
       "search_theta_rad must be 0..pi, got " + std::to_string(o.search_theta_rad));
  need(positive_finite(o.angular_step_rad) && o.angular_step_rad <= 0.5,
       "angular_step_rad must be > 0 and <= 0.5, got " + std::to_string(o.angular_step_rad));
  need(positive_finite(o.global_angular_step_rad) && o.global_angular_step_rad <= 0.5,
       "global_angular_step_rad must be > 0 and <= 0.5, got " + std::to_string(o.global_angular_step_rad));
  need(positive_finite(o.global_max_range_m), "global_max_range_m must be a number > 0, got " +
                                                  std::to_string(o.global_max_range_m));
  need(o.global_levels >= 1 && o.global_levels <= 10, "global_levels must be 1..10, got " +
                                                          std::to_string(o.global_levels));
  need(o.global_max_nodes >= 0, "global_max_nodes must be >= 0 (0: no budget), got " + std::to_string(o.global_max_nodes));
  need(std::isfinite(o.max_search_xy_m) && o.max_search_xy_m >= 0.0 && o.max_search_xy_m <= 5.0,
       "max_search_xy_m must be 0..5 m, got " + std::to_string(o.max_search_xy_m));
  need(std::isfinite(o.max_search_theta_rad) && o.max_search_theta_rad >= 0.0 &&
           o.max_search_theta_rad <= std::numbers::pi,
       "max_search_theta_rad must be 0..pi, got " + std::to_string(o.max_search_theta_rad));
  if (std::max(o.search_theta_rad, o.max_search_theta_rad) / std::max(o.angular_step_rad, 1e-9) > 1000) {
    d.error(where, "scan matcher: the tracking window is too large for its heading step (more than 1000 headings "
                   "each side)");
  }
  if (d.has_errors()) throw ConfigError(d);
}

ScanMatcher::ScanMatcher(const OccupancyGrid& map, ScanMatcherOptions options, const SourceLocation& where)
    : map_(map), options_(options) {
  validate(options_, where);
  if (map.width() < 2 || map.height() < 2) {
    throw ConfigError(where, "scan matcher: the map is " + std::to_string(map.width()) + " x " +
                                 std::to_string(map.height()) + " cells, expected at least 2 x 2");
  }
  if (map.count(Occupancy::occupied) == 0) {
    throw ConfigError(where, "scan matcher: the map has no occupied cell, nothing a scan could be matched against");
  }
  cell_m_ = map.resolution_m();
  width_ = map.width();
  height_ = map.height();
  const std::size_t cells = map.size();
  // The likelihood of a return is a function of its distance to the surface of a wall, measured
  // from the wall's boundary cells: occupied cells beside one that is not (were the whole
  // thickness of a wall a peak, a scan could slide inside thick walls at no cost). Unknown space
  // is not a wall a beam can hit: open, for this purpose; the outside of the map is solid (no beam
  // comes from there). In a map built from scans the surface lies inside the boundary cells, at
  // their centre on average: the distance is the one between cell centres. In a map drawn as
  // solid cells it is the face between a boundary cell and its open neighbour, half a cell from
  // the centres of both: outside a wall, the distance to the nearest boundary cell minus half a
  // cell; inside, the one to the nearest open cell beside a wall minus half a cell.
  std::vector<bool> surface(cells), facing(cells), inside(cells);
  auto solid = [&](int x, int y) {
    return x < 0 || y < 0 || x >= width_ || y >= height_ || map.state(map.index({x, y})) == Occupancy::occupied;
  };
  for (std::size_t i = 0; i < cells; ++i) {
    const CellIndex c = map.cell(i);
    const bool s = solid(c.x, c.y);
    inside[i] = s;
    const int solid_neighbours = static_cast<int>(solid(c.x + 1, c.y)) + static_cast<int>(solid(c.x - 1, c.y)) +
                                 static_cast<int>(solid(c.x, c.y + 1)) + static_cast<int>(solid(c.x, c.y - 1));
    surface[i] = s && solid_neighbours < 4;
    facing[i] = !s && solid_neighbours > 0;
  }
  const DistanceField to_surface(width_, height_, cell_m_, surface, false);
  std::optional<DistanceField> to_facing;
  if (options_.surface_at_cell_face) to_facing.emplace(width_, height_, cell_m_, facing, false);
  field_.resize(cells);
  const double k = -0.5 / (options_.sigma_m * options_.sigma_m);
  const double half_cell = 0.5 * cell_m_;
  for (std::size_t i = 0; i < cells; ++i) {
    double d = to_surface.distance_m(i);
    if (to_facing) d = std::max(0.0, (inside[i] ? to_facing->distance_m(i) : d) - half_cell);
    field_[i] = std::isfinite(d) ? static_cast<float>(std::exp(k * d * d)) : 0.0f;
  }

  free_sum_.assign(static_cast<std::size_t>(width_ + 1) * static_cast<std::size_t>(height_ + 1), 0);
  for (int y = 0; y < height_; ++y) {
    int row = 0;
    for (int x = 0; x < width_; ++x) {
      row += map_.is_free({x, y}) ? 1 : 0;
      const std::size_t at =
          static_cast<std::size_t>(y + 1) * static_cast<std::size_t>(width_ + 1) + static_cast<std::size_t>(x) + 1;
      free_sum_[at] = free_sum_[at - static_cast<std::size_t>(width_ + 1)] + row;
    }
  }
  // Max-pooled pyramid for the searches, on the domain extended by pad_ cells of zeros on every side
  // (a tile partly outside the grid still bounds its inside; the tracking search reads a point's
  // cells near the grid's edges without a check each).
  const int levels = options_.global_levels;
  pad_ = 1 << levels;
  const int ew = width_ + 2 * pad_, eh = height_ + 2 * pad_;
  pooled_.assign(static_cast<std::size_t>(levels) + 1, std::vector<float>(static_cast<std::size_t>(ew) * eh, 0.0f));
  for (int y = 0; y < height_; ++y) {
    for (int x = 0; x < width_; ++x) {
      pooled_[0][static_cast<std::size_t>(y + pad_) * ew + (x + pad_)] = field_[static_cast<std::size_t>(y) * width_ + x];
    }
  }
  for (int h = 1; h <= levels; ++h) {
    const int half = 1 << (h - 1);
    const std::vector<float>& lo = pooled_[static_cast<std::size_t>(h) - 1];
    std::vector<float>& hi = pooled_[static_cast<std::size_t>(h)];
    auto at = [&](int ex, int ey) -> float {
      return ex < ew && ey < eh ? lo[static_cast<std::size_t>(ey) * ew + ex] : 0.0f;
    };
    for (int ey = 0; ey < eh; ++ey) {
      for (int ex = 0; ex < ew; ++ex) {
        hi[static_cast<std::size_t>(ey) * ew + ex] =
            std::max(std::max(at(ex, ey), at(ex + half, ey)), std::max(at(ex, ey + half), at(ex + half, ey + half)));
      }
    }
  }

  const auto n = static_cast<std::size_t>(options_.max_points);
  px_.reserve(n);
  py_.reserve(n);
  range_.reserve(n);
  const int nx = static_cast<int>(std::ceil(std::max(options_.search_xy_m, options_.max_search_xy_m) / cell_m_));
  const int nt = static_cast<int>(
      std::ceil(std::max(options_.search_theta_rad, options_.max_search_theta_rad) / options_.angular_step_rad));
  const std::size_t headings = 2 * static_cast<std::size_t>(nt) + 1;
  cx_.resize(headings * n);
  cy_.resize(headings * n);
  at_.resize(headings * n);
  const std::size_t side = static_cast<std::size_t>(nx) + 1;
  blocks_.resize(headings * side * side);
}

std::size_t ScanMatcher::set_scan(const LaserScan& scan, const Pose2D& base_from_laser) noexcept {
  px_.clear();
  py_.clear();
  range_.clear();
  const std::size_t n = scan.ranges_m.size();
  const std::size_t cap = static_cast<std::size_t>(options_.max_points);
  const std::size_t stride = n <= cap ? 1 : (n + cap - 1) / cap;
  const double lo = std::max(scan.range_min_m, 1e-3);
  const double hi = std::min(scan.range_max_m > 0.0 ? scan.range_max_m : options_.max_range_m, options_.max_range_m);
  const double c0 = std::cos(base_from_laser.theta_rad), s0 = std::sin(base_from_laser.theta_rad);
  origin_x_ = base_from_laser.x_m;
  origin_y_ = base_from_laser.y_m;
  for (std::size_t i = 0; i < n && px_.size() < cap; i += stride) {
    const double r = scan.ranges_m[i];
    // a return at the maximum range is the scanner's "nothing seen", not a wall
    if (!std::isfinite(r) || r < lo || r >= hi) continue;
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.angle_increment_rad;
    const double lx = r * std::cos(a), ly = r * std::sin(a);
    px_.push_back(static_cast<float>(base_from_laser.x_m + c0 * lx - s0 * ly));
    py_.push_back(static_cast<float>(base_from_laser.y_m + s0 * lx + c0 * ly));
    range_.push_back(static_cast<float>(std::hypot(px_.back(), py_.back())));
  }
  return px_.size();
}

ScanMatcher::GridPose ScanMatcher::to_grid(const Pose2D& p) const noexcept {
  const Point2D g = map_.to_grid_frame({p.x_m, p.y_m});
  return {g.x_m / cell_m_, g.y_m / cell_m_, p.theta_rad - map_.origin().theta_rad};
}

Pose2D ScanMatcher::from_grid(const GridPose& g) const noexcept {
  const Point2D p = map_.from_grid_frame({g.x * cell_m_, g.y * cell_m_});
  return {p.x_m, p.y_m, wrap_angle(g.theta + map_.origin().theta_rad)};
}

ScanMatcher::Rotated ScanMatcher::rotated(std::size_t heading, std::size_t count) noexcept {
  const std::size_t from = heading * count;
  return {cx_.data() + from, cy_.data() + from, at_.data() + from};
}

void ScanMatcher::rotate_points(double theta, double x, double y, std::size_t count, int reach,
                                const Rotated& out) const noexcept {
  const double c = std::cos(theta) / cell_m_, s = std::sin(theta) / cell_m_;
  const int ew = width_ + 2 * pad_;
  auto place = [&](std::size_t i, int cx, int cy) {
    out.cx[i] = cx;
    out.cy[i] = cy;
    const bool inside = cx - reach >= -pad_ && cx + reach < width_ + pad_ && cy - reach >= -pad_ && cy + reach < height_ + pad_;
    out.at[i] = inside ? (cy + pad_) * ew + cx + pad_ : -1;
  };
  std::size_t i = 0;
#if defined(__SSE2__)
  // two points per pass in SSE2 doubles, each lane the scalar code's operations in its order
  const __m128d vc = _mm_set1_pd(c), vs = _mm_set1_pd(s), vx = _mm_set1_pd(x), vy = _mm_set1_pd(y);
  // inside: lo < cx < hi and the same in y, as place() below
  const __m128i lo_x = _mm_set1_epi32(reach - pad_ - 1), hi_x = _mm_set1_epi32(width_ + pad_ - reach);
  const __m128i lo_y = _mm_set1_epi32(reach - pad_ - 1), hi_y = _mm_set1_epi32(height_ + pad_ - reach);
  const __m128i stride = _mm_set1_epi32(ew), base = _mm_set1_epi32(pad_ * ew + pad_);
  for (; i + 2 <= count; i += 2) {
    const __m128d px = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(px_.data() + i))));
    const __m128d py = _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(py_.data() + i))));
    const __m128d u = _mm_sub_pd(_mm_add_pd(vx, _mm_mul_pd(vc, px)), _mm_mul_pd(vs, py));
    const __m128d v = _mm_add_pd(_mm_add_pd(vy, _mm_mul_pd(vs, px)), _mm_mul_pd(vc, py));
    // floor: truncated towards zero, then one less where that rose above (negative non-integers);
    // the comparison's all-ones lanes are -1 as integers
    const __m128i tu = _mm_cvttpd_epi32(u), tv = _mm_cvttpd_epi32(v);
    const __m128i below_u = _mm_shuffle_epi32(_mm_castpd_si128(_mm_cmplt_pd(u, _mm_cvtepi32_pd(tu))), 0x08);
    const __m128i below_v = _mm_shuffle_epi32(_mm_castpd_si128(_mm_cmplt_pd(v, _mm_cvtepi32_pd(tv))), 0x08);
    const __m128i cu = _mm_add_epi32(tu, below_u), cv = _mm_add_epi32(tv, below_v);
    // the index in the padded grid, cv * ew by the unsigned 32 x 32 -> 64 bit product of lanes 0
    // and 2 (the low 32 bits are the signed product's), and -1 for a point not inside
    const __m128i rows = _mm_shuffle_epi32(_mm_mul_epu32(_mm_shuffle_epi32(cv, 0x10), stride), 0x08);
    const __m128i index = _mm_add_epi32(_mm_add_epi32(rows, cu), base);
    const __m128i inside = _mm_and_si128(_mm_and_si128(_mm_cmpgt_epi32(cu, lo_x), _mm_cmplt_epi32(cu, hi_x)),
                                         _mm_and_si128(_mm_cmpgt_epi32(cv, lo_y), _mm_cmplt_epi32(cv, hi_y)));
    const __m128i at = _mm_or_si128(_mm_and_si128(inside, index), _mm_andnot_si128(inside, _mm_set1_epi32(-1)));
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out.cx + i), cu);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out.cy + i), cv);
    _mm_storel_epi64(reinterpret_cast<__m128i*>(out.at + i), at);
  }
#endif
  for (; i < count; ++i) place(i, floor_int(x + c * px_[i] - s * py_[i]), floor_int(y + s * px_[i] + c * py_[i]));
}

template <int kSums>
void ScanMatcher::padded_sums(int level, const Rotated& r, std::size_t count, const int* dx, const int* dy,
                              float* out) const noexcept {
  const float* f = pooled_[static_cast<std::size_t>(level)].data();
  const int ew = width_ + 2 * pad_;
  const auto w = static_cast<unsigned>(ew), h = static_cast<unsigned>(height_ + 2 * pad_);
  std::array<int, kSums> offset{};
  for (int j = 0; j < kSums; ++j) offset[static_cast<std::size_t>(j)] = dy[j] * ew + dx[j];
  std::array<float, kSums> acc{};
  for (std::size_t i = 0; i < count; ++i) {
    const int at = r.at[i];
    if (at >= 0) {
      for (int j = 0; j < kSums; ++j) acc[static_cast<std::size_t>(j)] += f[at + offset[static_cast<std::size_t>(j)]];
      continue;
    }
    for (int j = 0; j < kSums; ++j) {
      const auto ex = static_cast<unsigned>(r.cx[i] + dx[j] + pad_), ey = static_cast<unsigned>(r.cy[i] + dy[j] + pad_);
      if (ex < w && ey < h) acc[static_cast<std::size_t>(j)] += f[static_cast<std::size_t>(ey) * w + ex];
    }
  }
  std::copy(acc.begin(), acc.end(), out);
}

void ScanMatcher::padded_sums(int level, const Rotated& r, std::size_t count, const int* dx, const int* dy, int m,
                              float* out) const noexcept {
  switch (m) {
    case 1:
      padded_sums<1>(level, r, count, dx, dy, out);
      break;
    case 2:
      padded_sums<2>(level, r, count, dx, dy, out);
      break;
    case 3:
      padded_sums<3>(level, r, count, dx, dy, out);
      break;
    default:
      padded_sums<4>(level, r, count, dx, dy, out);
      break;
  }
}

template <int kCells>
void ScanMatcher::row_sums(const Rotated& r, std::size_t count, int dx, int dy, float* out) const noexcept {
  const float* f = pooled_[0].data();
  const int ew = width_ + 2 * pad_;
  const auto w = static_cast<unsigned>(ew), h = static_cast<unsigned>(height_ + 2 * pad_);
  const int offset = dy * ew + dx;
  // A point whose row leaves the padded grid adds 0 to the cells outside: x + 0.0f is x (the sums
  // are never -0), so the same floats as skipping them.
  auto checked_row = [&](std::size_t i, float* row) {
    const auto ey = static_cast<unsigned>(r.cy[i] + dy + pad_);
    for (int j = 0; j < kCells; ++j) {
      const auto ex = static_cast<unsigned>(r.cx[i] + dx + j + pad_);
      row[j] = ex < w && ey < h ? f[static_cast<std::size_t>(ey) * w + ex] : 0.0f;
    }
  };
#if defined(__SSE2__)
  // four cells per SSE2 addition: each lane adds the same floats in the same order as a scalar sum
  constexpr std::size_t kQuads = kCells / 4;
  static_assert(kQuads > 0);
  __m128 quad[kQuads];  // NOLINT(cppcoreguidelines-avoid-c-arrays): std::array drops __m128's alignment attribute
  for (__m128& q : quad) q = _mm_setzero_ps();
  std::array<float, kCells - 4 * kQuads> rest{};
  std::array<float, kCells> spill{};
  for (std::size_t i = 0; i < count; ++i) {
    const float* row = nullptr;
    if (r.at[i] >= 0) {
      row = f + r.at[i] + offset;
    } else {
      checked_row(i, spill.data());
      row = spill.data();
    }
    for (std::size_t q = 0; q < kQuads; ++q) quad[q] = _mm_add_ps(quad[q], _mm_loadu_ps(row + 4 * q));
    for (std::size_t j = 0; j < rest.size(); ++j) rest[j] += row[4 * kQuads + j];
  }
  for (std::size_t q = 0; q < kQuads; ++q) _mm_storeu_ps(out + 4 * q, quad[q]);
  std::copy(rest.begin(), rest.end(), out + 4 * kQuads);
#else
  std::array<float, kCells> acc{};
  std::array<float, kCells> spill{};
  for (std::size_t i = 0; i < count; ++i) {
    const float* row = nullptr;
    if (r.at[i] >= 0) {
      row = f + r.at[i] + offset;
    } else {
      checked_row(i, spill.data());
      row = spill.data();
    }
    for (int j = 0; j < kCells; ++j) acc[static_cast<std::size_t>(j)] += row[j];
  }
  std::copy(acc.begin(), acc.end(), out);
#endif
}

float ScanMatcher::pooled_sum(int level, const int* cx, const int* cy, std::size_t count, int x, int y) const noexcept {
  const std::vector<float>& f = pooled_[static_cast<std::size_t>(level)];
  const auto w = static_cast<unsigned>(width_ + 2 * pad_), h = static_cast<unsigned>(height_ + 2 * pad_);
  float s = 0.0f;
  for (std::size_t i = 0; i < count; ++i) {
    const auto ex = static_cast<unsigned>(cx[i] + x + pad_), ey = static_cast<unsigned>(cy[i] + y + pad_);
    if (ex < w && ey < h) s += f[static_cast<std::size_t>(ey) * w + ex];
  }
  return s;
}

double ScanMatcher::score_bilinear(const GridPose& g) const noexcept {
  const double c = std::cos(g.theta) / cell_m_, s = std::sin(g.theta) / cell_m_;
  auto at = [&](int x, int y) -> double {
    return static_cast<unsigned>(x) < static_cast<unsigned>(width_) && static_cast<unsigned>(y) < static_cast<unsigned>(height_)
               ? field_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)]
               : 0.0;
  };
  // The four cells from (x, y) up and right, 0 outside the grid. Inside the grid (the common
  // case) they are read without a check each: the same values, so the same sum.
  const auto last_x = static_cast<unsigned>(width_ - 1), last_y = static_cast<unsigned>(height_ - 1);
  auto corners = [&](int x, int y, std::array<double, 4>& f) {
    if (static_cast<unsigned>(x) < last_x && static_cast<unsigned>(y) < last_y) {
      const float* cell =
          field_.data() + static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x);
      f = {cell[0], cell[1], cell[width_], cell[width_ + 1]};
    } else {
      f = {at(x, y), at(x + 1, y), at(x, y + 1), at(x + 1, y + 1)};
    }
  };
  const std::size_t n = px_.size();
  double total = 0.0;
  std::size_t i = 0;
#if defined(__SSE2__)
  // Two points per pass, in SSE2 doubles: every lane computes what the scalar code below does (the
  // same operations in the same order, no fused multiply-add), and the lanes are added to the total
  // in the points' order, so the sum is the same double.
  const __m128d vc = _mm_set1_pd(c), vs = _mm_set1_pd(s), gx = _mm_set1_pd(g.x), gy = _mm_set1_pd(g.y);
  const __m128d half = _mm_set1_pd(0.5), one = _mm_set1_pd(1.0);
  auto floor_pd = [&](__m128d v) {
    // truncated towards zero, then one less where that rose above (negative non-integers)
    const __m128d t = _mm_cvtepi32_pd(_mm_cvttpd_epi32(v));
    return _mm_sub_pd(t, _mm_and_pd(_mm_cmplt_pd(v, t), one));
  };
  // two adjacent floats of the field as two doubles
  auto pair = [](const float* p) { return _mm_cvtps_pd(_mm_castsi128_ps(_mm_loadl_epi64(reinterpret_cast<const __m128i*>(p)))); };
  std::array<double, 4> f0{}, f1{};
  for (; i + 2 <= n; i += 2) {
    const __m128d px = pair(px_.data() + i), py = pair(py_.data() + i);
    const __m128d u = _mm_sub_pd(_mm_sub_pd(_mm_add_pd(gx, _mm_mul_pd(vc, px)), _mm_mul_pd(vs, py)), half);
    const __m128d v = _mm_sub_pd(_mm_add_pd(_mm_add_pd(gy, _mm_mul_pd(vs, px)), _mm_mul_pd(vc, py)), half);
    const __m128d fu = floor_pd(u), fv = floor_pd(v);
    const __m128i xs = _mm_cvttpd_epi32(fu), ys = _mm_cvttpd_epi32(fv);
    const int x0 = _mm_cvtsi128_si32(xs), y0 = _mm_cvtsi128_si32(ys);
    const int x1 = _mm_cvtsi128_si32(_mm_srli_si128(xs, 4)), y1 = _mm_cvtsi128_si32(_mm_srli_si128(ys, 4));
    __m128d f00, f10, f01, f11;
    if (static_cast<unsigned>(x0) < last_x && static_cast<unsigned>(y0) < last_y && static_cast<unsigned>(x1) < last_x &&
        static_cast<unsigned>(y1) < last_y) {
      // each point's two rows of two cells as doubles, then the lanes regrouped by corner
      const float* c0 =
          field_.data() + static_cast<std::size_t>(y0) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x0);
      const float* c1 =
          field_.data() + static_cast<std::size_t>(y1) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x1);
      const __m128d b0 = pair(c0), t0 = pair(c0 + width_), b1 = pair(c1), t1 = pair(c1 + width_);
      f00 = _mm_unpacklo_pd(b0, b1);
      f10 = _mm_unpackhi_pd(b0, b1);
      f01 = _mm_unpacklo_pd(t0, t1);
      f11 = _mm_unpackhi_pd(t0, t1);
    } else {
      corners(x0, y0, f0);
      corners(x1, y1, f1);
      f00 = _mm_setr_pd(f0[0], f1[0]);
      f10 = _mm_setr_pd(f0[1], f1[1]);
      f01 = _mm_setr_pd(f0[2], f1[2]);
      f11 = _mm_setr_pd(f0[3], f1[3]);
    }
    const __m128d a = _mm_sub_pd(u, fu), b = _mm_sub_pd(v, fv);
    const __m128d na = _mm_sub_pd(one, a), nb = _mm_sub_pd(one, b);
    const __m128d lower = _mm_add_pd(_mm_mul_pd(na, f00), _mm_mul_pd(a, f10));
    const __m128d upper = _mm_add_pd(_mm_mul_pd(na, f01), _mm_mul_pd(a, f11));
    const __m128d value = _mm_add_pd(_mm_mul_pd(nb, lower), _mm_mul_pd(b, upper));
    total += _mm_cvtsd_f64(value);
    total += _mm_cvtsd_f64(_mm_unpackhi_pd(value, value));
  }
#endif
  std::array<double, 4> f{};
  for (; i < n; ++i) {
    // the field holds cell-centre values: interpolate between the four nearest centres
    const double u = g.x + c * px_[i] - s * py_[i] - 0.5;
    const double v = g.y + s * px_[i] + c * py_[i] - 0.5;
    const double fu = std::floor(u), fv = std::floor(v);
    const double a = u - fu, b = v - fv;
    corners(static_cast<int>(fu), static_cast<int>(fv), f);
    total += (1 - b) * ((1 - a) * f[0] + a * f[1]) + b * ((1 - a) * f[2] + a * f[3]);
  }
  return total;
}

ScanMatcher::GridPose ScanMatcher::hill_climb(GridPose g, double step_cells, double step_rad, double* score) const noexcept {
  double best = score_bilinear(g);
  // After a move, the neighbour back where the climb came from scores what that pose scored, less
  // than the best: it is not scored again (only when its coordinates are the same doubles).
  GridPose from{std::nan(""), std::nan(""), std::nan("")};
  for (int halvings = 0, moves = 0; halvings < 4 && moves < 60; ++moves) {
    const GridPose around[6] = {{g.x + step_cells, g.y, g.theta}, {g.x - step_cells, g.y, g.theta},
                                {g.x, g.y + step_cells, g.theta}, {g.x, g.y - step_cells, g.theta},
                                {g.x, g.y, g.theta + step_rad},   {g.x, g.y, g.theta - step_rad}};
    int pick = -1;
    for (int k = 0; k < 6; ++k) {
      const GridPose& p = around[k];
      if (p.x == from.x && p.y == from.y && p.theta == from.theta) continue;
      const double s = score_bilinear(p);
      if (s > best) {
        best = s;
        pick = k;
      }
    }
    if (pick >= 0) {
      from = g;
      g = around[pick];
    } else {
      step_cells *= 0.5;
      step_rad *= 0.5;
      ++halvings;
    }
  }
  *score = best;
  return g;
}

double ScanMatcher::quality_at(const Pose2D& pose) const noexcept {
  return px_.empty() ? 0.0 : score_bilinear(to_grid(pose)) / static_cast<double>(px_.size());
}

namespace {
constexpr double kClutterRange = 2.0;  // metres from the base
}  // namespace

double ScanMatcher::explained_quality(const Pose2D& pose) const noexcept {
  if (px_.empty()) return 0.0;
  const GridPose g = to_grid(pose);
  const double c = std::cos(g.theta) / cell_m_, s = std::sin(g.theta) / cell_m_;
  auto field_at = [&](int x, int y) -> double {
    return static_cast<unsigned>(x) < static_cast<unsigned>(width_) && static_cast<unsigned>(y) < static_cast<unsigned>(height_)
               ? field_[static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)]
               : 0.0;
  };
  auto wall_at = [&](double u, double v) {
    const int x = static_cast<int>(std::floor(u)), y = static_cast<int>(std::floor(v));
    return x < 0 || y < 0 || x >= width_ || y >= height_ || map_.state(map_.index({x, y})) == Occupancy::occupied;
  };
  // Two sigmas from every wall: the field is below exp(-2) there.
  const double far = std::exp(-2.0);
  const double ou = g.x + c * origin_x_ - s * origin_y_, ov = g.y + s * origin_x_ + c * origin_y_;
  double all = 0.0, kept = 0.0;
  std::size_t left_out = 0;
  for (std::size_t i = 0; i < px_.size(); ++i) {
    const double pu = g.x + c * px_[i] - s * py_[i], pv = g.y + s * px_[i] + c * py_[i];
    const double u = pu - 0.5, v = pv - 0.5;
    const double fu = std::floor(u), fv = std::floor(v);
    const int x = static_cast<int>(fu), y = static_cast<int>(fv);
    const double a = u - fu, b = v - fv;
    const double f = (1 - b) * ((1 - a) * field_at(x, y) + a * field_at(x + 1, y)) +
                     b * ((1 - a) * field_at(x, y + 1) + a * field_at(x + 1, y + 1));
    all += f;
    // Only near returns: what the map does not hold and matters is beside the robot (a cart, a
    // person), and a wrong pose puts returns in open space at every range.
    if (f < far && range_[i] < kClutterRange) {
      // Walk the beam by half cells: a beam that crossed a wall of the map contradicts the pose
      // (it should have stopped there) and counts; one through open space only is left out.
      const double du = pu - ou, dv = pv - ov;
      const int steps = static_cast<int>(2.0 * std::hypot(du, dv));
      bool crossed = false;
      for (int k = 1; k < steps && !crossed; ++k) {
        const double t = static_cast<double>(k) / steps;
        crossed = wall_at(ou + t * du, ov + t * dv);
      }
      if (!crossed) {
        ++left_out;
        continue;
      }
    }
    kept += f;
  }
  const std::size_t n = px_.size();
  if (3 * left_out > n) return all / static_cast<double>(n);
  return kept / static_cast<double>(n - left_out);
}

ScanMatch ScanMatcher::match(const Pose2D& predicted, double search_xy_m, double search_theta_rad) noexcept {
  ScanMatch out;
  out.pose = predicted;
  const std::size_t n = px_.size();
  out.points = n;
  if (n == 0) return out;
  const GridPose g0 = to_grid(predicted);
  const int nx = static_cast<int>(std::ceil(std::clamp(search_xy_m, 0.0, options_.max_search_xy_m) / cell_m_));
  const int nt = static_cast<int>(
      std::ceil(std::clamp(search_theta_rad, 0.0, options_.max_search_theta_rad) / options_.angular_step_rad));
  const double step = options_.angular_step_rad;
  // Branch and bound over the max-pooled fields (as the global search): every heading's window is
  // tiled with blocks of 2^top cells (about two per axis), each bounded by the pooled field of its
  // level; the blocks are explored best bound first, depth first (a block's four sub-blocks, best
  // first, down to single cells scored exactly), and a block whose bound falls below the best
  // full score is cut with everything in it. The answer is the exhaustive search's: a bound is
  // never below the score of a cell it covers (sums of larger terms in the same order).
  const int side = 2 * nx + 1;
  int top = 0;
  while (top < options_.global_levels && (1 << (top + 1)) < side) ++top;
  const int tile = 1 << top;
  // every cell a point is read at: the window, and the covariance's reach around any cell of it
  const int reach = nx + kCovarianceReach;
  std::size_t count = 0;
  for (int k = -nt; k <= nt; ++k) {
    const int heading = k + nt;
    const Rotated r = rotated(static_cast<std::size_t>(heading), n);
    rotate_points(g0.theta + k * step, g0.x, g0.y, n, reach, r);
    // the heading's blocks, bounded four at a time in one pass over the points
    std::array<int, 4> bx{}, by{};
    std::array<float, 4> bound{};
    int m = 0;
    auto flush = [&] {
      padded_sums(top, r, n, bx.data(), by.data(), m, bound.data());
      for (int j = 0; j < m; ++j) {
        const auto i = static_cast<std::size_t>(j);
        blocks_[count++] = {bound[i], k, bx[i], by[i]};
      }
      m = 0;
    };
    for (int dy = -nx; dy <= nx; dy += tile) {
      for (int dx = -nx; dx <= nx; dx += tile) {
        bx[static_cast<std::size_t>(m)] = dx;
        by[static_cast<std::size_t>(m)] = dy;
        if (++m == 4) flush();
      }
    }
    if (m > 0) flush();
  }
  std::sort(blocks_.begin(), blocks_.begin() + static_cast<std::ptrdiff_t>(count),
            [](const Block& l, const Block& r) { return l.bound > r.bound; });
  float best = -1.0f;
  int bk = 0, bx = 0, by = 0;
  auto nearer = [](int k, int x, int y, int k2, int x2, int y2) {
    return std::abs(k) + std::abs(x) + std::abs(y) < std::abs(k2) + std::abs(x2) + std::abs(y2);
  };
  // Depth-first stack: at most four sub-blocks per level below the top (no allocation).
  struct Node {
    float bound;
    int level, k, dx, dy;
  };
  std::array<Node, 4 * 11 + 1> stack{};
  for (std::size_t c = 0; c < count; ++c) {
    const Block& blk = blocks_[c];
    if (blk.bound < best) break;
    std::size_t depth = 0;
    stack[depth++] = {blk.bound, top, blk.k, blk.dx, blk.dy};
    const int heading = blk.k + nt;
    const Rotated r = rotated(static_cast<std::size_t>(heading), n);
    while (depth > 0) {
      const Node node = stack[--depth];
      if (node.bound < best) continue;
      if (node.level == 0) {
        // ties go to the pose nearest the prediction (the odometry is the prior)
        if (node.bound > best || nearer(node.k, node.dx, node.dy, bk, bx, by)) {
          best = node.bound;
          bk = node.k;
          bx = node.dx;
          by = node.dy;
        }
        continue;
      }
      const int level = node.level - 1;
      const int half = 1 << level;
      // the (up to four) sub-blocks, bounded (level 0: scored) in one pass over the points
      std::array<int, 4> kx{}, ky{};
      std::array<float, 4> kb{};
      int all = 0;
      for (int y = node.dy; y <= std::min(node.dy + half, nx); y += half) {
        for (int x = node.dx; x <= std::min(node.dx + half, nx); x += half) {
          kx[static_cast<std::size_t>(all)] = x;
          ky[static_cast<std::size_t>(all)] = y;
          ++all;
        }
      }
      padded_sums(level, r, n, kx.data(), ky.data(), all, kb.data());
      std::array<Node, 4> kids{};
      int m = 0;
      for (int j = 0; j < all; ++j) {
        const auto i = static_cast<std::size_t>(j);
        if (kb[i] >= best) kids[static_cast<std::size_t>(m++)] = {kb[i], level, node.k, kx[i], ky[i]};
      }
      // pushed worst first so that the best is explored first
      // (an insertion sort of at most four: std::stable_sort would allocate its buffer)
      for (int i = 1; i < m; ++i) {
        const Node kid = kids[static_cast<std::size_t>(i)];
        int j = i;
        for (; j > 0 && kids[static_cast<std::size_t>(j) - 1].bound > kid.bound; --j) {
          kids[static_cast<std::size_t>(j)] = kids[static_cast<std::size_t>(j) - 1];
        }
        kids[static_cast<std::size_t>(j)] = kid;
      }
      for (int i = 0; i < m; ++i) stack[depth++] = kids[static_cast<std::size_t>(i)];
    }
  }
  // The covariance from the scores around the best pose, each weighted by how close its quality
  // comes to the best one.
  double sw = 0.0;
  std::array<double, 3> m1{};
  std::array<double, 6> m2{};  // xx xy xt yy yt tt
  const double inv_n = 1.0 / static_cast<double>(n);
  // The scores of a row of cells at once (row_sums): each point adds a run of adjacent cells of the
  // field, in the same order per cell as a single cell's score, so every score is the same float.
  constexpr int kReachCells = 2 * kCovarianceReach + 1;
  std::array<float, kReachCells> row{};
  for (int k = std::max(-nt, bk - kCovarianceReach); k <= std::min(nt, bk + kCovarianceReach); ++k) {
    const int heading = k + nt;
    const Rotated r = rotated(static_cast<std::size_t>(heading), n);
    for (int dy = by - kCovarianceReach; dy <= by + kCovarianceReach; ++dy) {
      row_sums<kReachCells>(r, n, bx - kCovarianceReach, dy, row.data());
      for (int dx = bx - kCovarianceReach; dx <= bx + kCovarianceReach; ++dx) {
        const int column = dx - bx + kCovarianceReach;  // 0 .. kReachCells - 1
        const float score = row[static_cast<std::size_t>(column)];
        const double w = std::exp((score - best) * inv_n / kQualityScale);
        if (w < 1e-6) continue;
        const double vx = (dx - bx) * cell_m_, vy = (dy - by) * cell_m_, vt = (k - bk) * step;
        sw += w;
        m1[0] += w * vx;
        m1[1] += w * vy;
        m1[2] += w * vt;
        m2[0] += w * vx * vx;
        m2[1] += w * vx * vy;
        m2[2] += w * vx * vt;
        m2[3] += w * vy * vy;
        m2[4] += w * vy * vt;
        m2[5] += w * vt * vt;
      }
    }
  }
  const GridPose coarse{g0.x + bx, g0.y + by, g0.theta + bk * step};
  double fine_score = 0.0;
  const GridPose fine = hill_climb(coarse, 0.5, 0.5 * step, &fine_score);
  out.pose = from_grid(fine);
  out.quality = fine_score * inv_n;
  const double mx = m1[0] / sw, my = m1[1] / sw, mt = m1[2] / sw;
  // the discretisation's own uncertainty (uniform over a step) is the floor
  const double fx = cell_m_ * cell_m_ / 12.0, ft = step * step / 12.0;
  const double xx = m2[0] / sw - mx * mx + fx, xy = m2[1] / sw - mx * my, xt = m2[2] / sw - mx * mt;
  const double yy = m2[3] / sw - my * my + fx, yt = m2[4] / sw - my * mt, tt = m2[5] / sw - mt * mt + ft;
  // the window is in the grid frame; rotate x, y into the map frame
  const double c = std::cos(map_.origin().theta_rad), s = std::sin(map_.origin().theta_rad);
  const double mxx = c * c * xx - 2 * c * s * xy + s * s * yy;
  const double myy = s * s * xx + 2 * c * s * xy + c * c * yy;
  const double mxy = c * s * (xx - yy) + (c * c - s * s) * xy;
  const double mxt = c * xt - s * yt, myt = s * xt + c * yt;
  out.covariance = {mxx, mxy, mxt, mxy, myy, myt, mxt, myt, tt};
  return out;
}

ScanMatch ScanMatcher::track(const Pose2D& predicted, const Pose2D& motion, const TrackingWindow& window) noexcept {
  const double moved_m = std::hypot(motion.x_m, motion.y_m), turned_rad = std::abs(wrap_angle(motion.theta_rad));
  ScanMatch m = match(predicted, options_.search_xy_m + window.m_per_m * moved_m,
                      options_.search_theta_rad + window.rad_per_rad * turned_rad + window.rad_per_m * moved_m);
  if (m.quality < window.retry_quality) {
    const ScanMatch wide = match(predicted, options_.max_search_xy_m, options_.max_search_theta_rad);
    if (wide.quality > m.quality) m = wide;
  }
  return m;
}

bool ScanMatcher::any_free(int x, int y, int side) const noexcept {
  const int x0 = std::max(x, 0), y0 = std::max(y, 0);
  const int x1 = std::min(x + side, width_), y1 = std::min(y + side, height_);
  if (x0 >= x1 || y0 >= y1) return false;
  const std::size_t w = static_cast<std::size_t>(width_) + 1;
  auto at = [&](int cx, int cy) { return free_sum_[static_cast<std::size_t>(cy) * w + static_cast<std::size_t>(cx)]; };
  return at(x1, y1) - at(x0, y1) - at(x1, y0) + at(x0, y0) > 0;
}

ScanMatch ScanMatcher::match_global() {
  // Only the nearer points: a heading step moves a far point by several cells, which the
  // pooled bounds would not cover.
  std::vector<std::size_t> near;
  near.reserve(px_.size());
  for (std::size_t i = 0; i < px_.size(); ++i) {
    if (range_[i] <= options_.global_max_range_m) near.push_back(i);
  }
  ScanMatch out;
  if (near.empty()) return out;
  const std::size_t m = near.size();
  const double step = options_.global_angular_step_rad;
  const int headings = static_cast<int>(std::ceil(2.0 * std::numbers::pi / step));
  gcx_.resize(static_cast<std::size_t>(headings) * m);
  gcy_.resize(static_cast<std::size_t>(headings) * m);
  const double theta0 = -std::numbers::pi;
  for (int a = 0; a < headings; ++a) {
    const double t = theta0 + a * step;
    const double c = std::cos(t) / cell_m_, s = std::sin(t) / cell_m_;
    int* ox = gcx_.data() + static_cast<std::size_t>(a) * m;
    int* oy = gcy_.data() + static_cast<std::size_t>(a) * m;
    for (std::size_t j = 0; j < m; ++j) {
      const std::size_t i = near[j];
      // the robot stands at a cell centre: offset of the point's cell from the robot's cell
      ox[j] = static_cast<int>(std::floor(0.5 + c * px_[i] - s * py_[i]));
      oy[j] = static_cast<int>(std::floor(0.5 + s * px_[i] + c * py_[i]));
    }
  }
  struct Candidate {
    float score;
    int a, x, y;
  };
  const int top = options_.global_levels;
  const int tile = 1 << top;
  std::vector<Candidate> roots;
  std::size_t nodes = 0;
  const auto budget = static_cast<std::size_t>(options_.global_max_nodes);
  bool stopped = false;
  for (int a = 0; a < headings; ++a) {
    const int* ox = gcx_.data() + static_cast<std::size_t>(a) * m;
    const int* oy = gcy_.data() + static_cast<std::size_t>(a) * m;
    for (int y = 0; y < height_; y += tile) {
      for (int x = 0; x < width_; x += tile) {
        if (!any_free(x, y, tile)) continue;  // no free cell: no pose here
        roots.push_back({pooled_sum(top, ox, oy, m, x, y), a, x, y});
        ++nodes;
      }
    }
  }
  auto by_score = [](const Candidate& l, const Candidate& r) { return l.score > r.score; };
  std::sort(roots.begin(), roots.end(), by_score);
  float best = 0.0f;
  Candidate winner{-1.0f, 0, 0, 0};
  // depth-first, best child first: the first leaves found set a high bar that prunes the rest
  auto branch = [&](auto&& self, const Candidate& c, int level) -> void {
    if (c.score <= best || stopped) return;
    if (level == 0) {
      if (map_.is_free({c.x, c.y})) {
        best = c.score;
        winner = c;
      }
      return;
    }
    const int half = 1 << (level - 1);
    const int* ox = gcx_.data() + static_cast<std::size_t>(c.a) * m;
    const int* oy = gcy_.data() + static_cast<std::size_t>(c.a) * m;
    std::array<Candidate, 4> kids;
    int count = 0;
    if (budget > 0 && nodes - roots.size() >= budget) {
      stopped = true;
      return;
    }
    for (int k = 0; k < 4; ++k) {
      const int x = c.x + (k & 1) * half, y = c.y + (k >> 1) * half;
      if (x >= width_ || y >= height_ || !any_free(x, y, half)) continue;
      kids[static_cast<std::size_t>(count++)] = {pooled_sum(level - 1, ox, oy, m, x, y), c.a, x, y};
      ++nodes;
    }
    // best first; an insertion sort of at most four (std::sort here trips GCC 12's bounds check)
    for (int i = 1; i < count; ++i) {
      for (int j = i; j > 0 && by_score(kids[static_cast<std::size_t>(j)], kids[static_cast<std::size_t>(j) - 1]); --j) {
        std::swap(kids[static_cast<std::size_t>(j)], kids[static_cast<std::size_t>(j) - 1]);
      }
    }
    for (int k = 0; k < count; ++k) self(self, kids[static_cast<std::size_t>(k)], level - 1);
  };
  for (const Candidate& c : roots) {
    if (c.score <= best || stopped) break;
    branch(branch, c, top);
  }
  out.nodes = nodes;
  out.exhaustive = !stopped;
  if (winner.score < 0.0f) return out;
  const GridPose g{winner.x + 0.5, winner.y + 0.5, theta0 + winner.a * step};
  ScanMatch refined = match(from_grid(g));
  refined.nodes = nodes;
  refined.exhaustive = !stopped;
  return refined;
}

void RecentQualities::add(double quality) noexcept {
  q_[count_ % kSize] = static_cast<float>(quality);
  ++count_;
}

double RecentQualities::typical() const noexcept {
  const std::size_t n = std::min(count_, kSize);
  if (n < kMin) return 0.0;
  std::array<float, kSize> sorted = q_;
  const auto mid = sorted.begin() + static_cast<std::ptrdiff_t>(n / 2);
  std::nth_element(sorted.begin(), mid, sorted.begin() + static_cast<std::ptrdiff_t>(n));
  return *mid;
}

}  // namespace tripodal::navi
