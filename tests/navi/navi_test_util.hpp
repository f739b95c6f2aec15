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

}  // namespace tripodal::navi::test
