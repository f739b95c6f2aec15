// The pieces of `tripodal run` that are not the robot: the PNG encoder (decoded back with zlib),
// the path figures of the report, the report's JSON, and the run's refusals of bad input.
#include <unistd.h>
#include <zlib.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <sstream>

#include "png.hpp"
#include "run_task.hpp"
#include "shutdown.hpp"
#include "tripodal/controllers/differential_drive_controller.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/core/diagnostic.hpp"

using namespace tripodal;
using namespace tripodal::app;

namespace {

std::uint32_t be32(const std::string& s, std::size_t at) {
  return (static_cast<std::uint32_t>(static_cast<unsigned char>(s[at])) << 24) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 1])) << 16) |
         (static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 2])) << 8) |
         static_cast<std::uint32_t>(static_cast<unsigned char>(s[at + 3]));
}

struct Chunk {
  std::string type, data;
  std::uint32_t crc = 0;
};

std::vector<Chunk> chunks(const std::string& png) {
  std::vector<Chunk> out;
  std::size_t at = 8;
  while (at + 12 <= png.size()) {
    const std::uint32_t len = be32(png, at);
    Chunk c;
    c.type = png.substr(at + 4, 4);
    c.data = png.substr(at + 8, len);
    c.crc = be32(png, at + 8 + len);
    out.push_back(c);
    at += 12 + len;
  }
  return out;
}

const std::filesystem::path kSource = TRIPODAL_SOURCE_DIR;

// A clock whose sleep moves it to the deadline at once: braking on it takes no wall time.
class SteppingClock final : public Clock {
 public:
  [[nodiscard]] Time now() const noexcept override { return now_; }
  void sleep_until(Time deadline) const noexcept override { now_ = std::max(now_, deadline); }

 private:
  mutable Time now_{};
};

// A differential base (Jinny's wheels) braking at 2 m/s^2, driven at 0.5 m/s as the behavior
// loop left it when its thread stopped.
struct MovingBase {
  ControllerConfig config = [] {
    ControllerConfig c;
    c.name = "base";
    c.type = "differential";
    c.period = std::chrono::milliseconds(10);
    c.differential = {0.4, 0.1};
    c.limits.vx.max_acceleration = 1.0;
    c.limits.vx.max_deceleration = 2.0;
    return c;
  }();
  IdealWheelHardware wheels{2, config.period};
  DifferentialDriveController controller{config, wheels};
  SteppingClock clock;

  MovingBase() {
    for (int k = 0; k < 100; ++k) {
      controller.set_command({0.5, 0.0, 0.0}, clock.now());
      (void)controller.update(clock.now());
      clock.sleep_until(clock.now() + config.period);
    }
  }
};

}  // namespace

TEST_CASE("PNG: signature, header, CRCs, and pixels that zlib decodes back", "[app][png]") {
  RgbImage img(3, 2, 10, 20, 30);
  img.set(2, 1, 255, 0, 128);
  img.blend(0, 0, 110, 120, 130, 0.5);
  img.set(7, 7, 1, 1, 1);  // outside: ignored
  const std::string png = encode_png(img);
  REQUIRE(png.substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8));
  const auto cs = chunks(png);
  REQUIRE(cs.size() == 3);
  CHECK(cs[0].type == "IHDR");
  CHECK(be32(cs[0].data, 0) == 3);
  CHECK(be32(cs[0].data, 4) == 2);
  CHECK(cs[0].data.substr(8) == std::string("\x08\x02\x00\x00\x00", 5));
  CHECK(cs[2].type == "IEND");
  CHECK(cs[2].crc == 0xAE426082u);  // the well-known CRC of an empty IEND chunk
  for (const auto& c : cs) CHECK(c.crc == png_crc32(c.type + c.data));
  REQUIRE(cs[1].type == "IDAT");
  std::string raw(2 * (1 + 9), '\0');
  uLongf size = raw.size();
  REQUIRE(::uncompress(reinterpret_cast<Bytef*>(raw.data()), &size, reinterpret_cast<const Bytef*>(cs[1].data.data()),
                       cs[1].data.size()) == Z_OK);
  REQUIRE(size == raw.size());
  const unsigned char bytes[] = {0, 60, 70, 80, 10, 20, 30, 10, 20, 30,  // filter 0, blended, fill, fill
                                 0, 10, 20, 30, 10, 20, 30, 255, 0, 128};
  const std::string expected(reinterpret_cast<const char*>(bytes), sizeof bytes);
  CHECK(raw == expected);
  CHECK_THROWS_WITH(encode_png(RgbImage{}), Catch::Contains("empty image"));
  RgbImage broken(2, 2);
  broken.rgb.pop_back();
  CHECK_THROWS_WITH(encode_png(broken), Catch::Contains("wrong size"));
  CHECK_THROWS_WITH(write_png("/nonexistent-dir/x.png", img), Catch::Contains("cannot write /nonexistent-dir/x.png"));
}

TEST_CASE("Path figures: length of the path, turns of its simplified shape", "[app]") {
  using navi::Point2D;
  // An L with a little zig-zag (1 cm) on the first leg: one turn, the zig-zag simplified away.
  std::vector<Point2D> l;
  for (int i = 0; i <= 100; ++i) l.push_back({0.01 * i, (i % 2) * 0.01});
  for (int i = 1; i <= 50; ++i) l.push_back({1.0, 0.02 * i});
  const PathFigures f = path_figures(l);
  CHECK(f.turns == 1);
  CHECK(f.length_m > 2.0);  // the zig-zag's own length counts: it is what the robot drove
  const PathFigures square = path_figures({{0, 0}, {1, 0}, {1, 1}, {0, 1}, {0, 0}});
  CHECK(square.turns == 3);
  CHECK(square.length_m == Approx(4.0));
  CHECK(path_figures({}).turns == 0);
  CHECK(path_figures({{1, 1}}).length_m == 0.0);
}

TEST_CASE("The run report is JSON with the measured values, strings escaped", "[app]") {
  RunResult r;
  r.robot = "psr2";
  r.task = "clean the \"big\" room";
  r.state = "succeeded";
  r.succeeded = true;
  r.coverage = 0.98765;
  r.total.length_m = 12.345;
  r.total.turns = 7;
  r.recoveries = {"310.000 fault"};
  SectionFigures s;
  s.name = "A";
  s.hybrid.turns = 5;
  s.balloon.turns = 3;
  s.boustrophedon.turns = 9;
  r.sections.push_back(s);
  const std::string j = r.json();
  CHECK_THAT(j, Catch::Contains("\"task\": \"clean the \\\"big\\\" room\"") && Catch::Contains("\"coverage\": 0.9877") &&
                    Catch::Contains("\"path\": {\n    \"length_m\": 12.35,\n    \"turns\": 7") &&
                    Catch::Contains("\"recoveries\": [\n    \"310.000 fault\"\n  ]") &&
                    Catch::Contains("\"hybrid\": {\n        \"length_m\": 0.0,\n        \"turns\": 5") &&
                    Catch::Contains("\"balloon\": {\n        \"length_m\": 0.0,\n        \"turns\": 3") &&
                    Catch::Contains("\"boustrophedon\": {\n        \"length_m\": 0.0,\n        \"turns\": 9") &&
                    Catch::Contains("\"succeeded\": true"));
  // The keys in the documented order, the whole report parsed back.
  const auto parsed = nlohmann::json::parse(j);
  CHECK(parsed.at("sections").at(0).at("name") == "A");
  CHECK(parsed.at("path").at("length_m") == 12.35);
  CHECK(j.find("\"robot\"") < j.find("\"task\""));
  CHECK(j.find("\"faults\"") < j.find("\"robot_steps\""));
}

TEST_CASE("The run report never prints a number that is not JSON", "[app]") {
  RunResult r;
  r.coverage = std::nan("");
  r.duration_s = std::numeric_limits<double>::infinity();
  r.total.length_m = -std::numeric_limits<double>::infinity();
  const std::string j = r.json();
  CHECK_THAT(j, Catch::Contains("\"coverage\": null") && Catch::Contains("\"duration_s\": null") &&
                    Catch::Contains("\"length_m\": null"));
  CHECK_THAT(j, !Catch::Contains("nan") && !Catch::Contains("inf"));
  CHECK_NOTHROW(nlohmann::json::parse(j));
}

TEST_CASE("run_task refuses a profile whose controller names no configuration, with its location", "[app]") {
  const auto dir = std::filesystem::temp_directory_path() / ("tripodal_app_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  std::ifstream in(kSource / "configs/robots/psr2.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const auto at = text.find("    parameters: { config: ../reactive/psr_omni.yaml }");
  REQUIRE(at != std::string::npos);
  text.erase(at, text.find('\n', at) - at + 1);
  // paths of the profile are relative to it: point them back at the source tree
  for (const std::string key : {"../petri/", "../tasks/"}) {
    for (auto p = text.find(key); p != std::string::npos; p = text.find(key, p + 1)) {
      text.replace(p, 3, (kSource / "configs").string() + "/");
    }
  }
  const auto profile = dir / "robot.yaml";
  std::ofstream(profile) << text;
  RunOptions o;
  o.robot = profile;
  o.world = kSource / "configs/worlds/workspace.yaml";
  o.task = "clean the room 3211";
  REQUIRE_THROWS_WITH(run_task(o), Catch::Contains("robot.yaml:16:5: error: controller 'base' needs parameters: {config: FILE}"));
  std::filesystem::remove_all(dir);
}

TEST_CASE("run_task in process: PSR-2 cleans room 2111 and measures it", "[app][run]") {
  RunOptions o;
  o.robot = kSource / "configs/robots/psr2.yaml";
  o.world = kSource / "configs/worlds/workspace.yaml";
  o.task = "clean the room 2111";
  o.seed = 2;
  const RunResult r = run_task(o);
  CHECK(r.succeeded);
  CHECK(r.state == "succeeded");
  CHECK(r.reachable_cells > 20000);  // about 60 m2 at 5 cm cells
  CHECK(r.coverage >= 0.99);
  CHECK(r.collisions == 0);
  REQUIRE(r.sections.size() == 1);
  CHECK(r.sections[0].name == "A");
  CHECK(r.total.length_m > r.cleaning.length_m - 1e-9);
  CHECK(r.processes.size() == 2);
  o.task = "clean the kitchen now";
  const RunResult refused = run_task(o);
  CHECK(refused.state == "refused");
  CHECK_THAT(refused.reason, Catch::Contains("not understood"));
}

TEST_CASE("run_task: the order of the processes follows the start (section D first from D, A first from the charger)",
          "[app][run][order]") {
  // Paper, section 5.1: the order of PrAutoMove and PrCleaning changes with the initial position.
  // A minute of simulated time is enough to see the plan and the first PrAutoMove end in the
  // first section; the whole run from D is the CLI test tripodal_run_cli:start_in_d_cleans_d_first.
  RunOptions o;
  o.robot = kSource / "configs/robots/psr2.yaml";
  o.task = "clean the room 3211";
  o.max_duration_s = 60.0;
  std::ostringstream log;
  o.log = &log;

  o.world = kSource / "configs/worlds/workspace_start_d.yaml";
  const RunResult d = run_task(o);
  CHECK(d.state == "timed out");
  CHECK_THAT(log.str(), Catch::Contains("PrAutoMove(goal=D.entry) -> PrCleaning(section=D) -> PrAutoMove(goal=C.entry) -> "
                                        "PrCleaning(section=C) -> PrAutoMove(goal=B.entry) -> PrCleaning(section=B) -> "
                                        "PrAutoMove(goal=A.entry) -> PrCleaning(section=A)"));
  REQUIRE(d.processes.size() == 2);
  CHECK_THAT(d.processes[0], Catch::EndsWith("X0 PrAutoMove(goal=D.entry) succeeded"));
  CHECK_THAT(d.processes[1], Catch::Contains("X1 PrCleaning(section=D) failed: stopped: no end within 60 s"));

  log.str({});
  o.world = kSource / "configs/worlds/workspace.yaml";  // the charger, in section A
  const RunResult a = run_task(o);
  CHECK_THAT(log.str(), Catch::Contains("PrAutoMove(goal=A.entry) -> PrCleaning(section=A) -> PrAutoMove(goal=B.entry) -> "
                                        "PrCleaning(section=B) -> PrAutoMove(goal=C.entry) -> PrCleaning(section=C) -> "
                                        "PrAutoMove(goal=D.entry) -> PrCleaning(section=D)"));
  REQUIRE(a.processes.size() == 2);
  CHECK_THAT(a.processes[0], Catch::EndsWith("X0 PrAutoMove(goal=A.entry) succeeded"));
  CHECK_THAT(a.processes[1], Catch::Contains("X1 PrCleaning(section=A) failed: stopped"));
}

TEST_CASE("run_task: a run without a task writes a valid map and report, a signal stops a task in order", "[app][run][shutdown]") {
  // Before, a run that never had a task drew the map from an empty vector of reachable cells
  // (a segfault: exit 139 and no report), and a refused task wrote nothing at all.
  const std::filesystem::path out = std::filesystem::temp_directory_path() / ("tripodal_app_empty_" + std::to_string(::getpid()));
  std::filesystem::remove_all(out);
  RunOptions o;
  o.robot = kSource / "configs/robots/psr2.yaml";
  o.world = kSource / "configs/worlds/workspace.yaml";
  o.seed = 2;
  o.out = out / "refused";
  o.task = "clean the kitchen now";
  const RunResult refused = run_task(o);
  CHECK(refused.state == "refused");
  CHECK_THAT(refused.reason, Catch::Contains("not understood"));
  CHECK(refused.reachable_cells == 0);
  CHECK(refused.sections.empty());
  CHECK(refused.base_at_rest);
  for (const char* f : {"map.png", "trajectory.csv", "report.json", "lifecycle.txt"}) CHECK(std::filesystem::exists(o.out / f));
  std::ifstream png(o.out / "map.png", std::ios::binary);
  std::string signature(8, '\0');
  png.read(signature.data(), 8);
  CHECK(signature == "\x89PNG\r\n\x1a\n");
  std::ifstream report_file(o.out / "report.json");
  const nlohmann::json report = nlohmann::json::parse(report_file);
  CHECK(report["state"] == "refused");
  CHECK(report["stopped_by"] == "");

  // A signal already received when the run starts its loop: the task is cancelled as interrupted,
  // the base commanded zero, the report names the signal.
  volatile std::sig_atomic_t stop = SIGTERM;
  o.stop = &stop;
  o.out = out / "interrupted";
  o.task = "clean the room 2111";
  const RunResult r = run_task(o);
  CHECK(r.state == "interrupted");
  CHECK(r.stopped_by == "interrupted by SIGTERM");
  CHECK_THAT(r.reason, Catch::Contains("interrupted by SIGTERM"));
  CHECK(r.base_at_rest);
  REQUIRE(r.base_command_at_end_rad_s.size() == 3);  // the PSR-2's three omni wheels
  for (const double w : r.base_command_at_end_rad_s) CHECK(w == 0.0);
  std::ifstream interrupted_file(o.out / "report.json");
  const nlohmann::json interrupted = nlohmann::json::parse(interrupted_file);
  CHECK(interrupted["stopped_by"] == "interrupted by SIGTERM");
  CHECK(interrupted["base_at_rest"] == true);
  std::filesystem::remove_all(out);
}

TEST_CASE("stop: after the threads, the base brakes to zero through its controller's limits", "[app][shutdown]") {
  // Before, the wheels were written zero at once beside the controller: the hardware held 0 while
  // the controller still said 0.5 m/s (limited_command, wheel_commands), and a tall robot could tip.
  MovingBase base;
  REQUIRE(base.controller.limited_command().vx_m_s == Approx(0.5));
  REQUIRE(base.wheels.commands()[0] == Approx(5.0));  // 0.5 m/s on 0.1 m wheels
  const Time from = base.clock.now();
  const std::size_t writes = base.wheels.writes();
  int periods = 0;
  CHECK(brake_through_controller(base.controller, base.clock, std::chrono::seconds(3), [&](Time) { ++periods; }));
  for (const double w : base.wheels.commands()) CHECK(w == 0.0);
  for (const double w : base.controller.wheel_commands()) CHECK(w == 0.0);
  CHECK(base.controller.limited_command().vx_m_s == 0.0);
  // 0.5 m/s at 2 m/s^2: 0.25 s, one write per 10 ms period, not one write of zeros.
  CHECK(to_seconds(base.clock.now() - from) == Approx(0.25).margin(0.011));
  CHECK(base.wheels.writes() - writes >= 25);
  CHECK(periods >= 25);
}

TEST_CASE("stop: a brake cut short by its limit says the base is not at rest", "[app][shutdown]") {
  MovingBase base;
  CHECK_FALSE(brake_through_controller(base.controller, base.clock, std::chrono::milliseconds(100)));
  CHECK(base.controller.limited_command().vx_m_s == Approx(0.3).margin(0.021));  // 0.5 - 2 * 0.1
  CHECK(base.wheels.commands()[0] > 0.0);
}
