#include "tripodal/navi/localizer.hpp"

#include <catch2/catch.hpp>

#include "tripodal/navi/section_splitter.hpp"

using namespace tripodal;
using namespace tripodal::navi;

namespace {

// The robot drives along x at 0.5 m/s.
class Straight final : public GroundTruthSource {
 public:
  std::optional<Pose2D> true_pose(Time now) const override {
    if (now < Time{}) return std::nullopt;
    return Pose2D{0.5 * to_seconds(now), 1.0, 0.0};
  }
};

Time at(double s) { return time_from_seconds(s); }

std::vector<ModuleEvent> run(CGroundTruthLocalizer& loc, double until_s, double dt_s = 0.1) {
  std::vector<ModuleEvent> events;
  for (double t = 0.0; t <= until_s + 1e-9; t += dt_s) loc.step(at(t), events);
  return events;
}

}  // namespace

TEST_CASE("CGroundTruthLocalizer: ok at start, lost during a fault, ok after global localization", "[navi][localizer]") {
  Straight truth;
  CGroundTruthLocalizer loc(&truth);
  loc.configure({{"faults", Value{std::string("2-4")}}, {"seed", Value{7.0}}});
  std::vector<ModuleEvent> ev = run(loc, 1.0);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].name == "localizer.ok");
  CHECK(ev[0].stamp == at(0));
  CHECK(loc.localized());
  CHECK(loc.position_error_m() < 0.1);
  ev.clear();
  for (double t = 1.1; t < 6.0; t += 0.1) loc.step(at(t), ev);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].name == "localizer.lost");
  CHECK(to_seconds(ev[0].stamp) == Approx(2.0).margin(0.11));
  CHECK_THAT(ev[0].message, Catch::Contains("disagrees"));
  CHECK_FALSE(loc.localized());
  CHECK(loc.position_error_m() == Approx(2.0).margin(0.1));
  // global localization fails inside the window, succeeds after it
  CHECK_FALSE(loc.relocalize(at(3.0)));
  REQUIRE(loc.relocalize(at(6.0)));
  ev.clear();
  loc.step(at(6.1), ev);
  REQUIRE(ev.size() == 1);
  CHECK(ev[0].name == "localizer.ok");
  NavigationData nd;
  loc.publish(nd);
  CHECK(nd.localized);
  CHECK(nd.map_from_base.x_m == Approx(3.05).margin(0.1));
  CHECK(nd.pose_stamp == at(6.1));
}

TEST_CASE("CGroundTruthLocalizer: recover_at_fault_end brings the estimate back by itself", "[navi][localizer]") {
  Straight truth;
  LocalizerOptions o;
  o.recover_at_fault_end = true;
  o.faults = {{at(1.0), at(2.0)}};
  CGroundTruthLocalizer loc(&truth, o);
  loc.configure({{"recover_at_fault_end", Value{true}}, {"faults", Value{std::string("1-2")}}});
  const std::vector<ModuleEvent> ev = run(loc, 3.0);
  REQUIRE(ev.size() == 3);
  CHECK(ev[0].name == "localizer.ok");
  CHECK(ev[1].name == "localizer.lost");
  CHECK(ev[2].name == "localizer.ok");
  CHECK(to_seconds(ev[2].stamp) == Approx(2.0).margin(0.11));
}

TEST_CASE("CGroundTruthLocalizer: the same seed gives the same estimates, another seed others", "[navi][localizer]") {
  Straight truth;
  const auto trace = [&](double seed) {
    CGroundTruthLocalizer loc(&truth);
    loc.configure({{"seed", Value{seed}}, {"faults", Value{std::string("0.5-0.8")}}});
    std::vector<Pose2D> poses;
    std::vector<ModuleEvent> ev;
    for (int i = 0; i < 20; ++i) {
      loc.step(at(0.1 * i), ev);
      poses.push_back(*loc.estimate());
    }
    return poses;
  };
  CHECK(trace(3) == trace(3));
  CHECK(trace(3) != trace(4));
}

TEST_CASE("CGroundTruthLocalizer: noise beyond the threshold reads as lost, no truth, no events", "[navi][localizer]") {
  Straight truth;
  CGroundTruthLocalizer noisy(&truth);
  noisy.configure({{"noise_xy_m", Value{5.0}}});
  std::vector<ModuleEvent> ev = run(noisy, 2.0);
  bool lost = false;
  for (const ModuleEvent& e : ev) lost = lost || e.name == "localizer.lost";
  CHECK(lost);
  CGroundTruthLocalizer blind(nullptr);
  blind.configure();
  CHECK(run(blind, 1.0).empty());
  CHECK_FALSE(blind.estimate().has_value());
  CHECK_FALSE(blind.relocalize(at(0)));
  // before configure() a step does nothing
  CGroundTruthLocalizer unconfigured(&truth);
  CHECK(run(unconfigured, 1.0).empty());
}

TEST_CASE("CGroundTruthLocalizer: bad parameters and fault schedules are reported", "[navi][localizer][errors]") {
  CGroundTruthLocalizer loc;
  CHECK_THROWS_WITH(loc.configure({{"noise_xy_m", Value{-1.0}}}, SourceLocation{"net.xml", 12, 3}),
                    Catch::Contains("net.xml:12:3") && Catch::Contains("noise_xy_m"));
  CHECK_THROWS_WITH(loc.configure({{"no_such", Value{1.0}}}), Catch::Contains("no_such"));
  CHECK_THROWS_WITH(parse_fault_schedule("10-20; 30-25", {"world.yaml", 4, 11}),
                    Catch::Contains("world.yaml:4:11: error: bad localization fault '30-25'"));
  CHECK_THROWS_WITH(parse_fault_schedule("abc"), Catch::Contains("expected START-END in seconds"));
  CHECK(parse_fault_schedule(" 10-20 ; 35.5-40;") ==
        std::vector<LocalizationFault>{{at(10), at(20)}, {at(35.5), at(40)}});
  CHECK(parse_fault_schedule("").empty());
}

TEST_CASE("Navigation modules: every one is created by name and configured with defaults", "[navi][modules]") {
  ModuleRegistry reg("module type");
  register_navigation_modules(reg);
  REQUIRE(reg.names() == std::vector<std::string>{"CoveragePlanner", "GridMaps", "GroundTruthLocalizer", "MapBuilder",
                                                  "PathPlanner", "ScanMatchingLocalizer", "SectionSplitter"});
  for (const std::string& name : reg.names()) {
    std::unique_ptr<CModule> m = reg.create(name);
    REQUIRE(m != nullptr);
    CHECK(m->type_name() == name);
    CHECK(m->manifest().layer == Layer::sequencing);
    CHECK(m->manifest().kind == ModuleKind::navigation);
    CHECK(&reg.manifest(name) != &m->manifest());  // the registry keeps its own copy...
    CHECK(reg.manifest(name).inputs == m->manifest().inputs);  // ...of the same manifest
    CHECK_FALSE(m->configured());
    m->configure();
    CHECK(m->configured());
  }
  CHECK_THROWS_WITH(reg.create("GroundTruthLocaliser"), Catch::Contains("unknown module type 'GroundTruthLocaliser'") &&
                                                            Catch::Contains("did you mean 'GroundTruthLocalizer'?"));
  CHECK_THROWS_WITH(reg.add<CGroundTruthLocalizer>(), Catch::Contains("already registered"));
}

TEST_CASE("CSectionSplitter: configured from parameters", "[navi][modules]") {
  CSectionSplitter s;
  s.configure({{"min_gap_m", Value{0.5}}, {"min_section_height_m", Value{1.0}}});
  CHECK(s.options().min_gap_m == 0.5);
  CHECK(s.options().min_section_height_m == 1.0);
  CHECK(s.options().min_section_area_m2 == 2.0);
  CHECK_THROWS_WITH(s.configure({{"min_gap_m", Value{std::string("wide")}}}), Catch::Contains("min_gap_m"));
}
