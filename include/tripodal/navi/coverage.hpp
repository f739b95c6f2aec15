// Coverage for the cleaning task (paper, section 3.2): the record of cleaned cells on the grid,
// and coverage paths for one section given by CSectionSplitter. The balloon coverage is the
// paper's wall-following algorithm that BhCleaning / BhCleaningTwoWheel follow; the boustrophedon
// (plowing) path is the baseline it is measured against.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <utility>
#include <vector>

#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/navi/path_planner.hpp"
#include "tripodal/navi/section_splitter.hpp"

namespace tripodal::navi {

/// The cleaned-cells record: which cells of a grid a cleaning footprint has passed over. A cell
/// is cleaned when its centre comes within the footprint radius of the robot's centre.
class CleanedCells {
 public:
  CleanedCells() = default;
  explicit CleanedCells(const OccupancyGrid& grid);

  /// Marks the cells under a disc (the footprint at one pose).
  void mark_disc(Point2D centre, double radius_m) noexcept;
  /// Marks the swath a disc sweeps moving straight from a to b (a capsule).
  void mark_segment(Point2D a, Point2D b, double radius_m) noexcept;
  /// Marks the swath along a polyline.
  void mark_path(const std::vector<Point2D>& path, double radius_m) noexcept;
  void clear() noexcept;

  [[nodiscard]] bool cleaned(CellIndex c) const noexcept {
    return c.x >= 0 && c.y >= 0 && c.x < width_ && c.y < height_ && mask_[index(c)] != 0;
  }
  [[nodiscard]] bool cleaned(std::size_t i) const noexcept { return mask_[i] != 0; }
  /// Number of cleaned cells in the whole grid.
  [[nodiscard]] std::size_t count() const noexcept;
  /// Fraction of `cells` (row-major indices) that are cleaned; 1 for an empty set.
  [[nodiscard]] double coverage(const std::vector<std::size_t>& cells) const noexcept;
  [[nodiscard]] const std::vector<std::uint8_t>& mask() const noexcept { return mask_; }

 private:
  [[nodiscard]] std::size_t index(CellIndex c) const noexcept {
    return static_cast<std::size_t>(c.y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(c.x);
  }
  int width_ = 0;
  int height_ = 0;
  OccupancyGrid frame_;  // 0 x 0 cells: only the grid's world <-> cell transform
  std::vector<std::uint8_t> mask_;
};

struct CoverageOptions {
  double cleaning_width_m = 0.4;  ///< diameter of the cleaning footprint (a disc centred on the robot)
  /// Radius of the robot's body: it keeps this clearance from physical obstacles. 0: half the
  /// cleaning width (the footprint is the body).
  double robot_radius_m = 0.0;
  /// Passes (rounds or lanes) are spaced cleaning_width - overlap apart; one cell of overlap
  /// absorbs the quantisation of the contours to grid cells.
  double overlap_m = 0.05;
  /// A vertex of the (simplified) path is a turn when the heading changes by more than this.
  double turn_threshold_rad = 0.5235987755982988;  // 30 degrees
  /// Douglas-Peucker tolerance of the path's shape on which length and turns are measured (the
  /// path itself keeps every cell centre of the contours); 0: 0.75 cell.
  double simplify_tolerance_m = 0.0;
  /// After the passes, visit the reachable cells still uncleaned (points of the medial axis,
  /// narrow places) one by one, nearest first.
  bool touch_up = true;
  /// hybrid(): neighbouring lanes are cleaning_width - lane_overlap apart (straight lanes on
  /// grid rows need less overlap than contours; 2 cm absorb the robot's tracking error: demo,
  /// seeds 1-3, both robots >= 99.70 % driven coverage).
  double lane_overlap_m = 0.02;
  /// hybrid(): lanes end this far inside the centre line of the wall round; 0: one cell. 0.1 m:
  /// the driven robot still turns on the round's swath, and the lane ends repeat less of it
  /// (demo, seeds 1-3, both robots: 1.29-1.30x the bound, safe at corners with link_margin_m).
  double lane_inset_m = 0.1;
  /// hybrid(): a turn weighs like this much travel when the lane direction is chosen.
  double turn_cost_m = 0.5;
  /// Links between passes keep this much more than the robot radius from physical obstacles
  /// where the way allows (PathPlannerOptions::preferred_clearance_m), or at least the
  /// clearance of their own ends: a link that cut by an obstacle corner at the robot radius left
  /// the driven robot no room for its tracking error (the demo's differential base hit box
  /// corners with lanes ending 0.1 m inside the round). 0: links only need to be traversable.
  double link_margin_m = 0.05;
};

/// Length and turns of a path.
struct PathStats {
  double length_m = 0.0;
  std::size_t turns = 0;          ///< vertices where the heading changes by more than the threshold
  double total_turn_rad = 0.0;    ///< sum of |heading change| over every vertex
};

[[nodiscard]] PathStats path_stats(const std::vector<Point2D>& path, double turn_threshold_rad) noexcept;

struct CoverageResult {
  /// Map frame, the whole route including the links between passes: contours as chains of cell
  /// centres (dense), lanes and links as straight legs.
  std::vector<Point2D> path;
  /// Speed limit (m/s) of each leg of the path (entry i: path[i] to path[i + 1]); empty: none.
  /// A dose-planned disinfection fills it (navi/dose_planner.hpp, CCoveragePlanner).
  std::vector<double> speed_m_s;
  std::size_t passes = 0;         ///< rounds' contour pieces or plough lanes
  std::size_t rounds = 0;         ///< balloon only: offsets from the wall
  std::size_t touch_ups = 0;      ///< points visited by the touch-up
  PathStats stats;                ///< of the path simplified with simplify_tolerance_m
  std::size_t section_cells = 0;
  std::size_t reachable_cells = 0;  ///< free cells of the section the footprint can reach
  std::size_t covered_cells = 0;    ///< of those, cleaned by following path
  [[nodiscard]] double coverage() const noexcept {
    return reachable_cells == 0 ? 1.0 : static_cast<double>(covered_cells) / static_cast<double>(reachable_cells);
  }
};

/// Coverage path generators for the sections of one map. The distance field of the map's
/// physical obstacles (and the planner that links passes) is computed once, in the constructor.
///
/// Where the robot may stand in a section: cells whose clearance from the section's boundary
/// (walls, obstacles and virtual walls) is at least half the cleaning width and whose clearance
/// from physical obstacles is at least the robot radius; their connected parts that the planner
/// can link. The reachable area is every section cell within half the cleaning width of such a
/// cell: the cells the footprint can clean at all (room corners a disc cannot enter are not in it).
class CoveragePlanner final {
 public:
  CoveragePlanner(const OccupancyGrid& grid, CoverageOptions options = {});

  /// The paper's wall-following "balloon" coverage. Round 0 keeps the footprint tangent to the
  /// walls, obstacles and virtual walls of the section (the balloon's offset from the boundary is
  /// half the cleaning width); each next round offsets the balloon inward by one spacing, so the
  /// robot spirals inward. Each round is the boundary of the region where the offset field
  /// E = min(section clearance - width/2, obstacle clearance - robot radius) >= k * spacing,
  /// walked as cell chains that keep their heading where they can.
  /// Rounds go outermost first; within a round the nearest piece comes next, entered at its
  /// nearest point, so most links are a step inward.
  [[nodiscard]] CoverageResult balloon(const Section& section, std::optional<Point2D> start = std::nullopt);

  /// Boustrophedon (plowing): straight lanes parallel to the longer side of the section's
  /// bounding box, one spacing apart, each the run of standing cells along a row (or column);
  /// lanes are taken nearest-end-first, alternating direction. Same grid, width and touch-up.
  [[nodiscard]] CoverageResult boustrophedon(const Section& section, std::optional<Point2D> start = std::nullopt);

  /// Walls by balloon, floor by plough: round 0 of the balloon (tangent to every wall, obstacle
  /// and virtual wall; its pieces joined where their ends meet, so the round around an obstacle
  /// is one loop), then straight lanes over the region whose offset leaves a full spacing to
  /// that round, spread evenly at most one spacing apart. Lanes that overlap one to one from lane
  /// to lane form the cells of a boustrophedon decomposition, each swept in one go. The lane
  /// cells and the open pieces of the round are toured in the order of least travel (exact up to
  /// kExactTourItems items, nearest-next beyond), ending near `finish_near` when given (where the
  /// robot goes next); each closed loop is walked from the point of the tour nearest to it. The
  /// direction (rows or columns) whose path costs less (length + turn_cost_m per turn + the way
  /// on to finish_near) is kept. Links go around obstacles (the planner); the touch-up then
  /// visits what is left, nearest first.
  [[nodiscard]] CoverageResult hybrid(const Section& section, std::optional<Point2D> start = std::nullopt,
                                      std::optional<Point2D> finish_near = std::nullopt);

  [[nodiscard]] const CoverageOptions& options() const noexcept { return options_; }

  /// Where lanes run, in window cells: along (along_x, along_y), one lane per whole step across
  /// (across_x, across_y); rows and columns on the grid's axes, any angle for slanted walls.
  struct LaneFrame {
    double along_x = 1.0, along_y = 0.0, across_x = 0.0, across_y = 1.0;
  };
  static constexpr LaneFrame kRows{1.0, 0.0, 0.0, 1.0};
  static constexpr LaneFrame kColumns{0.0, 1.0, 1.0, 0.0};
  [[nodiscard]] PathPlanner& planner() noexcept { return planner_; }

 private:
  struct Workspace;
  [[nodiscard]] Workspace prepare(const Section& section);
  /// Keeps the standing cells' parts (8-connected, as A* moves) that the planner can link to the
  /// largest one; false when there is no standing cell.
  bool keep_linked_stand(Workspace& ws);
  void link(std::vector<Point2D>& path, CellIndex from, CellIndex to);
  void finish(CoverageResult& r, Workspace& ws, CellIndex cur);
  /// Visits the reachable cells still uncleaned, nearest first from `cur`.
  void touch_up(CoverageResult& r, Workspace& ws, CellIndex cur);
  /// Where to stand to clean u: the standing cell covering u and the most of the cells `left`
  /// (reachable, window-local) still uncleaned; nullopt when no standing cell covers u.
  [[nodiscard]] std::optional<CellIndex> touch_up_target(const Workspace& ws, const std::vector<std::uint8_t>& left, CellIndex u,
                                                         CellIndex cur) const;
  /// A touch-up visit to `target` inserted where a leg of the path passes in plain sight of it
  /// (there and back), when that is shorter than going on from the path's end; the inserted
  /// points' range, or nullopt (nothing inserted).
  [[nodiscard]] std::optional<std::pair<std::size_t, std::size_t>> insert_visit(std::vector<Point2D>& path, CellIndex target);
  /// A piece of a round: a chain of boundary cells, closed when its ends touch.
  struct RoundPiece {
    std::vector<CellIndex> cells;
    bool closed = false;
  };
  /// The boundary of `in_round` as cell chains that keep their heading, in the order a walk from
  /// `cur` takes them (nearest piece next); nullopt if it has no boundary.
  [[nodiscard]] std::optional<std::vector<RoundPiece>> round_pieces(Workspace& ws, const std::vector<std::uint8_t>& in_round,
                                                                    CellIndex cur) const;
  /// The chain of boundary cells walked from `seed`, keeping its heading, until a dead end or a
  /// turn back; marks its cells used and their neighbours near.
  void walk_chain(const Workspace& ws, const std::vector<std::uint8_t>& boundary, std::vector<std::uint8_t>& used,
                  std::vector<std::uint8_t>& near, std::size_t seed, std::vector<CellIndex>& chain) const;
  /// Joins pieces whose ends are a few cells apart in plain sight; marks closed the ones whose
  /// ends meet (hybrid: the round around an obstacle as one loop, not four sides).
  void join_pieces(std::vector<RoundPiece>& pieces);
  /// The shortest way from a to b over traversable cells within `margin` cells of both, at most
  /// 2 * margin cells between them (filled in `between`, a and b excluded); false when none.
  [[nodiscard]] bool local_path(CellIndex a, CellIndex b, int margin, std::vector<CellIndex>& between) const;
  /// Links to the piece's first cell and walks it (the start, if the path is empty).
  void append_piece(CoverageResult& r, CellIndex& cur, const RoundPiece& piece, std::optional<Point2D> start);
  /// The lanes (whole steps across the frame) spread evenly, at most a lane spacing apart, over
  /// the part of `mask` that leaves a spacing to the wall round.
  [[nodiscard]] std::vector<int> place_lanes(const Workspace& ws, const std::vector<std::uint8_t>& mask,
                                             const LaneFrame& frame) const;
  /// Lanes over `mask` along the frame's direction, swept cell by cell of the decomposition, and
  /// the round's pieces, in one tour.
  void plough(Workspace& ws, const std::vector<std::uint8_t>& mask, const LaneFrame& frame, const std::vector<RoundPiece>& pieces,
              CellIndex& cur, CoverageResult& r, std::optional<Point2D> start, std::optional<Point2D> finish_near);
  /// The direction of the round's straight sides (modulo a right angle, the peak of their
  /// length-weighted directions) when it is slanted to the grid by at least kSlantedWallsMinRad;
  /// nullopt when the walls run along the grid's axes (or there are none).
  [[nodiscard]] std::optional<double> slanted_walls_rad(const std::vector<RoundPiece>& pieces) const;
  static constexpr double kSlantedWallsMinRad = 0.0524;  // 3 degrees
  /// Up to this many lane cells and open round pieces, plough orders them exactly.
  static constexpr std::size_t kExactTourItems = 10;
  /// Walks a closed piece (the round around an obstacle) from the point of the path since
  /// `tour_begin` nearest to it and back, or after the path's end when that is cheaper.
  void insert_round(CoverageResult& r, CellIndex& cur, const RoundPiece& piece, std::size_t tour_begin,
                    std::optional<Point2D> start);
  /// Links to a closed piece's cell nearest to `cur` and walks it round.
  void append_from(CoverageResult& r, CellIndex& cur, const RoundPiece& piece, std::optional<Point2D> start);
  [[nodiscard]] CellIndex start_cell(std::optional<Point2D> start) const noexcept;

  OccupancyGrid grid_;
  CoverageOptions options_;
  PathPlanner planner_;
};

}  // namespace tripodal::navi
