#include "tripodal/navi/regions.hpp"

#include <algorithm>
#include <cmath>
#include <set>

#include "yaml_util.hpp"

namespace tripodal::navi {

namespace {

using detail::as_double;
using detail::kind_name;
using detail::where;

class RegionLoader {
 public:
  explicit RegionLoader(std::string file) : file_(std::move(file)) {}

  RegionMap load(const YAML::Node& root) {
    RegionMap out;
    if (root.IsNull()) return out;
    if (!root.IsMap()) {
      d_.error(where(file_, root), "expected a map with 'rooms' and/or 'nodes' lists, got " + kind_name(root));
      throw ConfigError(d_);
    }
    for (const auto& kv : root) {
      const std::string key = kv.first.Scalar();
      if (key == "rooms") {
        for_each_item(kv.second, "rooms", [&](const YAML::Node& n) { load_room(n, out); });
      } else if (key == "nodes") {
        for_each_item(kv.second, "nodes", [&](const YAML::Node& n) { load_node(n, out); });
      } else {
        d_.error(where(file_, kv.first), "unknown key '" + key + "'; expected: rooms, nodes");
      }
    }
    if (d_.has_errors()) throw ConfigError(d_);
    return out;
  }

 private:
  template <typename F>
  void for_each_item(const YAML::Node& list, const std::string& what, F f) {
    if (list.IsNull()) return;
    if (!list.IsSequence()) {
      d_.error(where(file_, list), "'" + what + "' must be a list, got " + kind_name(list));
      return;
    }
    for (const auto& item : list) f(item);
  }

  std::optional<Point2D> point(const YAML::Node& n, const std::string& what) {
    if (!n.IsSequence() || n.size() != 2) {
      d_.error(where(file_, n), what + " must be [x, y] in metres, got " + kind_name(n));
      return std::nullopt;
    }
    const auto x = as_double(n[0], file_, what + " x", d_);
    const auto y = as_double(n[1], file_, what + " y", d_);
    if (!x || !y) return std::nullopt;
    return Point2D{*x, *y};
  }

  std::string name_of(const YAML::Node& item, const char* kind) {
    const YAML::Node n = item["name"];
    if (!n) {
      d_.error(where(file_, item), std::string("a ") + kind + " needs a 'name'");
      return {};
    }
    if (!n.IsScalar() || n.Scalar().empty()) {
      d_.error(where(file_, n), std::string("the name of a ") + kind + " must be a non-empty scalar, got " + kind_name(n));
      return {};
    }
    if (!names_.insert(std::string(kind) + ":" + n.Scalar()).second) {
      d_.error(where(file_, n), std::string("duplicate ") + kind + " name '" + n.Scalar() + "'");
    }
    return n.Scalar();
  }

  void load_room(const YAML::Node& item, RegionMap& out) {
    if (!item.IsMap()) {
      d_.error(where(file_, item), "a room must be a map with name and rectangle or polygon, got " + kind_name(item));
      return;
    }
    Region r;
    r.where = where(file_, item);
    r.name = name_of(item, "room");
    bool have_shape = false;
    for (const auto& kv : item) {
      const std::string key = kv.first.Scalar();
      const YAML::Node& v = kv.second;
      if (key == "name") continue;
      if (key == "rectangle" || key == "polygon") {
        if (have_shape) {
          d_.error(where(file_, kv.first), "room '" + r.name + "' has both a rectangle and a polygon; give one");
          continue;
        }
        have_shape = true;
        if (key == "rectangle") {
          if (!v.IsSequence() || v.size() != 4) {
            d_.error(where(file_, v), "'rectangle' must be [x_min, y_min, x_max, y_max] in metres, got " +
                                          (v.IsSequence() ? std::to_string(v.size()) + " values" : kind_name(v)));
            continue;
          }
          double c[4] = {};
          bool ok = true;
          for (std::size_t i = 0; i < 4; ++i) {
            const auto x = as_double(v[i], file_, "rectangle value", d_);
            ok = ok && x.has_value();
            if (x) c[i] = *x;
          }
          if (!ok) continue;
          if (!(c[0] < c[2]) || !(c[1] < c[3])) {
            d_.error(where(file_, v), "'rectangle' is empty: expected x_min < x_max and y_min < y_max");
            continue;
          }
          r.polygon = {{c[0], c[1]}, {c[2], c[1]}, {c[2], c[3]}, {c[0], c[3]}};
        } else {
          if (!v.IsSequence() || v.size() < 3) {
            d_.error(where(file_, v), "'polygon' must be a list of at least 3 corners [x, y], got " +
                                          (v.IsSequence() ? std::to_string(v.size()) + " corners" : kind_name(v)));
            continue;
          }
          for (const auto& p : v) {
            if (const auto pt = point(p, "a polygon corner")) r.polygon.push_back(*pt);
          }
        }
      } else {
        d_.error(where(file_, kv.first), "unknown key '" + key + "' in room; expected: name, rectangle, polygon");
      }
    }
    if (!have_shape) d_.error(r.where, "room '" + r.name + "' needs a 'rectangle' or a 'polygon'");
    out.rooms.push_back(std::move(r));
  }

  void load_node(const YAML::Node& item, RegionMap& out) {
    if (!item.IsMap()) {
      d_.error(where(file_, item), "a node must be a map with name and pose, got " + kind_name(item));
      return;
    }
    MapNode m;
    m.where = where(file_, item);
    m.name = name_of(item, "node");
    bool have_pose = false;
    for (const auto& kv : item) {
      const std::string key = kv.first.Scalar();
      const YAML::Node& v = kv.second;
      if (key == "name") continue;
      if (key == "pose") {
        have_pose = true;
        if (!v.IsSequence() || (v.size() != 2 && v.size() != 3)) {
          d_.error(where(file_, v), "'pose' must be [x, y] or [x, y, theta] (metres, radians), got " + kind_name(v));
          continue;
        }
        const auto x = as_double(v[0], file_, "pose x", d_);
        const auto y = as_double(v[1], file_, "pose y", d_);
        const auto t = v.size() == 3 ? as_double(v[2], file_, "pose theta", d_) : std::optional<double>(0.0);
        if (x && y && t) m.pose = {*x, *y, *t};
      } else if (key == "description") {
        if (!v.IsScalar()) d_.error(where(file_, v), "'description' must be text, got " + kind_name(v));
        else m.description = v.Scalar();
      } else {
        d_.error(where(file_, kv.first), "unknown key '" + key + "' in node; expected: name, pose, description");
      }
    }
    if (!have_pose) d_.error(m.where, "node '" + m.name + "' needs a 'pose'");
    out.nodes.push_back(std::move(m));
  }

  std::string file_;
  Diagnostics d_;
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
  return RegionLoader(file).load(detail::parse_yaml(text, file));
}

RegionMap load_regions(const std::filesystem::path& file) {
  return parse_regions(detail::read_text_file(file), file.string());
}

std::vector<std::size_t> cells_in_region(const OccupancyGrid& grid, const Region& region) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (region.contains(grid.cell_center(grid.cell(i)))) out.push_back(i);
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
