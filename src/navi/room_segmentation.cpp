#include "tripodal/navi/room_segmentation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <map>
#include <numeric>
#include <stdexcept>

#include "tripodal/navi/distance_field.hpp"

namespace tripodal::navi {

namespace {

// The grid's free cells and their 4-neighbourhood, row-major; everything beyond the border is a wall.
struct FreeSpace {
  int w = 0;
  int h = 0;
  std::vector<std::uint8_t> free;

  explicit FreeSpace(const OccupancyGrid& grid) : w(grid.width()), h(grid.height()), free(grid.size(), 0) {
    for (std::size_t i = 0; i < grid.size(); ++i) free[i] = grid.state(i) == Occupancy::free ? 1 : 0;
  }
  [[nodiscard]] std::size_t size() const noexcept { return free.size(); }
  // The up-to-four neighbours of i, written to out; returns how many.
  std::size_t neighbours(std::size_t i, std::array<std::size_t, 4>& out) const noexcept {
    const int x = static_cast<int>(i % static_cast<std::size_t>(w));
    const int y = static_cast<int>(i / static_cast<std::size_t>(w));
    std::size_t k = 0;
    if (x > 0) out[k++] = i - 1;
    if (x + 1 < w) out[k++] = i + 1;
    if (y > 0) out[k++] = i - static_cast<std::size_t>(w);
    if (y + 1 < h) out[k++] = i + static_cast<std::size_t>(w);
    return k;
  }
};

// Chessboard distance (in cells) from every free cell to the nearest cell that is not free (or
// the border): a cell survives k erosions with a 3x3 square exactly when its distance exceeds k.
std::vector<int> chessboard_distance(const FreeSpace& f) {
  const int w = f.w, h = f.h;
  std::vector<int> d(f.size(), 0);
  const auto at = [&](int x, int y) -> int {
    if (x < 0 || y < 0 || x >= w || y >= h) return 0;
    return d[static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)];
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      if (f.free[i] == 0) continue;
      d[i] = 1 + std::min({at(x - 1, y), at(x - 1, y - 1), at(x, y - 1), at(x + 1, y - 1)});
    }
  }
  for (int y = h - 1; y >= 0; --y) {
    for (int x = w - 1; x >= 0; --x) {
      const std::size_t i = static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
      if (f.free[i] == 0) continue;
      d[i] = std::min({d[i], 1 + at(x + 1, y), 1 + at(x + 1, y + 1), 1 + at(x, y + 1), 1 + at(x - 1, y + 1)});
    }
  }
  return d;
}

// Connected components (4-connected) of the cells `in` accepts; labels from 0, -1 elsewhere.
template <typename In>
std::vector<int> components(const FreeSpace& f, In in, std::vector<std::size_t>& sizes) {
  std::vector<int> label(f.size(), -1);
  sizes.clear();
  std::vector<std::size_t> stack;
  std::array<std::size_t, 4> nb{};
  for (std::size_t s = 0; s < f.size(); ++s) {
    if (label[s] >= 0 || !in(s)) continue;
    const int id = static_cast<int>(sizes.size());
    std::size_t count = 0;
    label[s] = id;
    stack.push_back(s);
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      ++count;
      const std::size_t k = f.neighbours(i, nb);
      for (std::size_t q = 0; q < k; ++q) {
        if (label[nb[q]] < 0 && in(nb[q])) {
          label[nb[q]] = id;
          stack.push_back(nb[q]);
        }
      }
    }
    sizes.push_back(count);
  }
  return label;
}

// Morphological: erode step by step; a part that comes loose within the area limits is a core.
std::vector<int> morphological_cores(const FreeSpace& f, double cell_m2, const RoomSegmentationOptions& o) {
  const std::vector<int> d = chessboard_distance(f);
  std::vector<int> core(f.size(), -1);
  int rooms = 0;
  // Only the cells of parts still too large are eroded further: each step visits those alone,
  // not the whole plan (a floor's rooms come loose early, its halls take many steps).
  std::vector<std::size_t> active;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (d[i] >= 1) active.push_back(i);
  }
  std::vector<int> part(f.size(), -1);
  std::vector<std::size_t> stack, members, next;
  std::array<std::size_t, 4> nb{};
  for (int k = 1; !active.empty(); ++k) {
    next.clear();
    for (const std::size_t s : active) {
      if (d[s] < k || part[s] >= 0) continue;
      // One part of the map eroded k - 1 times, among the active cells.
      members.clear();
      part[s] = k;
      stack.push_back(s);
      while (!stack.empty()) {
        const std::size_t i = stack.back();
        stack.pop_back();
        members.push_back(i);
        const std::size_t m = f.neighbours(i, nb);
        for (std::size_t q = 0; q < m; ++q) {
          if (part[nb[q]] < 0 && d[nb[q]] >= k && core[nb[q]] < 0) {
            part[nb[q]] = k;
            stack.push_back(nb[q]);
          }
        }
      }
      const double area = static_cast<double>(members.size()) * cell_m2;
      if (area >= o.room_min_area_m2 && area <= o.room_max_area_m2) {
        for (const std::size_t i : members) core[i] = rooms;
        ++rooms;
      } else if (area > o.room_max_area_m2) {
        next.insert(next.end(), members.begin(), members.end());
      }
    }
    for (const std::size_t i : active) part[i] = -1;
    active.swap(next);
  }
  return core;
}

// Distance transform: the threshold on the distance to the walls that gives the most parts within
// the limits. Cells are added in falling distance with a union-find, so every threshold is seen
// in one pass; the cores are then the parts at the best one.
std::vector<int> distance_cores(const FreeSpace& f, const DistanceField& field, double cell_m2,
                                const RoomSegmentationOptions& o) {
  std::vector<std::size_t> order;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (f.free[i] != 0) order.push_back(i);
  }
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return field.distance_m(a) > field.distance_m(b); });
  std::vector<std::size_t> parent(f.size());
  std::iota(parent.begin(), parent.end(), 0);
  std::vector<std::size_t> size(f.size(), 0);
  std::vector<std::uint8_t> added(f.size(), 0);
  const auto root = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  const auto counts = [&](std::size_t cells) {
    const double a = static_cast<double>(cells) * cell_m2;
    return a >= o.room_min_area_m2 && a <= o.distance_room_max_area_m2;
  };
  int in_range = 0;
  int best = 0;
  double best_threshold = 0.0;
  std::array<std::size_t, 4> nb{};
  for (std::size_t k = 0; k < order.size(); ++k) {
    const std::size_t i = order[k];
    added[i] = 1;
    size[i] = 1;
    in_range += counts(1) ? 1 : 0;
    const std::size_t m = f.neighbours(i, nb);
    for (std::size_t q = 0; q < m; ++q) {
      if (added[nb[q]] == 0) continue;
      std::size_t a = root(i), b = root(nb[q]);
      if (a == b) continue;
      in_range -= (counts(size[a]) ? 1 : 0) + (counts(size[b]) ? 1 : 0);
      if (size[a] < size[b]) std::swap(a, b);
      parent[b] = a;
      size[a] += size[b];
      in_range += counts(size[a]) ? 1 : 0;
    }
    // A threshold lies between distinct distances: count only when the next cell is farther in.
    const bool level_done = k + 1 == order.size() || field.distance_m(order[k + 1]) < field.distance_m(i);
    if (level_done && in_range > best) {
      best = in_range;
      best_threshold = field.distance_m(i);
    }
  }
  std::vector<std::size_t> sizes;
  const std::vector<int> part = components(
      f, [&](std::size_t i) { return f.free[i] != 0 && field.distance_m(i) >= best_threshold; }, sizes);
  std::vector<int> core(f.size(), -1);
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (part[i] >= 0 && counts(sizes[static_cast<std::size_t>(part[i])])) core[i] = part[i];
  }
  return core;
}

// Voronoi: cut the free space across the medial axis where its clearance has a local minimum
// narrower than a door; the parts are the cores (small ones merged later).
std::vector<int> voronoi_cores(const FreeSpace& f, const DistanceField& field, double resolution_m,
                               const RoomSegmentationOptions& o) {
  const int w = f.w, h = f.h;
  const auto idx = [&](int x, int y) {
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x);
  };
  const auto dist = [&](int x, int y) {
    return x < 0 || y < 0 || x >= w || y >= h ? 0.0 : static_cast<double>(field.distance_m(idx(x, y)));
  };
  // The medial axis: free cells on a ridge of the distance (not lower than both neighbours along a
  // line through them, in one of four directions, and strictly higher than one of them).
  std::vector<std::uint8_t> axis(f.size(), 0);
  constexpr std::array<std::array<int, 2>, 4> kDirs = {{{1, 0}, {0, 1}, {1, 1}, {1, -1}}};
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (f.free[idx(x, y)] == 0) continue;
      const double c = dist(x, y);
      for (const auto& dir : kDirs) {
        const double a = dist(x - dir[0], y - dir[1]), b = dist(x + dir[0], y + dir[1]);
        if (c >= a && c >= b && (c > a || c > b)) {
          axis[idx(x, y)] = 1;
          break;
        }
      }
    }
  }
  // Critical points: axis cells with clearance under half a door where the passage is narrowest
  // along its own direction and opens up on both sides within reach (a door between two wider
  // spaces; not a corridor of even width, not a branch of the axis running into a corner).
  const double half_door = o.door_max_width_m / 2.0;
  const int reach = std::max(2, static_cast<int>(std::lround(1.0 / resolution_m)));
  std::vector<std::uint8_t> cut(f.size(), 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = idx(x, y);
      if (axis[i] == 0) continue;
      const double c = dist(x, y);
      if (c > half_door || c < 1.5 * resolution_m) continue;
      // Across the passage: the direction along which the distance falls fastest (to the walls).
      double best_rise = -1.0;
      std::array<int, 2> across{1, 0};
      for (const auto& dir : kDirs) {
        const double rise = 2.0 * c - dist(x - dir[0], y - dir[1]) - dist(x + dir[0], y + dir[1]);
        if (rise > best_rise) {
          best_rise = rise;
          across = dir;
        }
      }
      const std::array<int, 2> along{-across[1], across[0]};
      bool narrowest = true;
      std::array<bool, 2> opens{false, false};
      for (std::size_t side = 0; side < 2 && narrowest; ++side) {
        const int sign = side == 0 ? -1 : 1;
        for (int s = 1; s <= reach; ++s) {
          const int nx = x + sign * s * along[0], ny = y + sign * s * along[1];
          if (nx < 0 || ny < 0 || nx >= w || ny >= h || f.free[idx(nx, ny)] == 0) break;
          const double n = dist(nx, ny);
          if (n < c - 1e-6) {
            narrowest = false;
            break;
          }
          if (n >= 1.3 * c + resolution_m) {
            opens[side] = true;
            break;
          }
        }
      }
      if (!narrowest || !opens[0] || !opens[1]) continue;
      // The cut: the line through the point across the passage, out to the walls on both sides.
      cut[i] = 1;
      for (const int sign : {-1, 1}) {
        for (int s = 1;; ++s) {
          const int nx = x + sign * s * across[0], ny = y + sign * s * across[1];
          if (nx < 0 || ny < 0 || nx >= w || ny >= h || f.free[idx(nx, ny)] == 0) break;
          cut[idx(nx, ny)] = 1;
          // A diagonal cut must not leak between its cells: fill the corner too.
          if (across[0] != 0 && across[1] != 0) cut[idx(nx - sign * across[0], ny)] = 1;
        }
      }
    }
  }
  std::vector<std::size_t> sizes;
  return components(
      f, [&](std::size_t i) { return f.free[i] != 0 && cut[i] == 0; }, sizes);
}

// Every free cell reachable from a core joins the nearest core (a breadth-first wave from all
// cores at once).
void grow(const FreeSpace& f, std::vector<int>& label) {
  std::deque<std::size_t> wave;
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (label[i] >= 0) wave.push_back(i);
  }
  std::array<std::size_t, 4> nb{};
  while (!wave.empty()) {
    const std::size_t i = wave.front();
    wave.pop_front();
    const std::size_t k = f.neighbours(i, nb);
    for (std::size_t q = 0; q < k; ++q) {
      if (f.free[nb[q]] != 0 && label[nb[q]] < 0) {
        label[nb[q]] = label[i];
        wave.push_back(nb[q]);
      }
    }
  }
}

// Rooms under the minimum area join the neighbour they share the longest border with, smallest
// first, until none is left; one that touches no other is dropped.
void merge_small(const FreeSpace& f, std::vector<int>& label, double cell_m2, double min_area_m2) {
  int count = 0;
  for (const int l : label) count = std::max(count, l + 1);
  std::vector<std::vector<std::size_t>> cells(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < label.size(); ++i) {
    if (label[i] >= 0) cells[static_cast<std::size_t>(label[i])].push_back(i);
  }
  const auto small = [&](std::size_t l) {
    return !cells[l].empty() && static_cast<double>(cells[l].size()) * cell_m2 < min_area_m2;
  };
  std::array<std::size_t, 4> nb{};
  for (;;) {
    std::size_t smallest = cells.size();
    for (std::size_t l = 0; l < cells.size(); ++l) {
      if (small(l) && (smallest == cells.size() || cells[l].size() < cells[smallest].size())) smallest = l;
    }
    if (smallest == cells.size()) return;
    std::map<int, std::size_t> border;  // neighbour -> shared edges
    for (const std::size_t i : cells[smallest]) {
      const std::size_t k = f.neighbours(i, nb);
      for (std::size_t q = 0; q < k; ++q) {
        if (label[nb[q]] >= 0 && label[nb[q]] != static_cast<int>(smallest)) ++border[label[nb[q]]];
      }
    }
    const int into = border.empty() ? -1 : std::max_element(border.begin(), border.end(), [](const auto& x, const auto& y) {
                                             return x.second < y.second;
                                           })->first;
    // Alone and too small to be a room (a closet behind a wall, a speck): no room at all.
    for (const std::size_t i : cells[smallest]) label[i] = into;
    if (into >= 0) {
      auto& target = cells[static_cast<std::size_t>(into)];
      target.insert(target.end(), cells[smallest].begin(), cells[smallest].end());
    }
    cells[smallest].clear();
  }
}

// Where two rooms touch: the touching cells of each pair, in connected groups, are its doors.
std::vector<Door> doors_of(const OccupancyGrid& grid, const FreeSpace& f, const std::vector<int>& label) {
  std::map<std::pair<int, int>, std::vector<std::size_t>> touching;
  std::array<std::size_t, 4> nb{};
  for (std::size_t i = 0; i < f.size(); ++i) {
    if (label[i] < 0) continue;
    const std::size_t k = f.neighbours(i, nb);
    for (std::size_t q = 0; q < k; ++q) {
      const int o = label[nb[q]];
      if (o > label[i]) touching[{label[i], o}].push_back(i);
    }
  }
  std::vector<Door> doors;
  std::vector<std::uint8_t> in(f.size(), 0), seen(f.size(), 0);
  for (auto& [pair, cells] : touching) {
    std::sort(cells.begin(), cells.end());
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    for (const std::size_t c : cells) in[c] = 1;
    for (const std::size_t s : cells) {
      if (seen[s] != 0) continue;
      // Group the touching cells 8-connected: a door's cells may meet only at corners.
      std::vector<std::size_t> group{s}, stack{s};
      seen[s] = 1;
      while (!stack.empty()) {
        const CellIndex c = grid.cell(stack.back());
        stack.pop_back();
        for (int dy = -1; dy <= 1; ++dy) {
          for (int dx = -1; dx <= 1; ++dx) {
            const CellIndex nc{c.x + dx, c.y + dy};
            if (!grid.contains(nc)) continue;
            const std::size_t j = grid.index(nc);
            if (in[j] != 0 && seen[j] == 0) {
              seen[j] = 1;
              group.push_back(j);
              stack.push_back(j);
            }
          }
        }
      }
      Door d;
      d.room_a = pair.first;
      d.room_b = pair.second;
      CellIndex lo{f.w, f.h}, hi{-1, -1};
      double sx = 0.0, sy = 0.0;
      for (const std::size_t j : group) {
        const CellIndex c = grid.cell(j);
        lo = {std::min(lo.x, c.x), std::min(lo.y, c.y)};
        hi = {std::max(hi.x, c.x), std::max(hi.y, c.y)};
        const Point2D p = grid.cell_center(c);
        sx += p.x_m;
        sy += p.y_m;
      }
      d.centre = {sx / static_cast<double>(group.size()), sy / static_cast<double>(group.size())};
      d.width_m = std::hypot(hi.x - lo.x + 1, hi.y - lo.y + 1) * grid.resolution_m();
      doors.push_back(d);
    }
    for (const std::size_t c : cells) in[c] = 0;
  }
  return doors;
}

}  // namespace

std::string_view to_string(RoomSegmentationMethod m) noexcept {
  switch (m) {
    case RoomSegmentationMethod::morphological:
      return "morphological";
    case RoomSegmentationMethod::distance_transform:
      return "distance_transform";
    case RoomSegmentationMethod::voronoi:
      return "voronoi";
  }
  return "?";
}

RoomSegmentationMethod room_segmentation_method(std::string_view name) {
  if (name == "morphological") return RoomSegmentationMethod::morphological;
  if (name == "distance_transform" || name == "distance") return RoomSegmentationMethod::distance_transform;
  if (name == "voronoi") return RoomSegmentationMethod::voronoi;
  throw std::invalid_argument("unknown room segmentation method '" + std::string(name) +
                              "' (known: morphological, distance_transform, voronoi)");
}

RoomSegmentation segment_rooms(const OccupancyGrid& grid, const RoomSegmentationOptions& options) {
  RoomSegmentation out;
  const FreeSpace f(grid);
  const double cell_m2 = grid.resolution_m() * grid.resolution_m();
  std::vector<int> label;
  if (grid.size() == 0 || std::none_of(f.free.begin(), f.free.end(), [](std::uint8_t v) { return v != 0; })) {
    out.rooms = sections_of_labels(grid, std::vector<int>(grid.size(), -1));
    return out;
  }
  switch (options.method) {
    case RoomSegmentationMethod::morphological:
      label = morphological_cores(f, cell_m2, options);
      break;
    case RoomSegmentationMethod::distance_transform:
      label = distance_cores(f, DistanceField(grid), cell_m2, options);
      break;
    case RoomSegmentationMethod::voronoi:
      label = voronoi_cores(f, DistanceField(grid), grid.resolution_m(), options);
      break;
  }
  grow(f, label);
  merge_small(f, label, cell_m2, options.room_min_area_m2);
  out.rooms = sections_of_labels(grid, label);
  out.doors = doors_of(grid, f, out.rooms.label);
  return out;
}

}  // namespace tripodal::navi
