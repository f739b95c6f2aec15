// Named places on a map, in a YAML file beside it: rooms (the "3211" of "clean the room 3211",
// a polygon or a rectangle in the map frame) and map nodes (named poses for guiding, transport
// and patrol). The planner asks for them by name; the cleaning task splits a room into sections.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/navi/occupancy_grid.hpp"

namespace tripodal::navi {

struct Region {
  std::string name;
  std::vector<Point2D> polygon;  ///< map frame, metres; a rectangle is stored as its 4 corners
  SourceLocation where;
  /// Whether p is inside (even-odd rule; points on an edge may go either way).
  [[nodiscard]] bool contains(Point2D p) const noexcept;
  [[nodiscard]] double area_m2() const noexcept;
};

struct MapNode {
  std::string name;
  Pose2D pose;  ///< map frame
  std::string description;
  SourceLocation where;
};

struct RegionMap {
  std::vector<Region> rooms;
  std::vector<MapNode> nodes;
  [[nodiscard]] const Region* room(std::string_view name) const noexcept;
  [[nodiscard]] const MapNode* node(std::string_view name) const noexcept;
  [[nodiscard]] std::vector<std::string> room_names() const;
};

/// Parses a regions file:
///   rooms:
///     - name: "3211"
///       rectangle: [x_min, y_min, x_max, y_max]    # or
///       polygon: [[x, y], [x, y], [x, y], ...]     # at least 3 corners
///   nodes:
///     - name: entrance
///       pose: [x, y, theta]                        # theta optional, radians
///       description: "main door"                   # optional
/// Both lists are optional. Every problem (unknown key, missing name, both or neither of
/// rectangle/polygon, fewer than 3 corners, an empty rectangle, a duplicate name, a non-number)
/// is collected and thrown as one ConfigError with file:line:col per problem.
[[nodiscard]] RegionMap parse_regions(std::string_view text, const std::string& file);
[[nodiscard]] RegionMap load_regions(const std::filesystem::path& file);

/// The row-major indices of the grid cells whose centre is inside the region.
[[nodiscard]] std::vector<std::size_t> cells_in_region(const OccupancyGrid& grid, const Region& region);
/// A copy of grid in which every free cell outside the region is unknown: what the section
/// splitter and the coverage see when a task names a room.
[[nodiscard]] OccupancyGrid restrict_to_region(const OccupancyGrid& grid, const Region& region);

}  // namespace tripodal::navi
