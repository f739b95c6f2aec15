// The guide demo (tools/tripodal/visit.hpp): the visit file with every error located, and Jinny's
// visit of the exhibit hall end to end among walking visitors: no collision and the dialogue's
// expected outcomes, for five seeds; a seed repeats its run.
#include <catch2/catch.hpp>

#include <algorithm>

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <string>

#include <spdlog/spdlog.h>

#include "tripodal/hri/speech.hpp"
#include "visit.hpp"

using namespace tripodal;
using namespace tripodal::app;
using Catch::Matchers::Contains;

namespace {

const std::filesystem::path kConfigs = TRIPODAL_SOURCE_DIR "/configs";

std::string error_of(const std::string& text) {
  try {
    (void)parse_visit(text, "visit.yaml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return {};
}

VisitResult visit(std::uint64_t seed, bool voice, const std::filesystem::path& out = {}, std::optional<double> give_way_m = {}) {
  spdlog::set_level(spdlog::level::warn);  // the planner's life cycle: in the result, not the test log
  VisitOptions o;
  o.out = out;
  o.robot = kConfigs / "robots/jinny.yaml";
  o.world = kConfigs / "worlds/exhibit_hall.yaml";
  o.visit = kConfigs / "visits/exhibit_hall.yaml";
  o.seed = seed;
  o.voice = voice;
  o.visitors_give_way_m = give_way_m;
  return run_visit(o);
}

VisitResult check_visit(std::uint64_t seed, bool voice, const std::filesystem::path& out = {}, std::optional<double> give_way_m = {}) {
  const VisitResult r = visit(seed, voice, out, give_way_m);
  INFO("seed " << seed << ": " << r.json());
  CHECK(r.completed);
  CHECK(r.collisions == 0);
  CHECK(r.visitor_collisions == 0);
  CHECK(r.mismatches == 0);
  REQUIRE(r.exchanges.size() == 10);
  // Introduces itself, answers the weather, guides to node 1 and explains the robot there.
  CHECK(r.exchanges[2].entry == "introduce");
  CHECK(r.exchanges[3].entry == "weather");
  CHECK(r.exchanges[4].task == "guide");
  CHECK(r.exchanges[4].task_end == "succeeded");
  // The guest followed Jinny across the hall: at node 1 it stands behind it (gap 0.8 m + bodies).
  CHECK(r.exchanges[4].follower_distance_m > 1.0);
  CHECK(r.exchanges[4].follower_distance_m < 1.8);
  CHECK(r.exchanges[5].task == "explain_here");
  CHECK(r.exchanges[5].task_end == "succeeded");
  CHECK(r.exchanges[6].kind == "button");
  CHECK_THAT(r.exchanges[7].reply, Contains("there is no node 7 here. I can guide you to node 0, 1 or 2"));
  CHECK(r.distance_m > 15.0);
  CHECK(r.min_visitor_clearance_m > 0.0);
  return r;
}

}  // namespace

TEST_CASE("visit file: typed, spoken and pressed steps with times and expectations", "[app][visit]") {
  const Visit v = parse_visit(R"(visit:
  name: short
  max_duration_s: 100
  steps:
    - type: "Hello"
      at_s: 2
      expect: {outcome: answered, entry: greeting}
    - say: "Guide me to node 1"
      after_s: 0.5
      expect: {task: guide, task_end: succeeded}
    - press: help
)",
                              "v.yaml");
  CHECK(v.name == "short");
  CHECK(v.max_duration_s == 100.0);
  REQUIRE(v.steps.size() == 3);
  CHECK(v.steps[0].kind == VisitStep::Kind::typed);
  CHECK(v.steps[0].at_s == 2.0);
  CHECK(v.steps[0].expect_entry == "greeting");
  CHECK(v.steps[1].kind == VisitStep::Kind::spoken);
  CHECK(v.steps[1].after_s == 0.5);
  CHECK(v.steps[1].expect_task_end == "succeeded");
  CHECK(v.steps[2].kind == VisitStep::Kind::button);
  CHECK(v.steps[2].text == "help");
  CHECK(v.steps[2].where.line == 11);
  CHECK(load_visit(kConfigs / "visits/exhibit_hall.yaml").steps.size() == 10);
}

TEST_CASE("visit file: every mistake located, all in one report", "[app][visit][errors]") {
  const std::string e = error_of(R"(visit:
  name: broken
  max_duration_s: -5
  steps:
    - type: "Hello"
      say: "Hello"
    - press: ""
    - type: "Hi"
      at_s: -1
      expect: {outcome: happy, mood: good}
    - wave: true
)");
  CHECK_THAT(e, Contains("visit.yaml:3:19: error: visit.max_duration_s: expected a number > 0"));
  CHECK_THAT(e, Contains("visit.yaml:5:7: error: a visit step needs exactly one of type:"));
  CHECK_THAT(e, Contains("visit.yaml:7:14:"));
  CHECK_THAT(e, Contains("visit.yaml:9:13: error: at_s: expected a number >= 0"));
  CHECK_THAT(e, Contains("visit.yaml:10:25: error: expect.outcome: expected one of answered, task_started"));
  CHECK_THAT(e, Contains("visit.yaml:10:32: error: unknown key 'mood' in a step's expect"));
  CHECK_THAT(e, Contains("visit.yaml:11:7: error: unknown key 'wave' in a visit step"));
  CHECK_THAT(error_of("visit: {name: x, steps: []}\n"), Contains("visit.yaml:1:25: error: visit.steps is empty"));
  CHECK_THAT(error_of("tour: {}\n"), Contains("visit.yaml:1:1: error: unknown key 'tour' in the visit file"));
  CHECK_THAT(error_of("visit: [\n"), Contains("visit.yaml:"));
}

// One test case per seed keeps each under a few seconds (Release); the first hears its spoken
// requests through espeak-ng and pocketsphinx when the build has voice.
TEST_CASE("guide visit, seed 1: no collision, the dialogue as expected", "[app][visit][e2e]") {
  const std::filesystem::path out = std::filesystem::temp_directory_path() / ("tripodal_guide_" + std::to_string(::getpid()));
  check_visit(1, true, out);
  CHECK(std::filesystem::is_regular_file(out / "dialogue.txt"));
  CHECK(std::filesystem::is_regular_file(out / "report.json"));
  // The answers' audio: the introduction is a few seconds of speech when the build has voice.
  if (voice_available()) {
    const AudioClip intro = read_wav(out / "audio/answer_03.wav");
    CHECK(intro.duration_s() > 3.0);
  } else {
    CHECK_FALSE(std::filesystem::exists(out / "audio/answer_01.wav"));
  }
  std::filesystem::remove_all(out);
}
TEST_CASE("guide visit, seed 2: no collision, the dialogue as expected", "[app][visit][e2e]") { check_visit(2, false); }
TEST_CASE("guide visit, seed 3: no collision, the dialogue as expected", "[app][visit][e2e]") { check_visit(3, false); }
TEST_CASE("guide visit, seed 4: no collision, the dialogue as expected", "[app][visit][e2e]") { check_visit(4, false); }
TEST_CASE("guide visit, seed 5: no collision, the dialogue as expected", "[app][visit][e2e]") { check_visit(5, false); }

// Walkers that do not give way (give_way_m 0: they stop only at contact). With the safety behavior
// (BhAutoMove told when it holds the robot, the back-off in the recovery of "path blocked") seeds 1,
// 2, 3 and 5 go as the visit expects with no collision; seed 5 is the one where a walker stands
// against Jinny and the back-off lets him pass. Seed 4 ends with no collision but one exchange short
// (the robot's pose lost in a crowd: docs/guide.md, "Not there").
TEST_CASE("guide visit among walkers that do not give way, seed 1: no collision", "[app][visit][e2e]") { check_visit(1, false, {}, 0.0); }
TEST_CASE("guide visit among walkers that do not give way, seed 2: no collision", "[app][visit][e2e]") { check_visit(2, false, {}, 0.0); }
TEST_CASE("guide visit among walkers that do not give way, seed 3: no collision", "[app][visit][e2e]") { check_visit(3, false, {}, 0.0); }
TEST_CASE("guide visit among walkers that do not give way, seed 5: a walker against Jinny, backed off, no collision",
          "[app][visit][e2e]") {
  // The recovery of "path blocked" backed Jinny off, then waited, then PrAutoMove reached node 0.
  const VisitResult r = check_visit(5, false, {}, 0.0);
  const auto ran = [&](std::string_view what) {
    return std::any_of(r.processes.begin(), r.processes.end(), [&](const std::string& p) { return p.find(what) != std::string::npos; });
  };
  CHECK(ran("PrAutoMove(goal=node0) failed"));
  CHECK(ran("PrBackOff() succeeded"));
  CHECK(ran("PrWait() succeeded"));
  CHECK(ran("PrAutoMove(goal=node0) succeeded"));
}

TEST_CASE("guide visit: a seed repeats its run, and visitors walk differently with another", "[app][visit][e2e]") {
  const VisitResult a = visit(6, false), b = visit(6, false);
  CHECK(a.json() == b.json());
  const VisitResult c = visit(7, false);
  CHECK(c.duration_s != a.duration_s);
}
