// CSectionSplitter, the navigation module that divides a large open workspace into sections
// (paper, section 3.2): the planner alternates PrCleaning over each section with PrAutoMove
// between them, and the cleaning behaviors cover one section at a time.
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/navi/regions.hpp"

namespace tripodal::navi {

struct RoomSegmentationOptions;  // room_segmentation.hpp

struct SectionSplitterOptions {
  /// Occupied components smaller than this are noise, not isolated obstacles.
  double min_obstacle_area_m2 = 0.01;
  /// Obstacle rows closer than this belong to one band: only a gap at least this tall (a real
  /// free passage across the map) hosts a virtual wall. Without it, one table and two pillars
  /// at slightly different heights would cut the floor into slivers.
  double min_gap_m = 1.5;
  /// A virtual wall is kept only if the strips on both sides of it (to the neighbouring kept
  /// wall or the end of the map) are at least this tall; closer walls are dropped.
  double min_section_height_m = 3.0;
  /// A free component smaller than this after the cut is merged into the section it shares the
  /// longest virtual-wall border with (or dropped, if it touches none: a free speck inside walls).
  double min_section_area_m2 = 2.0;
};

/// One section: a set of free cells with its extent.
struct Section {
  int id = 0;                     ///< index in SectionSet::sections
  std::string name;               ///< "A", "B", ... in scan order (lowest first row first)
  std::vector<std::size_t> cells; ///< row-major indices into the grid, ascending
  CellIndex min;                  ///< bounding box, inclusive
  CellIndex max;
  double area_m2 = 0.0;
  Point2D centroid;               ///< map frame
};

struct SectionSet {
  std::vector<Section> sections;
  /// Section id of every grid cell, -1 for cells in no section (not free, or dropped).
  std::vector<int> label;
  /// Virtual walls: a wall at row r separates rows r and r + 1 (it lies on the edge between them).
  std::vector<int> virtual_wall_rows;
  /// Rows (grid y) holding at least one isolated obstacle cell.
  std::vector<int> obstacle_rows;
  /// Number of isolated obstacles (occupied components not connected to the outer wall).
  std::size_t isolated_obstacles = 0;
};

/// Sections from a label per grid cell (-1: none; any other value names a section): ids and names
/// in scan order (the section whose first cell comes first is "A"), cells ascending, extent, area
/// and centroid filled. The section splitter and the room segmentation both end here.
[[nodiscard]] SectionSet sections_of_labels(const OccupancyGrid& grid, const std::vector<int>& label);

/// The section splitter. The rule, on the paper's criterion (isolated obstacles):
///  1. The outer wall is every occupied or unknown cell 8-connected to the border of the grid
///     through occupied/unknown cells; the other occupied components, at least
///     min_obstacle_area_m2, are isolated obstacles (furniture, pillars standing in free space).
///  2. Scanning the grid row by row (from row 0), rows holding isolated obstacle cells form
///     obstacle bands; rows between two bands hold none. Bands separated by fewer than
///     min_gap_m of obstacle-free rows are one band. A candidate virtual wall lies in the middle
///     of every remaining gap between two consecutive bands, along the row.
///  3. Walls closer than min_section_height_m to the previous kept wall (or to the first/last
///     free row) are dropped, so no section is a thin strip.
///  4. Sections are the 4-connected components of free cells, not crossing a virtual wall; a
///     component under min_section_area_m2 is merged into its largest neighbour across a wall.
/// Every free cell ends up in exactly one section (unless dropped in 4).
///
/// As a navigation module (type "SectionSplitter") its parameters are the option fields (same
/// names) and `method`: "splitter" (the rule above, the default) or a room segmentation
/// (segment_rooms: "morphological", "distance_transform", "voronoi", with room_min_area_m2,
/// room_max_area_m2 and door_max_width_m), whose rooms are then the sections; it splits the map of the robot's GridMaps at start
/// and answers the planner's question sections(room): the room's sections nearest first from the robot's pose when the localizer
/// trusts it (order_nearest_first; paper, section 5.1: the order of the processes follows the
/// initial position), else in scan order. split() may be called without configure() with the
/// options given to the constructor.
class CSectionSplitter final : public CNaviModules {
 public:
  explicit CSectionSplitter(SectionSplitterOptions options = {}) : options_(options) {}
  static const ModuleManifest& static_manifest();
  [[nodiscard]] SectionSet split(const OccupancyGrid& grid) const;
  [[nodiscard]] const SectionSplitterOptions& options() const noexcept { return options_; }

  /// The sections of the robot's map (after start, or split_map()).
  [[nodiscard]] const SectionSet& sections() const noexcept { return sections_; }
  /// Splits `grid` and keeps the result with the regions it is read against (start does this
  /// with the robot's map).
  void split_map(const OccupancyGrid& grid, const RegionMap& regions);
  /// The section called `name` ("A"), nullptr when there is none.
  [[nodiscard]] const Section* section(std::string_view name) const noexcept;
  /// Names of the sections most of whose cells lie in the room, in scan order; an error naming
  /// the known rooms for an unknown room.
  [[nodiscard]] KnowledgeAnswer sections_of_room(std::string_view room) const;

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  void on_start(ModuleContext& context) override;
  [[nodiscard]] std::optional<KnowledgeAnswer> on_answer(std::string_view function, std::string_view argument,
                                                         const NavigationData& navigation) const override;

 private:
  SectionSplitterOptions options_;
  // The profile's `method` when it is a room segmentation (null: the paper's splitter).
  std::shared_ptr<const RoomSegmentationOptions> rooms_;
  SectionSet sections_;
  const OccupancyGrid* grid_ = nullptr;
  const RegionMap* regions_ = nullptr;
};

/// The order in which to visit sections, and the path length of each leg.
struct SectionOrder {
  std::vector<int> ids;        ///< section ids, the first to visit first
  /// legs_m[k]: grid path length to ids[k] (to its nearest cell) from the start point (k = 0) or
  /// from where the robot is taken to end the previous section (k > 0); +infinity when no path
  /// of free cells leads there (such sections come last, in the order given).
  std::vector<double> legs_m;
};

/// Nearest uncleaned section next (paper, sections 3.1 and 5.1: the order of the PrCleaning
/// processes "changed according to the robot's initial position"): from `from`, the next section
/// is the one whose nearest cell is the fewest metres of grid path away; the robot is then taken
/// to be at that section's centre (its cell nearest the centroid: the balloon coverage spirals
/// inward from the walls and ends inside), and so on. A greedy tour, not an optimal one, as the
/// paper's planner does it. Grid path distance (8-connected free cells, diagonals only between
/// two free side cells) rather than straight-line distance because a section behind a wall is
/// not near; one Dijkstra per leg, stopped at the first section it reaches, so a leg costs the
/// cells nearer than that section (bench/navi, BM_OrderSectionsNearestFirst). A start outside the
/// free cells starts from the nearest free cell. Ties go to the id given first. `grid` is the
/// grid `set` was split from; ids not in `set` are ignored.
[[nodiscard]] SectionOrder order_nearest_first(const OccupancyGrid& grid, const SectionSet& set, std::span<const int> ids,
                                               Point2D from);

/// The same over section names ("A", "B", ...), as the planner's knowledge answers them; names
/// that are not sections of `set` keep their place at the end.
[[nodiscard]] std::vector<std::string> order_nearest_first(const OccupancyGrid& grid, const SectionSet& set,
                                                           std::span<const std::string> names, Point2D from);

}  // namespace tripodal::navi
