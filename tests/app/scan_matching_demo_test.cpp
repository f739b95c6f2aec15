// The demo robot localizes from its laser: the robot profiles name the scan-matching localizer,
// and on the simulator it works from the simulated RPLIDAR and the drifting wheel odometry
// (docs/localization.md). A kidnapping (the world carries the robot off without a wheel turning)
// is then a physical localization loss: the localizer notices it from its match quality, and the
// paper's PrCleaning / PrGlobalLocalization narrative follows.
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "run_task.hpp"
#include "tripodal/robot/robot_profile.hpp"

using namespace tripodal;
using namespace tripodal::app;

namespace {

const std::filesystem::path kSource = TRIPODAL_SOURCE_DIR;

// One row of trajectory.csv: time, true pose, estimate, localized.
struct Sample {
  double t = 0.0, x = 0.0, y = 0.0, ex = 0.0, ey = 0.0;
  bool localized = false;
  [[nodiscard]] double error() const { return std::hypot(ex - x, ey - y); }
};

std::vector<Sample> trajectory(const std::filesystem::path& csv) {
  std::ifstream in(csv);
  std::string line;
  std::getline(in, line);  // header
  std::vector<Sample> out;
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::vector<double> v;
    for (std::string cell; std::getline(row, cell, ',');) v.push_back(std::stod(cell));
    REQUIRE(v.size() == 9);
    out.push_back({v[0], v[1], v[2], v[4], v[5], v[7] != 0.0});
  }
  return out;
}

std::string read(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// The workspace world with extra faults, written beside a temporary folder (map paths absolute).
std::filesystem::path world_with(const std::filesystem::path& dir, const std::string& faults) {
  std::filesystem::create_directories(dir);
  const auto worlds = kSource / "configs/worlds";
  const auto file = dir / "world.yaml";
  std::ofstream(file) << "map: " << (worlds / "workspace_map.yaml").string() << "\n"
                      << "regions: " << (worlds / "workspace_regions.yaml").string() << "\n"
                      << "start_pose: [0.8, 0.8, 0.0]\nseed: 1\n"
                      << "robot:\n  laser: {preset: rplidar_a1, noise_stddev_m: 0.01}\n  odometry: {noise_ratio: 0.01}\n"
                      << "faults:\n"
                      << faults;
  return file;
}

struct TempDir {
  std::filesystem::path path;
  explicit TempDir(const std::string& name)
      : path(std::filesystem::temp_directory_path() / (name + "_" + std::to_string(::getpid()))) {}
  ~TempDir() { std::filesystem::remove_all(path); }
};

}  // namespace

TEST_CASE("The demo robots' profiles localize from the laser", "[app][scan_matching]") {
  for (const char* robot : {"psr2.yaml", "jinny_differential.yaml"}) {
    const RobotProfile p = load_robot_profile(kSource / "configs/robots" / robot);
    const ModuleEntry* localizer = nullptr;
    for (const ModuleEntry& e : p.navigation) {
      if (e.name == "localizer") localizer = &e;
    }
    INFO(robot);
    REQUIRE(localizer != nullptr);
    CHECK(localizer->type == "ScanMatchingLocalizer");
  }
}

TEST_CASE("PSR-2, localizing from its laser, cleans room 2111", "[app][run][scan_matching]") {
  const TempDir dir("tripodal_app_sm");
  RunOptions o;
  o.robot = kSource / "configs/robots/psr2.yaml";
  o.world = kSource / "configs/worlds/workspace.yaml";
  o.task = "clean the room 2111";
  o.seed = 2;
  o.out = dir.path / "out";
  const RunResult r = run_task(o);
  CHECK(r.succeeded);
  CHECK(r.state == "succeeded");
  CHECK(r.coverage >= 0.99);
  CHECK(r.collisions == 0);
  REQUIRE(r.sections.size() == 1);
  CHECK(r.sections[0].name == "A");
  // The estimate is the matcher's, not the truth: within centimetres, never lost.
  const std::vector<Sample> path = trajectory(o.out / "trajectory.csv");
  REQUIRE(path.size() > 100);
  // From the first second: the odometry resource's first reading precedes the controller's reset
  // to the start pose, and that one jump moves the estimate off for one sample at 0.1 s.
  double sum = 0.0, worst = 0.0;
  std::size_t n = 0;
  for (const Sample& s : path) {
    CHECK(s.localized);
    if (s.t < 1.0) continue;
    sum += s.error();
    worst = std::max(worst, s.error());
    ++n;
  }
  const double mean = sum / static_cast<double>(n);
  INFO("mean error " << mean << " m, worst " << worst << " m");
  // seed 1 on room 3211: 0.008 m mean, 0.017 m p95
  CHECK(mean < 0.02);
  CHECK(worst < 0.10);
}

TEST_CASE("A kidnapped robot is detected from its scans and found again by PrGlobalLocalization",
          "[app][run][scan_matching][kidnap]") {
  const TempDir dir("tripodal_app_kidnap");
  RunOptions o;
  o.robot = kSource / "configs/robots/psr2.yaml";
  // At 60 s, carried 3 m across section A (the odometry does not see it).
  o.world = world_with(dir.path, "  kidnap:\n    - {at_s: 60, to: [2.5, 6.0, 2.0]}\n");
  o.task = "clean the room 2111";
  o.seed = 1;
  o.out = dir.path / "out";
  const RunResult r = run_task(o);
  const std::string life = read(o.out / "lifecycle.txt");
  INFO(life);
  CHECK(r.succeeded);
  CHECK(r.collisions == 0);
  // Measured 0.945, against 0.998 without the kidnapping; where the 5 points go is not analysed
  // yet (docs/localization.md, Not done).
  CHECK(r.coverage >= 0.93);
  // The narrative: the scans stop matching (localizer.lost, PrCleaning pauses: t3), the loss lasts
  // (t5: localization fault), the recovery rule inserts PrGlobalLocalization, whose global search
  // finds the robot, and PrCleaning resumes.
  const auto at = [&](const std::string& what) { return life.find(what); };
  REQUIRE(at("simulator: kidnapped to (2.50, 6.00, 2.00)") != std::string::npos);
  CHECK(at("simulator: kidnapped") < at("fire t3 [localizer.lost]"));
  CHECK(at("fire t3 [localizer.lost]") < at("PrCleaning failed: localization fault"));
  CHECK(at("PrCleaning failed: localization fault") < at("insert PrGlobalLocalization"));
  CHECK(at("insert PrGlobalLocalization") < at("PrGlobalLocalization succeeded"));
  CHECK(at("PrGlobalLocalization succeeded") != std::string::npos);
  REQUIRE(r.recoveries.size() == 1);

  const std::vector<Sample> path = trajectory(o.out / "trajectory.csv");
  REQUIRE(path.size() > 100);
  // Before the kidnapping: tracked. Just after: the estimate stayed where the odometry says, 3 m
  // off, and the robot is declared lost within a few scans (5.5 Hz, 5 poor scans).
  double worst_before = 0.0, first_lost = -1.0, error_after = 0.0;
  for (const Sample& s : path) {
    if (s.t > 1.0 && s.t < 59.9) worst_before = std::max(worst_before, s.error());
    if (s.t > 60.05 && s.t < 60.2) error_after = std::max(error_after, s.error());
    if (s.t >= 60.0 && first_lost < 0.0 && !s.localized) first_lost = s.t;
  }
  CHECK(worst_before < 0.1);
  CHECK(error_after > 2.0);
  REQUIRE(first_lost > 0.0);
  CHECK(first_lost < 62.0);
  // Found again: localized and within centimetres for the rest of the run.
  double worst_end = 0.0;
  for (std::size_t i = path.size() - path.size() / 4; i < path.size(); ++i) {
    CHECK(path[i].localized);
    worst_end = std::max(worst_end, path[i].error());
  }
  CHECK(worst_end < 0.1);
}

TEST_CASE("A laser dazzled for a few seconds is a short loss: PrCleaning pauses and resumes, no fault",
          "[app][run][scan_matching]") {
  const TempDir dir("tripodal_app_dazzled");
  RunOptions o;
  o.robot = kSource / "configs/robots/psr2.yaml";
  o.world = world_with(dir.path, "  localization_loss: \"60-64\"\n");
  o.task = "clean the room 2111";
  o.seed = 1;
  o.out = dir.path / "out";
  const RunResult r = run_task(o);
  const std::string life = read(o.out / "lifecycle.txt");
  INFO(life);
  CHECK(r.succeeded);
  CHECK(r.coverage >= 0.99);
  const auto lost = life.find("fire t3 [localizer.lost]");
  REQUIRE(lost != std::string::npos);
  CHECK(life.find("fire t2 [localizer.ok]", lost) != std::string::npos);
  CHECK(life.find("localization fault") == std::string::npos);
  CHECK(r.recoveries.empty());
}
