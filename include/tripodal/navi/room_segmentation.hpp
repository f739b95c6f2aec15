// Room segmentation, the navigation module that divides a floor plan into rooms as people see
// them (beside CSectionSplitter, which keeps the paper's criterion of isolated obstacles): the
// coverage planner cleans room by room and the planner sends the robot from room to room through
// the doors found here. Methods after the published surveys of room segmentation (Bormann et
// al., ICRA 2016): morphological, distance-transform and Voronoi-graph segmentation.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/navi/section_splitter.hpp"

namespace tripodal::navi {

enum class RoomSegmentationMethod {
  /// Erode the free space step by step; a part that comes loose with an area within the limits is
  /// a room's core. Doors are narrow, so rooms come apart at them first.
  morphological,
  /// Threshold the distance to the walls; the threshold giving the most parts within the limits
  /// wins and its parts are the rooms' cores.
  distance_transform,
  /// The free space's medial axis (the generalized Voronoi graph); where its clearance has a
  /// local minimum narrower than a door, the free space is cut along the shortest line to the
  /// walls; the parts, small ones merged into their neighbour, are the rooms.
  voronoi,
};

[[nodiscard]] std::string_view to_string(RoomSegmentationMethod m) noexcept;
/// "morphological", "distance_transform" (or "distance"), "voronoi"; throws std::invalid_argument
/// naming the known ones otherwise.
[[nodiscard]] RoomSegmentationMethod room_segmentation_method(std::string_view name);

struct RoomSegmentationOptions {
  RoomSegmentationMethod method = RoomSegmentationMethod::morphological;
  /// A room's core must be at least this large to count (m2); smaller rooms after growing are
  /// merged into the neighbour they share the longest border with.
  double room_min_area_m2 = 1.0;
  /// A core larger than this keeps being eroded (morphological) or does not count (distance
  /// transform): a hall is not one room with its corridors.
  double room_max_area_m2 = 50.0;
  /// The distance transform's limit is larger: its cores are taken at one threshold for the
  /// whole plan, so a hall's core must still count.
  double distance_room_max_area_m2 = 160.0;
  /// Voronoi: a passage narrower than this (clearance twice) is a door candidate.
  double door_max_width_m = 1.6;
};

/// A passage between two rooms: where their cells touch.
struct Door {
  int room_a = -1;  ///< section ids, room_a < room_b
  int room_b = -1;
  Point2D centre;
  double width_m = 0.0;  ///< the extent of the touching cells
};

struct RoomSegmentation {
  /// The rooms, as sections (ids and names in scan order: "A", "B", ...); every free cell
  /// reachable from a room's core is in one.
  SectionSet rooms;
  std::vector<Door> doors;
};

/// Segments the free space of `grid` (unknown is not free) into rooms. Never throws for a grid:
/// an empty plan, one with no free space or one with no room-sized part give no rooms.
[[nodiscard]] RoomSegmentation segment_rooms(const OccupancyGrid& grid, const RoomSegmentationOptions& options = {});

}  // namespace tripodal::navi
