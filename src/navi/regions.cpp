#include "tripodal/navi/regions.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal::navi {

namespace {

class RegionLoader {
 public:
  explicit RegionLoader(std::string file) : r_(std::move(file), d_) {}

  RegionMap load(const YAML::Node& root) {
    RegionMap out;
    if (root.IsNull()) return out;
    if (!r_.expect_keys(root, {"rooms", "nodes"}, "the regions file")) throw ConfigError(d_);
    for_each_item(root["rooms"], "rooms", [&](const YAML::Node& n) { load_room(n, out); });
    for_each_item(root["nodes"], "nodes", [&](const YAML::Node& n) { load_node(n, out); });
    if (d_.has_errors()) throw ConfigError(d_);
    return out;
  }

 private:
  template <typename F>
  void for_each_item(const YAML::Node& list, const std::string& what, F f) {
    if (!list || list.IsNull() || !r_.expect_list(list, what)) return;
    for (const auto& item : list) f(item);
  }

  std::optional<Point2D> point(const YAML::Node& n, const std::string& what) {
    if (!n.IsSequence() || n.size() != 2) {
      r_.error(n, what + ": expected [x, y] in metres, got " + yaml::kind(n));
      return std::nullopt;
    }
    const auto x = r_.number(n[0], what + " x");
    const auto y = r_.number(n[1], what + " y");
    if (!x || !y) return std::nullopt;
    return Point2D{*x, *y};
  }

  std::string name_of(const YAML::Node& item, const char* kind) {
    const YAML::Node n = r_.require(item, "name", std::string("a ") + kind, "its name");
    if (!n) return {};
    const auto name = r_.text(n, std::string("the name of a ") + kind, true);
    if (!name) return {};
    if (!names_.insert(std::string(kind) + ":" + *name).second) r_.error(n, std::string("duplicate ") + kind + " name '" + *name + "'");
    return *name;
  }

  void load_room(const YAML::Node& item, RegionMap& out) {
    if (!r_.expect_keys(item, {"name", "rectangle", "polygon"}, "a room")) return;
    Region r;
    r.where = r_.at(item);
    r.name = name_of(item, "room");
    bool have_shape = false;
    for (const auto& kv : item) {
      const std::string key = kv.first.Scalar();
      const YAML::Node& v = kv.second;
      if (key == "name") continue;
      if (key == "rectangle" || key == "polygon") {
        if (have_shape) {
          r_.error(kv.first, "room '" + r.name + "' has both a rectangle and a polygon; give one");
          continue;
        }
        have_shape = true;
        if (key == "rectangle") {
          if (!v.IsSequence() || v.size() != 4) {
            r_.error(v, "'rectangle': expected [x_min, y_min, x_max, y_max] in metres, got " +
                            (v.IsSequence() ? std::to_string(v.size()) + " values" : yaml::kind(v)));
            continue;
          }
          double c[4] = {};
          bool ok = true;
          for (std::size_t i = 0; i < 4; ++i) {
            const auto x = r_.number(v[i], "rectangle value");
            ok = ok && x.has_value();
            if (x) c[i] = *x;
          }
          if (!ok) continue;
          if (!(c[0] < c[2]) || !(c[1] < c[3])) {
            r_.error(v, "'rectangle' is empty: expected x_min < x_max and y_min < y_max");
            continue;
          }
          r.polygon = {{c[0], c[1]}, {c[2], c[1]}, {c[2], c[3]}, {c[0], c[3]}};
        } else {
          if (!v.IsSequence() || v.size() < 3) {
            r_.error(v, "'polygon': expected a list of at least 3 corners [x, y], got " +
                            (v.IsSequence() ? std::to_string(v.size()) + " corners" : yaml::kind(v)));
            continue;
          }
          for (const auto& p : v) {
            if (const auto pt = point(p, "a polygon corner")) r.polygon.push_back(*pt);
          }
        }
      }
    }
    if (!have_shape) d_.error(r.where, "room '" + r.name + "' needs a 'rectangle' or a 'polygon'");
    out.rooms.push_back(std::move(r));
  }

  void load_node(const YAML::Node& item, RegionMap& out) {
    if (!r_.expect_keys(item, {"name", "pose", "description"}, "a node")) return;
    MapNode m;
    m.where = r_.at(item);
    m.name = name_of(item, "node");
    bool have_pose = false;
    for (const auto& kv : item) {
      const std::string key = kv.first.Scalar();
      const YAML::Node& v = kv.second;
      if (key == "name") continue;
      if (key == "pose") {
        have_pose = true;
        if (!v.IsSequence() || (v.size() != 2 && v.size() != 3)) {
          r_.error(v, "'pose': expected [x, y] or [x, y, theta] (metres, radians), got " + yaml::kind(v));
          continue;
        }
        const auto x = r_.number(v[0], "pose x");
        const auto y = r_.number(v[1], "pose y");
        const auto t = v.size() == 3 ? r_.number(v[2], "pose theta") : std::optional<double>(0.0);
        if (x && y && t) m.pose = {*x, *y, *t};
      } else if (key == "description") {
        if (auto text = r_.text(v, "'description'")) m.description = *text;
      }
    }
    if (!have_pose) d_.error(m.where, "node '" + m.name + "' needs a 'pose'");
    out.nodes.push_back(std::move(m));
  }

  Diagnostics d_;
  yaml::Reader r_;
  std::set<std::string> names_;
};

}  // namespace

bool Region::contains(Point2D p) const noexcept {
  bool inside = false;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Point2D& a = polygon[i];
    const Point2D& b = polygon[j];
    if ((a.y_m > p.y_m) != (b.y_m > p.y_m)) {
      const double x = a.x_m + (p.y_m - a.y_m) * (b.x_m - a.x_m) / (b.y_m - a.y_m);
      if (p.x_m < x) inside = !inside;
    }
  }
  return inside;
}

double Region::area_m2() const noexcept {
  double a = 0.0;
  const std::size_t n = polygon.size();
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    a += polygon[j].x_m * polygon[i].y_m - polygon[i].x_m * polygon[j].y_m;
  }
  return std::abs(a) / 2.0;
}

const Region* RegionMap::room(std::string_view name) const noexcept {
  for (const Region& r : rooms) {
    if (r.name == name) return &r;
  }
  return nullptr;
}

const MapNode* RegionMap::node(std::string_view name) const noexcept {
  for (const MapNode& m : nodes) {
    if (m.name == name) return &m;
  }
  return nullptr;
}

std::vector<std::string> RegionMap::room_names() const {
  std::vector<std::string> out;
  for (const Region& r : rooms) out.push_back(r.name);
  return out;
}

RegionMap parse_regions(std::string_view text, const std::string& file) {
  return yaml::guarded(file, [&] { return RegionLoader(file).load(yaml::parse(text, file)); });
}

RegionMap load_regions(const std::filesystem::path& file) {
  return parse_regions(yaml::read_file(file), file.string());
}

std::vector<std::size_t> cells_in_region(const OccupancyGrid& grid, const Region& region) {
  std::vector<std::size_t> out;
  if (region.polygon.empty() || grid.size() == 0) return out;
  // Only the cells whose centres can be inside: those of the polygon's bounding box in the grid's
  // frame (one cell of margin against rounding). A box the size of the region, not the whole map,
  // keeps a world of 10^5 small obstacles linear in obstacles + map (the simulator's start-up).
  double lo_x = std::numeric_limits<double>::infinity(), lo_y = lo_x, hi_x = -lo_x, hi_y = -lo_x;
  for (const Point2D& p : region.polygon) {
    const Point2D g = grid.to_grid_frame(p);
    lo_x = std::min(lo_x, g.x_m);
    lo_y = std::min(lo_y, g.y_m);
    hi_x = std::max(hi_x, g.x_m);
    hi_y = std::max(hi_y, g.y_m);
  }
  int x0 = 0, y0 = 0, x1 = grid.width() - 1, y1 = grid.height() - 1;
  if (std::isfinite(lo_x) && std::isfinite(lo_y) && std::isfinite(hi_x) && std::isfinite(hi_y)) {
    // cell x's centre is at (x + 0.5) * resolution; clamped before the integer conversion
    const auto first = [&](double v, int n) {
      return static_cast<int>(std::clamp(std::ceil(v / grid.resolution_m() - 0.5) - 1.0, 0.0, static_cast<double>(n)));
    };
    const auto last = [&](double v, int n) {
      return static_cast<int>(std::clamp(std::floor(v / grid.resolution_m() - 0.5) + 1.0, -1.0, static_cast<double>(n - 1)));
    };
    x0 = first(lo_x, grid.width());
    y0 = first(lo_y, grid.height());
    x1 = last(hi_x, grid.width());
    y1 = last(hi_y, grid.height());
  }
  for (int y = y0; y <= y1; ++y) {
    for (int x = x0; x <= x1; ++x) {
      const CellIndex c{x, y};
      if (region.contains(grid.cell_center(c))) out.push_back(grid.index(c));
    }
  }
  return out;
}

OccupancyGrid restrict_to_region(const OccupancyGrid& grid, const Region& region) {
  OccupancyGrid out = grid;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    const CellIndex c = grid.cell(i);
    if (grid.state(i) == Occupancy::free && !region.contains(grid.cell_center(c))) {
      out.set_state(c, Occupancy::unknown);
    }
  }
  return out;
}

}  // namespace tripodal::navi
