// The trace test of BhApproach (docs/behavior-tutorial.md): a real laser log, the behavior stepped
// on the simulated clock, assertions on its commands and outcome over time.
#define CATCH_CONFIG_MAIN
#include "bh_approach.hpp"

#include <catch2/catch.hpp>

#include "tripodal/behaviors/builtin_behaviors.hpp"
#include "tripodal/testing/behavior_harness.hpp"
#include "tripodal/trace/carmen_import.hpp"
#include "tripodal/trace/trace_writer.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

// The CARMEN excerpt of the Intel Research Lab log, imported into tripodal's trace format.
std::filesystem::path excerpt_trace() {
  const auto out = std::filesystem::temp_directory_path() / "bh_approach_intel_excerpt.trp";
  trace::TraceWriter writer(out);
  (void)trace::import_carmen_log(EXCERPT_LOG, writer);
  writer.close();
  return out;
}

}  // namespace

TEST_CASE("BhApproach stops short of the first wall of the Intel excerpt") {
  testing::BehaviorHarness harness;
  harness.load_trace(excerpt_trace());
  harness.attach(std::make_unique<example::BhApproach>(), {{"stop_distance_m", Value{0.8}}});
  const testing::RunLog& run = harness.run(std::nullopt, /*stop_when_done=*/true);

  CHECK(run.succeeds_before("BhApproach", Time{40s}));
  CHECK(run.never_fails("BhApproach"));
  CHECK(run.command_never_exceeds({.max_vx_m_s = 0.4, .max_vy_m_s = 0.0, .max_wz_rad_s = 0.0}));
  CHECK(run.never_drives_toward_obstacle_closer_than(0.8));
}

TEST_CASE("BhApproach slows down before it stops") {
  testing::BehaviorHarness harness;
  harness.load_trace(excerpt_trace());
  // Slowing starts 2 m short: the first scan (1.78 m ahead) already slows it down.
  harness.attach(std::make_unique<example::BhApproach>(), {{"slow_distance_m", Value{2.0}}, {"stop_distance_m", Value{0.7}}});
  const testing::RunLog& run = harness.run(std::nullopt, true);
  bool slowed = false;
  for (const auto& step : run.steps()) slowed |= step.command.vx_m_s > 0.0 && step.command.vx_m_s < 0.4;
  CHECK(slowed);
  // The helpers fail when the behavior breaks a promise: here a speed limit below its cruise speed.
  CHECK_FALSE(run.command_never_exceeds({.max_vx_m_s = 0.3}));
}

TEST_CASE("BhApproach under the safety behavior BhAvoidObstacle, as the reactive layer runs them") {
  testing::BehaviorHarness harness;
  harness.load_trace(excerpt_trace());
  harness.attach(std::make_unique<example::BhApproach>(), {}, {.priority = 1});
  harness.attach(std::make_unique<BhAvoidObstacle>(), {{"stop_distance_m", Value{0.7}}, {"slow_distance_m", Value{1.5}}},
                 {.priority = 100, .role = InputRole::safety});
  const testing::RunLog& run = harness.run(std::nullopt, true);
  CHECK(run.succeeds_before("BhApproach", Time{40s}));
  CHECK(run.never_drives_toward_obstacle_closer_than(0.7));
}
