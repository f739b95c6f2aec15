#include "tripodal/navi/section_splitter.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <deque>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <queue>

#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/navi/room_segmentation.hpp"

namespace tripodal::navi {

namespace {

std::string section_name(int i) {
  std::string s;
  int n = i;
  do {
    s.insert(s.begin(), static_cast<char>('A' + n % 26));
    n = n / 26 - 1;
  } while (n >= 0);
  return s;
}

constexpr double kUnreachable = std::numeric_limits<double>::infinity();

constexpr std::size_t kNoCell = std::numeric_limits<std::size_t>::max();

// Of the cells cell_of(0 .. count-1), the one whose centre is closest to p among those `accept`
// takes; kNoCell if none. (An index function, not a range: clang 14, the fuzzing build's compiler,
// cannot compile libstdc++ 12's views::iota.)
template <typename CellOf, typename Accept>
std::size_t closest_cell(const OccupancyGrid& grid, Point2D p, std::size_t count, CellOf cell_of, Accept accept) {
  std::size_t best = kNoCell;
  double best_d2 = kUnreachable;
  for (std::size_t k = 0; k < count; ++k) {
    const std::size_t i = cell_of(k);
    if (!accept(i)) continue;
    const Point2D q = grid.cell_center(grid.cell(i));
    const double d2 = (q.x_m - p.x_m) * (q.x_m - p.x_m) + (q.y_m - p.y_m) * (q.y_m - p.y_m);
    if (d2 < best_d2) {
      best_d2 = d2;
      best = i;
    }
  }
  return best;
}

// The free cell nearest to p (p's own cell when it is free); kNoCell for a grid without free cells.
std::size_t nearest_free_cell(const OccupancyGrid& grid, Point2D p) {
  const CellIndex c = grid.cell_at(p);
  if (grid.contains(c) && grid.is_free(c)) return grid.index(c);
  return closest_cell(grid, p, grid.size(), [](std::size_t k) { return k; },
                      [&](std::size_t i) { return grid.state(i) == Occupancy::free; });
}

// The section of `remaining` nearest to `source` by grid path, and that path's length to its
// nearest cell: Dijkstra over free cells, stopped once the queue is past the first section
// reached (ties within 1 um go to the section listed first). {-1, +inf} when none is reachable.
std::pair<int, double> nearest_section(const OccupancyGrid& grid, const std::vector<std::uint8_t>& free,
                                       const SectionSet& set, std::size_t source, const std::vector<int>& remaining) {
  constexpr double kTie = 1e-6;
  std::vector<std::size_t> rank(set.sections.size(), remaining.size());  // remaining.size(): not wanted
  for (std::size_t k = 0; k < remaining.size(); ++k) rank[static_cast<std::size_t>(remaining[k])] = k;
  int best = -1;
  double best_m = kUnreachable;
  std::vector<double> dist(grid.size(), kUnreachable);
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  dist[source] = 0.0;
  open.emplace(0.0, source);
  const double straight = grid.resolution_m();
  const double diagonal = straight * std::numbers::sqrt2;
  const int w = grid.width(), h = grid.height();
  const auto free_at = [&](int x, int y) { return x >= 0 && y >= 0 && x < w && y < h && free[grid.index({x, y})] != 0; };
  while (!open.empty() && open.top().first <= best_m + kTie) {
    const auto [d, i] = open.top();
    open.pop();
    if (d > dist[i]) continue;
    const int label = set.label[i];
    if (label >= 0 && rank[static_cast<std::size_t>(label)] < remaining.size() &&
        (best < 0 || rank[static_cast<std::size_t>(label)] < rank[static_cast<std::size_t>(best)])) {
      best = label;
      best_m = std::min(best_m, d);
    }
    const CellIndex c = grid.cell(i);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        if ((dx == 0 && dy == 0) || !free_at(c.x + dx, c.y + dy)) continue;
        // no corner cutting: a diagonal step needs both side cells free
        if (dx != 0 && dy != 0 && (!free_at(c.x + dx, c.y) || !free_at(c.x, c.y + dy))) continue;
        const std::size_t j = grid.index({c.x + dx, c.y + dy});
        const double nd = d + ((dx != 0 && dy != 0) ? diagonal : straight);
        if (nd < dist[j]) {
          dist[j] = nd;
          open.emplace(nd, j);
        }
      }
    }
  }
  return {best, best_m};
}

// Where the robot is taken to be once a section is cleaned: its cell nearest the centroid.
std::size_t centre_cell(const OccupancyGrid& grid, const Section& s) {
  return closest_cell(grid, s.centroid, s.cells.size(), [&](std::size_t k) { return s.cells[k]; },
                      [](std::size_t) { return true; });
}

}  // namespace

SectionOrder order_nearest_first(const OccupancyGrid& grid, const SectionSet& set, std::span<const int> ids, Point2D from) {
  SectionOrder out;
  std::vector<int> remaining;
  for (const int id : ids) {
    const bool known = id >= 0 && static_cast<std::size_t>(id) < set.sections.size() &&
                       !set.sections[static_cast<std::size_t>(id)].cells.empty();
    if (known && std::find(remaining.begin(), remaining.end(), id) == remaining.end()) remaining.push_back(id);
  }
  std::vector<std::uint8_t> free(grid.size());
  for (std::size_t i = 0; i < grid.size(); ++i) free[i] = grid.state(i) == Occupancy::free ? 1 : 0;
  std::size_t at = set.label.size() == grid.size() ? nearest_free_cell(grid, from) : kNoCell;
  while (!remaining.empty()) {
    const auto [next, leg_m] = at != kNoCell ? nearest_section(grid, free, set, at, remaining) : std::pair<int, double>{-1, kUnreachable};
    if (next < 0) {  // nothing left can be reached: the rest as given
      for (const int id : remaining) {
        out.ids.push_back(id);
        out.legs_m.push_back(kUnreachable);
      }
      break;
    }
    out.ids.push_back(next);
    out.legs_m.push_back(leg_m);
    at = centre_cell(grid, set.sections[static_cast<std::size_t>(next)]);
    remaining.erase(std::find(remaining.begin(), remaining.end(), next));
  }
  return out;
}

std::vector<std::string> order_nearest_first(const OccupancyGrid& grid, const SectionSet& set, std::span<const std::string> names,
                                             Point2D from) {
  std::vector<int> ids;
  std::vector<std::string> unknown;
  for (const std::string& name : names) {
    const auto it = std::find_if(set.sections.begin(), set.sections.end(), [&](const Section& s) { return s.name == name; });
    if (it != set.sections.end()) ids.push_back(it->id);
    else unknown.push_back(name);
  }
  std::vector<std::string> out;
  for (const int id : order_nearest_first(grid, set, ids, from).ids) out.push_back(set.sections[static_cast<std::size_t>(id)].name);
  out.insert(out.end(), unknown.begin(), unknown.end());
  return out;
}

const ModuleManifest& CSectionSplitter::static_manifest() {
  static const ModuleManifest m = navi_manifest(
      "SectionSplitter",
      "divides a large workspace into sections at virtual walls between bands of isolated obstacles; "
      "answers sections(room)",
      {"grid_map"}, {"sections"},
      {ParameterSpec{"min_obstacle_area_m2", ValueType::number, Value{0.01}, "m^2",
                     "occupied components smaller than this are noise, not isolated obstacles", 0.0, std::nullopt},
       ParameterSpec{"min_gap_m", ValueType::number, Value{1.5}, "m",
                     "obstacle-free rows needed between two bands for a virtual wall", 0.0, std::nullopt},
       ParameterSpec{"min_section_height_m", ValueType::number, Value{3.0}, "m",
                     "a wall is kept only if the strips on both sides are at least this tall", 0.0, std::nullopt},
       ParameterSpec{"min_section_area_m2", ValueType::number, Value{2.0}, "m^2",
                     "smaller free components merge into a neighbour across a virtual wall", 0.0, std::nullopt},
       ParameterSpec{"method", ValueType::string, Value{std::string("splitter")}, "",
                     "splitter (the paper's virtual walls between obstacle bands) or a room segmentation: "
                     "morphological, distance_transform, voronoi (include/tripodal/navi/room_segmentation.hpp)",
                     std::nullopt, std::nullopt},
       ParameterSpec{"room_min_area_m2", ValueType::number, Value{1.0}, "m^2",
                     "room segmentation: smaller rooms merge into their neighbour", 0.0, std::nullopt},
       ParameterSpec{"room_max_area_m2", ValueType::number, Value{50.0}, "m^2",
                     "room segmentation: a larger part is not one room (morphological, distance_transform)", 0.0, std::nullopt},
       ParameterSpec{"door_max_width_m", ValueType::number, Value{1.6}, "m",
                     "room segmentation (voronoi): a narrower passage may be a door", 0.0, std::nullopt}});
  return m;
}

void CSectionSplitter::on_configure(const ParameterSet& params) {
  options_.min_obstacle_area_m2 = params.number("min_obstacle_area_m2");
  options_.min_gap_m = params.number("min_gap_m");
  options_.min_section_height_m = params.number("min_section_height_m");
  options_.min_section_area_m2 = params.number("min_section_area_m2");
  const std::string& method = params.string("method");
  if (method == "splitter") {
    rooms_.reset();
  } else {
    RoomSegmentationOptions rooms;
    rooms.method = room_segmentation_method(method);  // throws naming the known methods
    rooms.room_min_area_m2 = params.number("room_min_area_m2");
    rooms.room_max_area_m2 = params.number("room_max_area_m2");
    rooms.door_max_width_m = params.number("door_max_width_m");
    rooms_ = std::make_shared<const RoomSegmentationOptions>(rooms);
  }
}

SectionSet sections_of_labels(const OccupancyGrid& grid, const std::vector<int>& label) {
  SectionSet out;
  const std::size_t n = grid.size();
  out.label.assign(n, -1);
  std::map<int, int> id_of;  // label -> section id, in the order of each label's first cell
  for (std::size_t i = 0; i < n && i < label.size(); ++i) {
    if (label[i] < 0) continue;
    const auto [it, added] = id_of.try_emplace(label[i], static_cast<int>(out.sections.size()));
    if (added) {
      Section s;
      s.id = it->second;
      s.name = section_name(it->second);
      out.sections.push_back(std::move(s));
    }
    out.label[i] = it->second;
    out.sections[static_cast<std::size_t>(it->second)].cells.push_back(i);
  }
  const double cell_area = grid.resolution_m() * grid.resolution_m();
  for (Section& s : out.sections) {
    s.min = {grid.width(), grid.height()};
    s.max = {-1, -1};
    double sx = 0.0, sy = 0.0;
    for (const std::size_t i : s.cells) {
      const CellIndex c = grid.cell(i);
      s.min = {std::min(s.min.x, c.x), std::min(s.min.y, c.y)};
      s.max = {std::max(s.max.x, c.x), std::max(s.max.y, c.y)};
      const Point2D p = grid.cell_center(c);
      sx += p.x_m;
      sy += p.y_m;
    }
    s.area_m2 = static_cast<double>(s.cells.size()) * cell_area;
    if (!s.cells.empty()) s.centroid = {sx / static_cast<double>(s.cells.size()), sy / static_cast<double>(s.cells.size())};
  }
  return out;
}

namespace {

// The outer wall: the non-free cells reachable from the map's border through non-free cells.
std::vector<std::uint8_t> outer_wall(const OccupancyGrid& grid) {
  const int w = grid.width(), h = grid.height();
  std::vector<std::uint8_t> wall(grid.size(), 0);
  std::deque<std::size_t> queue;
  const auto seed = [&](int x, int y) {
    const std::size_t i = grid.index({x, y});
    if (wall[i] == 0 && grid.state(i) != Occupancy::free) {
      wall[i] = 1;
      queue.push_back(i);
    }
  };
  for (int x = 0; x < w; ++x) {
    seed(x, 0);
    seed(x, h - 1);
  }
  for (int y = 0; y < h; ++y) {
    seed(0, y);
    seed(w - 1, y);
  }
  while (!queue.empty()) {
    const CellIndex c = grid.cell(queue.front());
    queue.pop_front();
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const CellIndex nb{c.x + dx, c.y + dy};
        if (grid.contains(nb)) seed(nb.x, nb.y);
      }
    }
  }
  return wall;
}

// The isolated obstacles (the occupied components off the outer wall, of at least
// `min_area_m2`): counted, and the rows they cover, in out.obstacle_rows.
void find_isolated_obstacles(const OccupancyGrid& grid, const std::vector<std::uint8_t>& wall, double min_area_m2,
                             SectionSet& out) {
  const std::size_t n = grid.size();
  const double cell_area = grid.resolution_m() * grid.resolution_m();
  std::vector<std::uint8_t> row_has(static_cast<std::size_t>(grid.height()), 0);
  std::vector<std::uint8_t> seen(n, 0);
  std::vector<std::size_t> comp;
  std::deque<std::size_t> queue;
  for (std::size_t i = 0; i < n; ++i) {
    if (seen[i] != 0 || wall[i] != 0 || grid.state(i) != Occupancy::occupied) continue;
    comp.clear();
    seen[i] = 1;
    queue.push_back(i);
    while (!queue.empty()) {
      const std::size_t j = queue.front();
      queue.pop_front();
      comp.push_back(j);
      const CellIndex c = grid.cell(j);
      for (int dy = -1; dy <= 1; ++dy) {
        for (int dx = -1; dx <= 1; ++dx) {
          const CellIndex nb{c.x + dx, c.y + dy};
          if (!grid.contains(nb)) continue;
          const std::size_t k = grid.index(nb);
          if (seen[k] == 0 && wall[k] == 0 && grid.state(k) == Occupancy::occupied) {
            seen[k] = 1;
            queue.push_back(k);
          }
        }
      }
    }
    if (static_cast<double>(comp.size()) * cell_area < min_area_m2) continue;
    ++out.isolated_obstacles;
    for (const std::size_t j : comp) row_has[static_cast<std::size_t>(grid.cell(j).y)] = 1;
  }
  for (int y = 0; y < grid.height(); ++y) {
    if (row_has[static_cast<std::size_t>(y)] != 0) out.obstacle_rows.push_back(y);
  }
}

// Virtual walls (out.virtual_wall_rows) in the middle of the gaps between obstacle bands, kept
// where they leave tall enough strips, measured from the free rows actually present.
void place_virtual_walls(const OccupancyGrid& grid, const SectionSplitterOptions& options, SectionSet& out) {
  std::vector<int> candidates;
  const int min_gap_rows = std::max(1, static_cast<int>(std::ceil(options.min_gap_m / grid.resolution_m() - 1e-9)));
  for (std::size_t k = 1; k < out.obstacle_rows.size(); ++k) {
    const int prev = out.obstacle_rows[k - 1], next = out.obstacle_rows[k];
    if (next - prev - 1 >= min_gap_rows) candidates.push_back((prev + next) / 2);  // wall between r and r+1
  }
  int first_free = grid.height(), last_free = -1;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (grid.state(i) == Occupancy::free) {
      first_free = std::min(first_free, grid.cell(i).y);
      last_free = std::max(last_free, grid.cell(i).y);
    }
  }
  const int min_rows = static_cast<int>(std::ceil(options.min_section_height_m / grid.resolution_m()));
  int last_kept = first_free - 1;  // the strip above a wall at r starts at r + 1
  for (const int r : candidates) {
    if (r - last_kept >= min_rows && last_free - r >= min_rows) {
      out.virtual_wall_rows.push_back(r);
      last_kept = r;
    }
  }
}

// The free components, 4-connected, not crossing a virtual wall (cut_above[r]: a wall between
// rows r and r + 1); comp_of: each cell's component, -1 for none.
std::vector<std::vector<std::size_t>> free_components(const OccupancyGrid& grid, const std::vector<std::uint8_t>& cut_above,
                                                      std::vector<int>& comp_of) {
  const std::size_t n = grid.size();
  comp_of.assign(n, -1);
  std::vector<std::vector<std::size_t>> comps;
  std::deque<std::size_t> queue;
  for (std::size_t i = 0; i < n; ++i) {
    if (comp_of[i] >= 0 || grid.state(i) != Occupancy::free) continue;
    const int id = static_cast<int>(comps.size());
    comps.emplace_back();
    comp_of[i] = id;
    queue.push_back(i);
    while (!queue.empty()) {
      const std::size_t j = queue.front();
      queue.pop_front();
      comps.back().push_back(j);
      const CellIndex c = grid.cell(j);
      const CellIndex nbs[4] = {{c.x + 1, c.y}, {c.x - 1, c.y}, {c.x, c.y + 1}, {c.x, c.y - 1}};
      for (const CellIndex& nb : nbs) {
        if (!grid.contains(nb)) continue;
        if (nb.y > c.y && cut_above[static_cast<std::size_t>(c.y)] != 0) continue;
        if (nb.y < c.y && cut_above[static_cast<std::size_t>(nb.y)] != 0) continue;
        const std::size_t k = grid.index(nb);
        if (comp_of[k] < 0 && grid.state(k) == Occupancy::free) {
          comp_of[k] = id;
          queue.push_back(k);
        }
      }
    }
  }
  return comps;
}

// Merges components below `min_cells` into the neighbour across a wall with the longest shared
// border, smallest first so a chain of slivers ends in a large section (one with no neighbour is
// dropped); one label per kept root, cell by cell (-1: none).
std::vector<int> merged_labels(const OccupancyGrid& grid, const std::vector<std::vector<std::size_t>>& comps,
                               const std::vector<int>& comp_of, std::size_t min_cells) {
  std::vector<int> parent(comps.size());
  for (std::size_t k = 0; k < comps.size(); ++k) parent[k] = static_cast<int>(k);
  const auto root = [&](int k) {
    while (parent[static_cast<std::size_t>(k)] != k) k = parent[static_cast<std::size_t>(k)];
    return k;
  };
  std::vector<std::size_t> size(comps.size());
  for (std::size_t k = 0; k < comps.size(); ++k) size[k] = comps[k].size();
  std::vector<std::size_t> order(comps.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = k;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return size[a] < size[b]; });
  std::vector<std::uint8_t> dropped(comps.size(), 0);
  for (const std::size_t k : order) {
    const int rk = root(static_cast<int>(k));
    if (size[static_cast<std::size_t>(rk)] >= min_cells) continue;
    std::map<int, std::size_t> border;
    for (const std::size_t j : comps[k]) {
      const CellIndex c = grid.cell(j);
      const CellIndex nbs[2] = {{c.x, c.y + 1}, {c.x, c.y - 1}};
      for (const CellIndex& nb : nbs) {
        if (!grid.contains(nb)) continue;
        const int other = comp_of[grid.index(nb)];
        if (other >= 0 && root(other) != rk) ++border[root(other)];
      }
    }
    if (border.empty()) {
      dropped[static_cast<std::size_t>(rk)] = 1;
      continue;
    }
    const auto best = std::max_element(border.begin(), border.end(),
                                       [](const auto& a, const auto& b) { return a.second < b.second; });
    parent[static_cast<std::size_t>(rk)] = best->first;
    size[static_cast<std::size_t>(best->first)] += size[static_cast<std::size_t>(rk)];
  }
  std::vector<int> root_label(grid.size(), -1);
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (comp_of[i] < 0) continue;
    const int r = root(comp_of[i]);
    if (dropped[static_cast<std::size_t>(r)] == 0) root_label[i] = r;
  }
  return root_label;
}

}  // namespace

SectionSet CSectionSplitter::split(const OccupancyGrid& grid) const {
  if (rooms_) return segment_rooms(grid, *rooms_).rooms;
  SectionSet out;
  const std::size_t n = grid.size();
  out.label.assign(n, -1);
  if (n == 0) return out;
  const double cell_area = grid.resolution_m() * grid.resolution_m();

  // 1. the outer wall, then the isolated obstacles and the rows they cover
  find_isolated_obstacles(grid, outer_wall(grid), options_.min_obstacle_area_m2, out);
  // 2. and 3. the virtual walls between obstacle bands
  place_virtual_walls(grid, options_, out);
  std::vector<std::uint8_t> cut_above(static_cast<std::size_t>(grid.height()), 0);
  for (const int r : out.virtual_wall_rows) cut_above[static_cast<std::size_t>(r)] = 1;
  // 4. free components, not crossing a virtual wall; the small ones merged into a neighbour
  std::vector<int> comp_of;
  const std::vector<std::vector<std::size_t>> comps = free_components(grid, cut_above, comp_of);
  const std::size_t min_cells = static_cast<std::size_t>(std::ceil(options_.min_section_area_m2 / cell_area));
  // sections_of_labels numbers the kept roots in scan order
  SectionSet labelled = sections_of_labels(grid, merged_labels(grid, comps, comp_of, min_cells));
  out.sections = std::move(labelled.sections);
  out.label = std::move(labelled.label);
  return out;
}

void CSectionSplitter::split_map(const OccupancyGrid& grid, const RegionMap& regions) {
  sections_ = split(grid);
  grid_ = &grid;
  regions_ = &regions;
}

void CSectionSplitter::on_start(ModuleContext& context) {
  const CGridMaps* maps = context.modules != nullptr ? context.modules->find<CGridMaps>() : nullptr;
  if (maps == nullptr) throw ConfigError(where(), "SectionSplitter needs the robot's map: add a GridMaps module");
  split_map(maps->grid(), maps->regions());
}

const Section* CSectionSplitter::section(std::string_view name) const noexcept {
  for (const Section& s : sections_.sections) {
    if (s.name == name) return &s;
  }
  return nullptr;
}

KnowledgeAnswer CSectionSplitter::sections_of_room(std::string_view room) const {
  KnowledgeAnswer out;
  const Region* r = regions_ != nullptr ? regions_->room(room) : nullptr;
  if (r == nullptr) {
    out.error = "unknown room '" + std::string(room) + "' (known:";
    if (regions_ != nullptr) {
      for (const auto& n : regions_->room_names()) out.error += " " + n;
    }
    out.error += ")";
    return out;
  }
  for (const Section& s : sections_.sections) {
    std::size_t inside = 0;
    for (const std::size_t i : s.cells) inside += r->contains(grid_->cell_center(grid_->cell(i))) ? 1 : 0;
    if (2 * inside > s.cells.size()) out.items.push_back(s.name);
  }
  if (out.items.empty()) {
    out.error = "room '" + std::string(room) + "' holds no section of the map";
    return out;
  }
  out.ok = true;
  return out;
}

std::optional<KnowledgeAnswer> CSectionSplitter::on_answer(std::string_view function, std::string_view argument,
                                                           const NavigationData& navigation) const {
  if (function != "sections") return std::nullopt;
  KnowledgeAnswer out = sections_of_room(argument);
  // The plan is made once, from where the robot stands when it gets the task: an untrusted pose
  // would order the sections from the wrong place, so scan order is the better guess then.
  if (out.ok && navigation.localized && grid_ != nullptr) {
    const Point2D at{navigation.map_from_base.x_m, navigation.map_from_base.y_m};
    out.items = order_nearest_first(*grid_, sections_, out.items, at);
  }
  return out;
}

}  // namespace tripodal::navi
