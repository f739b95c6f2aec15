// Helpers shared by the simulator tests: worlds built in code, base configurations, temp files.
#pragma once

#include <unistd.h>

#include <atomic>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <vector>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/navi/occupancy_grid.hpp"
#include "tripodal/sim/world.hpp"

namespace tripodal::sim::test {

/// A room of w x h cells with a one-cell wall around free space; origin at (0, 0).
inline navi::OccupancyGrid room_grid(int w, int h, double res = 0.05) {
  navi::OccupancyGrid g(w, h, res, {}, navi::Occupancy::free);
  for (int x = 0; x < w; ++x) {
    g.set_state({x, 0}, navi::Occupancy::occupied);
    g.set_state({x, h - 1}, navi::Occupancy::occupied);
  }
  for (int y = 0; y < h; ++y) {
    g.set_state({0, y}, navi::Occupancy::occupied);
    g.set_state({w - 1, y}, navi::Occupancy::occupied);
  }
  return g;
}

/// A world in a room of w x h cells with the robot at `start`; noise-free sensors unless asked.
inline World room_world(int w, int h, Pose2D start, double res = 0.05) {
  World world;
  world.grid = room_grid(w, h, res);
  world.start_pose = start;
  world.robot.laser.noise_stddev_m = 0.0;
  world.robot.odometry.noise_ratio = 0.0;
  world.robot.gyro.noise_stddev_rad_s = 0.0;
  return world;
}

inline ControllerConfig differential_base() {
  ControllerConfig c;
  c.type = "differential";
  c.differential = {0.42, 0.09};
  return c;
}

inline ControllerConfig omni3_base() {
  ControllerConfig c;
  c.type = "omni";
  const std::vector<double> angles = {60.0 * std::numbers::pi / 180.0, std::numbers::pi, 300.0 * std::numbers::pi / 180.0};
  c.holonomic = omni_base(0.05, 0.22, angles);
  return c;
}

inline ControllerConfig mecanum_base4() {
  ControllerConfig c;
  c.type = "mecanum";
  c.holonomic = mecanum_base(0.05, 0.2, 0.18);
  return c;
}

/// A fresh folder in the temporary directory, removed with its contents at scope exit.
class TempDir {
 public:
  explicit TempDir(const std::string& stem) {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("tripodal_sim_" + stem + "_" + std::to_string(::getpid()) + "_" + std::to_string(counter++));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  [[nodiscard]] std::filesystem::path operator/(const std::string& name) const { return path_ / name; }

 private:
  std::filesystem::path path_;
};

inline void write_file(const std::filesystem::path& p, const std::string& text) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f << text;
}

/// The message of the ConfigError that loading `text` as a world file DIR/world.yaml throws ("" if
/// none).
inline std::string world_error_of(const std::string& text) {
  TempDir dir("world");
  write_file(dir / "world.yaml", text);
  try {
    (void)load_world(dir / "world.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return {};
}

}  // namespace tripodal::sim::test
