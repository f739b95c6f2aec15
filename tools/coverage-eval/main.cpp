// tripodal-coverage-eval: the coverage planners and the section splitter measured on floor plans
// (docs/coverage.md). For the demo workspace, the 20 ipa floor plans with a human room
// segmentation (read from ../shared/data/ipa-maps, never shipped) and seeded random rooms it
// prints, per map and pattern: coverage of the reachable floor, length / bound (bound = reachable
// area / cleaning width), turns, total rotation and planning time; for the ipa maps also the
// precision and recall of the sections against the ground-truth rooms.
#include <png.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <numbers>
#include <numeric>
#include <random>
#include <stdexcept>
#include <string>
#include <vector>

#include "cli_tool.hpp"
#include "tripodal/navi/coverage.hpp"
#include "tripodal/navi/distance_field.hpp"
#include "tripodal/navi/distance_transform_coverage.hpp"
#include "tripodal/navi/map_io.hpp"
#include "tripodal/navi/room_segmentation.hpp"
#include "tripodal/navi/section_splitter.hpp"

using namespace tripodal::navi;
namespace fs = std::filesystem;
namespace cli = tripodal::cli;

namespace {

struct Gray {
  int width = 0, height = 0;
  std::vector<std::uint8_t> px;  // row 0 at the top
};

Gray read_png(const fs::path& file) {
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  if (png_image_begin_read_from_file(&img, file.c_str()) == 0) {
    throw std::runtime_error(file.string() + ": cannot read the PNG: " + img.message);
  }
  img.format = PNG_FORMAT_GRAY;
  Gray g;
  g.width = static_cast<int>(img.width);
  g.height = static_cast<int>(img.height);
  g.px.resize(PNG_IMAGE_SIZE(img));
  // transparent pixels composed over white: the plans' background
  png_color white{255, 255, 255};
  if (png_image_finish_read(&img, &white, g.px.data(), 0, nullptr) == 0) {
    throw std::runtime_error(file.string() + ": cannot decode the PNG: " + img.message);
  }
  return g;
}

// A floor plan as a grid: white is free, anything darker a wall (0.05 m per pixel).
OccupancyGrid grid_of(const Gray& g, double resolution_m) {
  OccupancyGrid grid(g.width, g.height, resolution_m);
  for (int r = 0; r < g.height; ++r) {
    for (int x = 0; x < g.width; ++x) {
      const bool free = g.px[static_cast<std::size_t>(r) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(x)] >= 250;
      grid.set_state({x, g.height - 1 - r}, free ? Occupancy::free : Occupancy::occupied);
    }
  }
  return grid;
}

// Ground-truth rooms: the white regions of the segmentation image (4-connected), at least
// min_cells large; label per grid cell (-1: none).
std::vector<int> rooms_of(const Gray& g, std::size_t min_cells, int& count) {
  const std::size_t n = g.px.size();
  std::vector<int> label(n, -1);
  count = 0;
  std::vector<std::size_t> stack, comp;
  std::vector<bool> seen(n, false);
  for (std::size_t s = 0; s < n; ++s) {
    if (seen[s] || g.px[s] < 250) continue;
    comp.clear();
    stack.push_back(s);
    seen[s] = true;
    while (!stack.empty()) {
      const std::size_t i = stack.back();
      stack.pop_back();
      comp.push_back(i);
      const int x = static_cast<int>(i % static_cast<std::size_t>(g.width));
      const int r = static_cast<int>(i / static_cast<std::size_t>(g.width));
      const int nx[4] = {x + 1, x - 1, x, x}, nr[4] = {r, r, r + 1, r - 1};
      for (int q = 0; q < 4; ++q) {
        if (nx[q] < 0 || nr[q] < 0 || nx[q] >= g.width || nr[q] >= g.height) continue;
        const std::size_t k = static_cast<std::size_t>(nr[q]) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(nx[q]);
        if (!seen[k] && g.px[k] >= 250) {
          seen[k] = true;
          stack.push_back(k);
        }
      }
    }
    if (comp.size() < min_cells) continue;
    for (const std::size_t i : comp) {
      const int x = static_cast<int>(i % static_cast<std::size_t>(g.width));
      const int r = static_cast<int>(i / static_cast<std::size_t>(g.width));
      label[static_cast<std::size_t>(g.height - 1 - r) * static_cast<std::size_t>(g.width) + static_cast<std::size_t>(x)] = count;
    }
    ++count;
  }
  return label;
}

struct Figures {
  double reachable_m2 = 0.0, covered_m2 = 0.0, length_m = 0.0, rotation_rad = 0.0, time_ms = 0.0, worst_ms = 0.0;
  std::size_t turns = 0;
};

enum class Pattern { balloon, boustrophedon, hybrid, distance_transform };
const char* name_of(Pattern p) {
  return p == Pattern::balloon         ? "balloon"
         : p == Pattern::boustrophedon ? "boustrophedon"
         : p == Pattern::hybrid        ? "hybrid"
                                       : "distance_transform";
}

// Every section of the grid covered by one pattern, one after the other from the previous end.
Figures cover(const OccupancyGrid& grid, const SectionSet& sections, Pattern pattern, const CoverageOptions& o,
              std::vector<CoverageResult>* results = nullptr) {
  Figures f;
  const auto t0 = std::chrono::steady_clock::now();
  CoveragePlanner cp(grid, o);
  for (const Section& s : sections.sections) {
    const auto ts = std::chrono::steady_clock::now();
    const CoverageResult r = pattern == Pattern::balloon         ? cp.balloon(s)
                             : pattern == Pattern::boustrophedon ? cp.boustrophedon(s)
                             : pattern == Pattern::hybrid        ? cp.hybrid(s)
                                                                 : distance_transform_coverage(grid, s, o);
    f.worst_ms = std::max(f.worst_ms, std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - ts).count());
    const double cell_m2 = grid.resolution_m() * grid.resolution_m();
    f.reachable_m2 += static_cast<double>(r.reachable_cells) * cell_m2;
    f.covered_m2 += static_cast<double>(r.covered_cells) * cell_m2;
    f.length_m += r.stats.length_m;
    f.turns += r.stats.turns;
    f.rotation_rad += r.stats.total_turn_rad;
    if (results != nullptr) results->push_back(r);
  }
  f.time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return f;
}

void print_row(const std::string& map, Pattern p, const Figures& f, double width_m, const std::string& extra = "") {
  const double bound = f.reachable_m2 / width_m;
  std::printf("| %s | %s | %.1f | %.2f %% | %.1f | %.2f | %zu | %.0f | %.1f | %.1f |%s\n", map.c_str(), name_of(p),
              f.reachable_m2, f.reachable_m2 > 0 ? 100.0 * f.covered_m2 / f.reachable_m2 : 100.0, f.length_m,
              bound > 0 ? f.length_m / bound : 0.0, f.turns, f.rotation_rad * 180.0 / std::numbers::pi, f.time_ms,
              f.worst_ms, extra.c_str());
}

void header(bool segmentation) {
  std::printf(
      "| map | pattern | reachable m2 | coverage | length m | length / bound | turns | rotation deg | plan ms | worst section ms "
      "|%s\n",
      segmentation ? " sections | rooms | precision | recall | segmentation ms |" : "");
  std::printf("|---|---|---|---|---|---|---|---|---|---|%s\n", segmentation ? "---|---|---|---|---|" : "");
}

// The sections to cover: the section splitter's, or the rooms of a room segmentation method.
struct Split {
  SectionSet sections;
  double ms = 0.0;
};
Split split(const OccupancyGrid& grid, const std::string& rooms) {
  const auto t0 = std::chrono::steady_clock::now();
  Split s;
  if (rooms.empty()) {
    s.sections = CSectionSplitter().split(grid);
  } else {
    RoomSegmentationOptions ro;
    ro.method = room_segmentation_method(rooms);
    s.sections = segment_rooms(grid, ro).rooms;
  }
  s.ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  return s;
}

// Per section: its reachable area, path length / its own bound, passes and touch-ups, worst first
// (where a map's excess over the bound lies).
void print_sections(const std::vector<CoverageResult>& results, double resolution_m, double width_m) {
  std::vector<std::size_t> order(results.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  const auto excess = [&](std::size_t k) {
    const CoverageResult& r = results[k];
    return r.stats.length_m - static_cast<double>(r.reachable_cells) * resolution_m * resolution_m / width_m;
  };
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return excess(a) > excess(b); });
  for (const std::size_t k : order) {
    const CoverageResult& r = results[k];
    const double m2 = static_cast<double>(r.reachable_cells) * resolution_m * resolution_m;
    std::printf("    section %zu: %.1f m2, %.1f m (%.2fx, %+.1f m over the bound), %zu turns, %zu passes, %zu touch-ups\n", k, m2,
                r.stats.length_m, m2 > 0 ? r.stats.length_m / (m2 / width_m) : 0.0, excess(k), r.stats.turns, r.passes,
                r.touch_ups);
  }
}

// Sums over maps per pattern, printed last.
std::map<Pattern, Figures> totals;
void add(Pattern p, const Figures& f) {
  Figures& t = totals[p];
  t.reachable_m2 += f.reachable_m2;
  t.covered_m2 += f.covered_m2;
  t.length_m += f.length_m;
  t.turns += f.turns;
  t.rotation_rad += f.rotation_rad;
  t.time_ms += f.time_ms;
  t.worst_ms = std::max(t.worst_ms, f.worst_ms);
}

const Pattern kPatterns[] = {Pattern::balloon, Pattern::boustrophedon, Pattern::hybrid, Pattern::distance_transform};

// Area-weighted precision (each section's best-matching room over the section) and recall (each
// room's best-matching section over the room), with the counts.
struct Score {
  double precision = 0.0;
  double recall = 0.0;
};
std::string segmentation(const SectionSet& sections, const std::vector<int>& gt, int rooms, Score* score = nullptr) {
  std::map<std::pair<int, int>, std::size_t> overlap;
  std::vector<std::size_t> sec_size(sections.sections.size(), 0), room_size(static_cast<std::size_t>(rooms), 0);
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const int s = sections.label[i], r = gt[i];
    if (s >= 0) ++sec_size[static_cast<std::size_t>(s)];
    if (r >= 0) ++room_size[static_cast<std::size_t>(r)];
    if (s >= 0 && r >= 0) ++overlap[{s, r}];
  }
  std::vector<std::size_t> best_sec(sec_size.size(), 0), best_room(room_size.size(), 0);
  for (const auto& [key, n] : overlap) {
    best_sec[static_cast<std::size_t>(key.first)] = std::max(best_sec[static_cast<std::size_t>(key.first)], n);
    best_room[static_cast<std::size_t>(key.second)] = std::max(best_room[static_cast<std::size_t>(key.second)], n);
  }
  std::size_t ps = 0, pn = 0, rs = 0, rn = 0;
  for (std::size_t k = 0; k < sec_size.size(); ++k) ps += best_sec[k], pn += sec_size[k];
  for (std::size_t k = 0; k < room_size.size(); ++k) rs += best_room[k], rn += room_size[k];
  if (score != nullptr) {
    score->precision = pn > 0 ? static_cast<double>(ps) / static_cast<double>(pn) : 0.0;
    score->recall = rn > 0 ? static_cast<double>(rs) / static_cast<double>(rn) : 0.0;
  }
  char buf[160];
  std::snprintf(buf, sizeof buf, " %zu | %d | %.2f | %.2f |", sections.sections.size(), rooms,
                pn > 0 ? static_cast<double>(ps) / static_cast<double>(pn) : 0.0,
                rn > 0 ? static_cast<double>(rs) / static_cast<double>(rn) : 0.0);
  return buf;
}

// A seeded random room: a rectangle 4-12 m a side with 0-6 boxes and pillars inside.
OccupancyGrid random_room(unsigned seed, double resolution_m) {
  std::mt19937 rng(seed);
  const auto uni = [&](int lo, int hi) { return std::uniform_int_distribution<int>(lo, hi)(rng); };
  const int w = uni(80, 240), h = uni(80, 240);
  OccupancyGrid g(w, h, resolution_m);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const bool wall = x == 0 || y == 0 || x == w - 1 || y == h - 1;
      g.set_state({x, y}, wall ? Occupancy::occupied : Occupancy::free);
    }
  }
  const int boxes = uni(0, 6);
  for (int b = 0; b < boxes; ++b) {
    const int bw = uni(4, 30), bh = uni(4, 30);
    const int bx = uni(1, w - bw - 1), by = uni(1, h - bh - 1);
    for (int y = by; y < by + bh; ++y) {
      for (int x = bx; x < bx + bw; ++x) g.set_state({x, y}, Occupancy::occupied);
    }
  }
  return g;
}

// The map (walls black, sections grey), the cleaned cells (light green) and the path (red), as a
// PNG, row 0 at the top.
void write_picture(const fs::path& file, const OccupancyGrid& grid, const SectionSet& sections,
                   const std::vector<CoverageResult>& results, double width_m) {
  const int w = grid.width(), h = grid.height();
  std::vector<std::uint8_t> rgb(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 3, 255);
  const auto put = [&](int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) {
    if (x < 0 || y < 0 || x >= w || y >= h) return;
    const std::size_t i = (static_cast<std::size_t>(h - 1 - y) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)) * 3;
    rgb[i] = r, rgb[i + 1] = g, rgb[i + 2] = b;
  };
  CleanedCells cleaned(grid);
  for (const CoverageResult& r : results) cleaned.mark_path(r.path, width_m / 2.0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = grid.index({x, y});
      if (grid.state({x, y}) != Occupancy::free) put(x, y, 0, 0, 0);
      else if (cleaned.cleaned(i)) put(x, y, 200, 240, 200);
      else if (sections.label[i] >= 0) put(x, y, 255, 200, 200);
    }
  }
  for (const CoverageResult& r : results) {
    for (std::size_t k = 1; k < r.path.size(); ++k) {
      const Point2D a = r.path[k - 1], b = r.path[k];
      const int steps = static_cast<int>(std::ceil(std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) / (grid.resolution_m() / 2))) + 1;
      for (int t = 0; t <= steps; ++t) {
        const double f = static_cast<double>(t) / steps;
        if (const auto c = grid.world_to_cell({a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m)})) put(c->x, c->y, 220, 0, 0);
      }
    }
  }
  png_image img{};
  img.version = PNG_IMAGE_VERSION;
  img.width = static_cast<png_uint_32>(w);
  img.height = static_cast<png_uint_32>(h);
  img.format = PNG_FORMAT_RGB;
  if (png_image_write_to_file(&img, file.c_str(), 0, rgb.data(), 0, nullptr) == 0) {
    throw std::runtime_error(file.string() + ": cannot write the PNG: " + img.message);
  }
}

// A simulator world made from a floor plan (docs/simulator.md's schema): the plan as a map_server
// map (PGM), one room over the whole plan named after it ("clean the room NAME"), and the start
// where the plan's free space is widest (the footprint fits there on any plan with a room).
void export_world(const fs::path& dir, const std::string& name, const OccupancyGrid& grid) {
  fs::create_directories(dir);
  save_map(grid, dir / (name + "_map.yaml"));
  const DistanceField field(grid);
  std::size_t best = 0;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (field.distance_m(i) > field.distance_m(best)) best = i;
  }
  if (grid.size() == 0 || field.distance_m(best) <= 0.0) throw std::runtime_error(name + ": no free space for a world");
  const Point2D start = grid.cell_center(grid.cell(best));
  const double w_m = grid.width() * grid.resolution_m(), h_m = grid.height() * grid.resolution_m();
  {
    std::ofstream regions(dir / (name + "_regions.yaml"));
    regions << "# The whole floor plan " << name << " as one room (tripodal-coverage-eval --export-worlds).\n"
            << "rooms:\n  - name: \"" << name << "\"\n    rectangle: [0.0, 0.0, " << w_m << ", " << h_m << "]\n";
    if (!regions) throw std::runtime_error((dir / (name + "_regions.yaml")).string() + ": cannot write");
  }
  std::ofstream world(dir / (name + ".yaml"));
  world << "# A world made from the ipa floor plan " << name << " (tripodal-coverage-eval --export-worlds; evaluation\n"
        << "# data, not shipped). Paths are relative to this file.\n"
        << "map: " << name << "_map.yaml\nregions: " << name << "_regions.yaml\n"
        << "start_pose: [" << start.x_m << ", " << start.y_m << ", 0.0]\nseed: 1\n";
  if (!world) throw std::runtime_error((dir / (name + ".yaml")).string() + ": cannot write");
}

// The command line: which floor plans, which patterns, what to write and what to expect.
struct EvalArgs {
  std::string ipa, workspace, pictures, rooms, worlds;
  bool segment_only = false, no_touch_up = false;
  std::vector<std::string> pattern_names;
  double expect_precision = -1.0, expect_recall = -1.0, expect_bound = -1.0, expect_worst_bound = -1.0;
  bool verbose = false;
  int random_rooms = 0;
  CoverageOptions o;

  EvalArgs() {
    o.cleaning_width_m = 0.64;
    o.robot_radius_m = 0.3;
  }
  [[nodiscard]] bool wanted(Pattern p) const {
    return pattern_names.empty() || std::find(pattern_names.begin(), pattern_names.end(), name_of(p)) != pattern_names.end();
  }
};

void add_options(CLI::App& app, EvalArgs& a) {
  CoverageOptions& o = a.o;
  app.add_option("--ipa", a.ipa, "DIR: the ipa floor plans (NAME.png + NAME_gt_segmentation.png), e.g. ../shared/data/ipa-maps")
      ->check(CLI::ExistingDirectory);
  app.add_option("--workspace", a.workspace, "MAP.yaml: a map_server map (e.g. configs/worlds/workspace_map.yaml)")
      ->check(CLI::ExistingFile);
  app.add_option("--random", a.random_rooms, "N: N seeded random rooms (seeds 1..N)")->check(cli::positive_count());
  app.add_option("--pictures", a.pictures, "DIR: the paths per map and pattern as PNG pictures")->check(cli::writable_folder());
  app.add_flag("--verbose", a.verbose, "per-section figures (ipa maps: worst excess over the bound first)");
  app.add_option("--width", o.cleaning_width_m, "M: cleaning width (PSR-2's)")
      ->check(cli::positive_number())
      ->capture_default_str();
  app.add_option("--radius", o.robot_radius_m, "M: robot radius")->check(cli::positive_number())->capture_default_str();
  app.add_option("--lane-overlap", o.lane_overlap_m, "M: CoverageOptions::lane_overlap_m")->check(cli::non_negative_number());
  app.add_option("--lane-inset", o.lane_inset_m, "M: CoverageOptions::lane_inset_m")->check(cli::non_negative_number());
  app.add_option("--turn-cost", o.turn_cost_m, "M: CoverageOptions::turn_cost_m")->check(cli::non_negative_number());
  app.add_option("--link-margin", o.link_margin_m,
                 "M: CoverageOptions::link_margin_m (the clearance links keep beyond the robot radius)")
      ->check(cli::non_negative_number());
  app.add_option("--export-worlds", a.worlds,
                 "DIR: with --ipa, write a simulator world per plan (NAME.yaml, its map and one room NAME) and plan nothing")
      ->check(cli::writable_folder());
  app.add_flag("--no-touch-up", a.no_touch_up,
               "plan without the touch-up (CoverageOptions::touch_up off): what the passes leave");
  app.add_option("--rooms", a.rooms,
                 "METHOD: cover the rooms of a room segmentation (morphological, distance_transform, voronoi) instead of the "
                 "section splitter's sections")
      ->check(CLI::IsMember({"morphological", "distance_transform", "voronoi"}));
  app.add_flag("--segment-only", a.segment_only, "with --ipa: only the room segmentation's precision and recall, no coverage");
  app.add_option("--pattern", a.pattern_names,
                 "NAME: only this pattern (repeatable): balloon, boustrophedon, hybrid, distance_transform")
      ->check(CLI::IsMember({"balloon", "boustrophedon", "hybrid", "distance_transform"}));
  app.add_option("--expect-precision", a.expect_precision, "P: with --ipa, exit 1 unless the mean room precision is at least P")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--expect-recall", a.expect_recall, "R: with --ipa, exit 1 unless the mean room recall is at least R")
      ->check(CLI::Range(0.0, 1.0));
  app.add_option("--expect-bound", a.expect_bound,
                 "X: with --ipa, exit 1 unless the hybrid's mean length / bound over the maps is at most X")
      ->check(cli::positive_number());
  app.add_option("--expect-worst-bound", a.expect_worst_bound,
                 "X: with --ipa, exit 1 unless the hybrid's length / bound is at most X on every map")
      ->check(cli::positive_number());
}

// --workspace: every wanted pattern on one map_server map.
void eval_workspace(const EvalArgs& a) {
  const CoverageOptions& o = a.o;
  const MapFile m = load_map(a.workspace);
  const SectionSet sections = split(m.grid, a.rooms).sections;
  header(false);
  for (const Pattern p : kPatterns) {
    if (!a.wanted(p)) continue;
    std::vector<CoverageResult> results;
    print_row(fs::path(a.workspace).stem().string(), p, cover(m.grid, sections, p, o, &results), o.cleaning_width_m);
    if (!a.pictures.empty()) {
      fs::create_directories(a.pictures);
      write_picture(fs::path(a.pictures) / (std::string(name_of(p)) + ".png"), m.grid, sections, results, o.cleaning_width_m);
    }
    if (a.verbose) {
      for (const CoverageResult& r : results) {
        std::printf("    %.1f m, %zu turns, %zu passes, %zu touch-ups\n", r.stats.length_m, r.stats.turns, r.passes, r.touch_ups);
      }
    }
  }
  std::printf("\n");
}

// The ipa floor plans in `dir` (NAME.png beside NAME_gt_segmentation.png), by name.
std::vector<std::string> ipa_names(const std::string& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string f = e.path().filename().string();
    const std::string suffix = "_gt_segmentation.png";
    if (f.size() > suffix.size() && f.ends_with(suffix)) names.push_back(f.substr(0, f.size() - suffix.size()));
  }
  std::sort(names.begin(), names.end());
  return names;
}

// One ipa plan: its world exported, or its segmentation scored and every wanted pattern run on
// it (the hybrid's length / bound kept).
void eval_ipa_map(const EvalArgs& a, const std::string& name, std::vector<Score>& scores, std::vector<double>& hybrid_ratio) {
  const CoverageOptions& o = a.o;
  const Gray plan = read_png(fs::path(a.ipa) / (name + ".png"));
  const Gray truth = read_png(fs::path(a.ipa) / (name + "_gt_segmentation.png"));
  const OccupancyGrid grid = grid_of(plan, 0.05);
  if (!a.worlds.empty()) {
    export_world(a.worlds, name, grid);
    std::printf("%s: %s\n", name.c_str(), (fs::path(a.worlds) / (name + ".yaml")).c_str());
    return;
  }
  const Split cut = split(grid, a.rooms);
  const SectionSet& sections = cut.sections;
  int truth_rooms = 0;
  const std::vector<int> gt = rooms_of(truth, 400, truth_rooms);  // rooms of at least 1 m2
  char ms[32];
  std::snprintf(ms, sizeof ms, " %.1f |", cut.ms);
  Score score;
  const bool comparable = truth.width == plan.width && truth.height == plan.height;
  const std::string seg = (comparable ? segmentation(sections, gt, truth_rooms, &score) : " - | - | - | - |") + ms;
  if (comparable) scores.push_back(score);
  if (a.segment_only) {
    std::printf("| %s | %s |%s\n", name.c_str(), a.rooms.empty() ? "splitter" : a.rooms.c_str(), seg.c_str());
    return;
  }
  for (const Pattern p : kPatterns) {
    if (!a.wanted(p)) continue;
    std::vector<CoverageResult> results;
    const Figures f = cover(grid, sections, p, o, &results);
    add(p, f);
    if (!a.pictures.empty()) {
      fs::create_directories(a.pictures);
      write_picture(fs::path(a.pictures) / (name + "_" + name_of(p) + ".png"), grid, sections, results, o.cleaning_width_m);
    }
    if (a.verbose) print_sections(results, grid.resolution_m(), o.cleaning_width_m);
    print_row(name, p, f, o.cleaning_width_m, seg);
    if (p == Pattern::hybrid && f.reachable_m2 > 0) hybrid_ratio.push_back(f.length_m / (f.reachable_m2 / o.cleaning_width_m));
  }
}

// The means over the ipa maps, and what falls short of the expectations (a test over the ipa
// set: tests/app, tripodal_coverage_eval_ipa:*), one line each.
std::string ipa_expectations(const EvalArgs& a, const std::vector<Score>& scores, const std::vector<double>& hybrid_ratio) {
  auto mean = [](const std::vector<double>& v) {
    return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
  };
  std::vector<double> precision, recall;
  for (const Score& sc : scores) precision.push_back(sc.precision), recall.push_back(sc.recall);
  std::printf("\nmean over %zu maps: precision %.3f, recall %.3f", scores.size(), mean(precision), mean(recall));
  if (!hybrid_ratio.empty()) {
    std::printf(", hybrid length / bound %.3f (worst %.3f)", mean(hybrid_ratio),
                *std::max_element(hybrid_ratio.begin(), hybrid_ratio.end()));
  }
  std::printf("\n");
  std::string failures;
  if (a.expect_precision >= 0 && mean(precision) < a.expect_precision)
    failures += "mean precision below the expected " + std::to_string(a.expect_precision) + "\n";
  if (a.expect_recall >= 0 && mean(recall) < a.expect_recall)
    failures += "mean recall below the expected " + std::to_string(a.expect_recall) + "\n";
  if ((a.expect_bound > 0 || a.expect_worst_bound > 0) && hybrid_ratio.empty())
    failures += "no hybrid figures to check (--pattern hybrid)\n";
  if (a.expect_bound > 0 && !hybrid_ratio.empty() && mean(hybrid_ratio) > a.expect_bound) {
    failures += "mean hybrid length / bound above the expected " + std::to_string(a.expect_bound) + "\n";
  }
  if (a.expect_worst_bound > 0 && !hybrid_ratio.empty() &&
      *std::max_element(hybrid_ratio.begin(), hybrid_ratio.end()) > a.expect_worst_bound) {
    failures += "worst hybrid length / bound above the expected " + std::to_string(a.expect_worst_bound) + "\n";
  }
  return failures;
}

// --ipa: every plan, then the means and the totals; adds what falls short to `failures`. False
// when it only exported worlds (the run ends there).
bool eval_ipa(const EvalArgs& a, std::string& failures) {
  const std::vector<std::string> names = ipa_names(a.ipa);
  header(true);
  std::vector<Score> scores;
  std::vector<double> hybrid_ratio;
  for (const std::string& name : names) eval_ipa_map(a, name, scores, hybrid_ratio);
  if (!a.worlds.empty()) return false;
  failures += ipa_expectations(a, scores, hybrid_ratio);
  if (!a.segment_only) {
    for (const Pattern p : kPatterns) {
      if (a.wanted(p)) print_row("all ipa maps", p, totals[p], a.o.cleaning_width_m);
    }
  }
  totals.clear();
  std::printf("\n");
  return true;
}

// --random N: every wanted pattern over N seeded rooms, in total.
void eval_random_rooms(const EvalArgs& a) {
  header(false);
  for (int s = 1; s <= a.random_rooms; ++s) {
    const OccupancyGrid grid = random_room(static_cast<unsigned>(s), 0.05);
    const SectionSet sections = CSectionSplitter().split(grid);
    for (const Pattern p : kPatterns) {
      if (a.wanted(p)) add(p, cover(grid, sections, p, a.o));
    }
  }
  for (const Pattern p : kPatterns) {
    if (a.wanted(p)) print_row(std::to_string(a.random_rooms) + " random rooms", p, totals[p], a.o.cleaning_width_m);
  }
}

int run(int argc, char** argv) {
  EvalArgs a;
  CLI::App app{
      "Evaluates the coverage patterns (hybrid, balloon, boustrophedon, distance_transform) on floor plans: the ipa maps,\n"
      "a map_server map, or seeded random rooms (docs/coverage.md).\n"};
  add_options(app, a);
  if (auto code =
          cli::parse_command_line(app, "tripodal-coverage-eval",
                                  "exit codes: 0 ok, 1 a map could not be read or covered, 2 bad command line", argc, argv)) {
    return *code;
  }
  if (a.ipa.empty() && a.workspace.empty() && a.random_rooms <= 0) {
    std::cerr << "tripodal-coverage-eval: give --ipa DIR, --workspace MAP.yaml or --random N\nrun "
                 "'tripodal-coverage-eval --help' for the usage\n";
    return cli::kUsage;
  }
  a.o.touch_up = !a.no_touch_up;
  if (!a.worlds.empty()) a.segment_only = true;  // the worlds only, no plan
  std::string failures;
  try {
    if (!a.workspace.empty()) eval_workspace(a);
    if (!a.ipa.empty() && !eval_ipa(a, failures)) return 0;
    if (a.random_rooms > 0) eval_random_rooms(a);
  } catch (const std::exception& e) {
    std::cerr << "tripodal-coverage-eval: " << e.what() << "\n";
    return 1;
  }
  if (!failures.empty()) {
    std::cerr << "tripodal-coverage-eval: " << failures;
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  // CLI11's own set-up and the printing can throw too (bad_alloc, stream errors): none may escape main.
  try {
    return run(argc, argv);
  } catch (const std::exception& e) {
    std::cerr << "tripodal-coverage-eval: error: " << e.what() << "\n";
  } catch (...) {
    std::cerr << "tripodal-coverage-eval: error: unexpected exception\n";
  }
  return 1;
}
