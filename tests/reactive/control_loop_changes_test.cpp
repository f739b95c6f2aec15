// How the sequencing layer's changes reach a control loop: the changes of one supervision step
// held and applied together (hold_changes / release_changes, ChangeBatch), the feedback flowing
// back meanwhile, and the navigation data's path copied into the loop only when its path_id is new.
#include <catch2/catch.hpp>
#include <vector>

#include "tripodal/reactive/control_loop.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {

// What a behavior saw at its last step.
struct Seen {
  int steps = 0;
  std::uint32_t path_id = 0;
  std::size_t path_points = 0;
  Pose2D first_point;
  bool localized = false;
};

// Records what it sees and reports following the path it is given (0.1 m more each cycle); with
// end_after_cycles, reports the end of the path then and succeeds.
class BhRecordNavigation final : public CBehavior {
 public:
  explicit BhRecordNavigation(Seen& seen, int end_after_cycles = 0)
      : seen_(seen), end_after_(end_after_cycles) {}
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m{"BhRecordNavigation",
                                  Layer::reactive,
                                  ModuleKind::behavior,
                                  "records the navigation data",
                                  {"path"},
                                  {"behavior_command"},
                                  {}};
    return m;
  }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet&, const BehaviorContext&) override {}
  std::optional<Twist2D> on_step(const BehaviorContext& ctx) noexcept override {
    ++seen_.steps;
    seen_.path_id = ctx.navi->path_id;
    seen_.path_points = ctx.navi->path.size();
    seen_.first_point = ctx.navi->path.empty() ? Pose2D{} : ctx.navi->path.front();
    seen_.localized = ctx.navi->localized;
    ctx.feedback->path_id = ctx.navi->path_id;
    ctx.feedback->progress_m = 0.1 * static_cast<double>(steps());
    if (end_after_ > 0 && static_cast<int>(steps()) >= end_after_) {
      ctx.feedback->reached_end = true;
      succeed();
    }
    return Twist2D{};
  }

 private:
  Seen& seen_;
  int end_after_;
};

struct Loop {
  ResourceTable resources;
  std::unique_ptr<ControlLoop> loop;
  Time now{};
  explicit Loop(std::size_t max_path_points = 4096) {
    CoordinatorConfig cc;
    cc.inputs = {{"record", 10, 200ms}};
    ControlLoopOptions o;
    o.name = "motion";
    o.period = 10ms;
    o.max_path_points = max_path_points;
    loop = std::make_unique<ControlLoop>(o, resources, CBehaviorCoordinator(cc), nullptr);
  }
  const CycleReport& cycle() {
    const CycleReport& r = loop->step(now);
    now += loop->period();
    return r;
  }
};

NavigationData with_path(const std::vector<Pose2D>& path, std::uint32_t id) {
  NavigationData n;
  n.path = path;
  n.path_id = id;
  return n;
}

}  // namespace

TEST_CASE(
    "Changes made while held reach the loop together at release: a behavior never starts with the previous "
    "path",
    "[reactive][loop]") {
  Loop l;
  Seen seen;
  const std::vector<Pose2D> old_path{{0, 0, 0}, {1, 0, 0}};
  const std::vector<Pose2D> new_path{{5, 5, 0}, {6, 5, 0}, {7, 5, 0}};
  l.loop->set_navigation(with_path(old_path, 1));
  (void)l.cycle();

  l.loop->hold_changes();
  const BehaviorHandle h = l.loop->activate(std::make_unique<BhRecordNavigation>(seen), {}, "record");
  (void)l.cycle();  // the activation is held: the loop has not seen the new path either
  l.loop->set_navigation(with_path(new_path, 2));
  CHECK(l.cycle().active_behaviors == 0);
  CHECK(seen.steps == 0);
  CHECK(l.loop->deferred_applies() == 2);
  l.loop->release_changes();
  CHECK(l.cycle().active_behaviors == 1);
  CHECK(seen.steps == 1);
  CHECK(seen.path_id == 2);  // its first step sees the path planned with its activation
  CHECK(seen.path_points == 3);
  CHECK(seen.first_point.x_m == 5.0);
  CHECK(l.loop->status(h) == BehaviorStatus::running);

  // Nested batches: held until the outermost ends. The feedback keeps flowing meanwhile.
  {
    ControlLoop::ChangeBatch outer(*l.loop);
    {
      ControlLoop::ChangeBatch inner(*l.loop);
      CHECK(l.loop->deactivate(h));
      (void)l.cycle();
      CHECK(l.loop->navigation_feedback().path_id == 2);  // reported by the behavior's last cycle
    }
    CHECK(l.cycle().active_behaviors == 1);
    CHECK(seen.steps == 3);
  }
  CHECK(l.cycle().active_behaviors == 0);
  CHECK(seen.steps == 3);
  l.loop->release_changes();  // more releases than holds: ignored
  CHECK(l.loop->deferred_applies() == 4);
}

TEST_CASE("set_navigation copies the path into the loop only when path_id changes", "[reactive][loop]") {
  Loop l(4);
  Seen seen;
  l.loop->activate(std::make_unique<BhRecordNavigation>(seen), {}, "record");
  std::vector<Pose2D> path{{0, 0, 0}, {1, 0, 0}};
  CHECK(l.loop->set_navigation(with_path(path, 1)));
  (void)l.cycle();
  CHECK(seen.path_points == 2);

  // The publisher changes its storage and the other data, under the same id: the loop keeps its
  // copy of the path (the points a behavior took up stay valid), the rest is updated.
  path[0] = {9, 9, 0};
  path.push_back({2, 0, 0});
  NavigationData n = with_path(path, 1);
  n.localized = true;
  CHECK(l.loop->set_navigation(n));
  (void)l.cycle();
  CHECK(seen.path_points == 2);
  CHECK(seen.first_point.x_m == 0.0);
  CHECK(seen.localized);

  // A new id: copied, and independent of the publisher's storage afterwards.
  CHECK(l.loop->set_navigation(with_path(path, 2)));
  path.assign(1, Pose2D{-1, -1, 0});
  (void)l.cycle();
  CHECK(seen.path_id == 2);
  CHECK(seen.path_points == 3);
  CHECK(seen.first_point.x_m == 9.0);

  // No path (id 0) after a path: cleared.
  CHECK(l.loop->set_navigation(NavigationData{}));
  (void)l.cycle();
  CHECK(seen.path_id == 0);
  CHECK(seen.path_points == 0);

  // Longer than max_path_points: truncated, and said so.
  const std::vector<Pose2D> long_path(6, Pose2D{1, 1, 0});
  CHECK_FALSE(l.loop->set_navigation(with_path(long_path, 3)));
  (void)l.cycle();
  CHECK(seen.path_points == 4);
}

TEST_CASE("The report of a path followed to its end stays until the next report", "[reactive][loop]") {
  // The sequencing layer reads the feedback every few cycles of the loop: the end of a path, the
  // behavior's last report, must not be overwritten by the empty cycles after it.
  Loop l;
  Seen seen;
  const std::vector<Pose2D> path{{0, 0, 0}, {1, 0, 0}};
  l.loop->set_navigation(with_path(path, 7));
  l.loop->activate(std::make_unique<BhRecordNavigation>(seen, 3), {}, "record");
  (void)l.cycle();  // joins, reports progress 0.1
  (void)l.cycle();  // 0.2
  (void)l.cycle();  // 0.3 and the end of the path; handed over at the start of the next cycle
  CHECK(l.loop->navigation_feedback().progress_m == Approx(0.2));
  CHECK_FALSE(l.loop->navigation_feedback().reached_end);
  for (int k = 0; k < 10; ++k) (void)l.cycle();
  NavigationFeedback fb = l.loop->navigation_feedback();
  CHECK(fb.path_id == 7);
  CHECK(fb.reached_end);
  CHECK(fb.progress_m == Approx(0.3));
  // The next behavior's report replaces it.
  l.loop->set_navigation(with_path(path, 8));
  l.loop->activate(std::make_unique<BhRecordNavigation>(seen), {}, "record");
  (void)l.cycle();
  (void)l.cycle();
  (void)l.cycle();
  fb = l.loop->navigation_feedback();
  CHECK(fb.path_id == 8);
  CHECK_FALSE(fb.reached_end);
}
