// Helpers shared by the navi tests: a temporary folder and small grids drawn from ASCII art.
#pragma once

#include <unistd.h>

#include <atomic>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tripodal/navi/occupancy_grid.hpp"

namespace tripodal::navi::test {

/// A fresh folder in the temporary directory, removed with its contents at scope exit.
class TempDir {
 public:
  explicit TempDir(const std::string& stem) {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("tripodal_navi_" + stem + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  [[nodiscard]] std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

inline void write_file(const std::filesystem::path& p, const std::string& bytes) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f << bytes;
}

/// A grid from rows of text, the FIRST string being the TOP row (highest y), as a picture reads:
/// '#' occupied, '.' free, '?' unknown.
inline OccupancyGrid grid_from_art(const std::vector<std::string>& rows, double resolution_m = 0.05,
                                   Pose2D origin = {}) {
  const int h = static_cast<int>(rows.size());
  const int w = h == 0 ? 0 : static_cast<int>(rows[0].size());
  OccupancyGrid g(w, h, resolution_m, origin);
  for (int r = 0; r < h; ++r) {
    for (int x = 0; x < w; ++x) {
      const char c = rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(x)];
      g.set_state({x, h - 1 - r}, c == '#' ? Occupancy::occupied : c == '.' ? Occupancy::free : Occupancy::unknown);
    }
  }
  return g;
}

/// A rectangular room: a one-cell wall around free space.
inline OccupancyGrid room(int w, int h, double resolution_m = 0.05) {
  OccupancyGrid g(w, h, resolution_m, {}, Occupancy::free);
  for (int x = 0; x < w; ++x) {
    g.set_state({x, 0}, Occupancy::occupied);
    g.set_state({x, h - 1}, Occupancy::occupied);
  }
  for (int y = 0; y < h; ++y) {
    g.set_state({0, y}, Occupancy::occupied);
    g.set_state({w - 1, y}, Occupancy::occupied);
  }
  return g;
}

/// How many of `built`'s occupied cells there are, and how many lie on or beside (one cell) an
/// occupied cell of `world`: a built map lines up with the world when nearly all do.
struct WallAgreement {
  std::size_t marked = 0;
  std::size_t on_wall = 0;
  [[nodiscard]] double fraction() const noexcept {
    return marked == 0 ? 0.0 : static_cast<double>(on_wall) / static_cast<double>(marked);
  }
};

inline WallAgreement wall_agreement(const OccupancyGrid& built, const OccupancyGrid& world) {
  WallAgreement a;
  const double step = world.resolution_m();
  for (std::size_t i = 0; i < built.size(); ++i) {
    if (built.state(i) != Occupancy::occupied) continue;
    ++a.marked;
    const Point2D p = built.cell_center(built.cell(i));
    bool near = false;
    for (int dy = -1; dy <= 1 && !near; ++dy) {
      for (int dx = -1; dx <= 1 && !near; ++dx) {
        const auto c = world.world_to_cell({p.x_m + dx * step, p.y_m + dy * step});
        near = c && world.is_occupied(*c);
      }
    }
    a.on_wall += near ? 1 : 0;
  }
  return a;
}

}  // namespace tripodal::navi::test
