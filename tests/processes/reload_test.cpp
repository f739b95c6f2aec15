// CProcessSupervisor::reload: an edited net replaces a running process's net at a quiet marking,
// carrying the marking over by place id; refused, with located diagnostics and nothing changed,
// when the net does not load, a marked place is missing, or the run is not quiet.
#include <catch2/catch.hpp>

#include <regex>

#include "doubles.hpp"
#include "tripodal/core/net_loader.hpp"
#include "tripodal/processes/process_supervisor.hpp"

using namespace tripodal;
using namespace tripodal::test;

namespace {

struct Reloads final : SupervisorObserver {
  std::vector<std::string> lines;
  CProcessSupervisor* reenter = nullptr;  // when set, on_firing tries a reload from inside the step
  std::string reenter_text;
  std::optional<ReloadResult> inside;
  void on_net_reloaded(std::string_view run, const CProcess& p, std::string_view marking, Time now) override {
    lines.push_back(FakeBehaviors::stamp(now) + " reload " + std::string(run) + " " + p.name() + " " + std::string(marking));
  }
  void on_run_finished(const ProcessResult& r) override {
    lines.push_back(FakeBehaviors::stamp(r.finished) + " end " + r.run + (r.success ? " success " + r.place : " fault: " + r.message));
  }
  void on_firing(std::string_view run, const PetriNet&, const Firing&) override {
    if (reenter != nullptr && !inside) inside = reenter->reload(run, reenter_text, "inside.xml");
  }
};

struct Rig {
  SimClock clock;
  FakeBehaviors behaviors;
  std::unique_ptr<CProcess> process;
  CProcessSupervisor supervisor{behaviors, clock};
  Reloads seen;

  Rig() {
    behaviors.add("BhCleaning", 10.0);
    behaviors.add("BhAutoMove", 3.0);
    ProcessDefinition d;
    d.name = "PrCleaning";
    d.net = pr_cleaning(5.0);
    process = std::make_unique<CProcess>(std::move(d));
    supervisor.add_observer(seen);
    const BoundParameters b = process->bind({{"section", "A", {}}});
    REQUIRE(b.ok);
    REQUIRE(supervisor.start("X0", *process, b.values));
    supervisor.step();  // t = 0: P0 -> t0 -> P1, BhCleaning runs; P3 (localization normal) stays
  }

  void run_to(double end_s, const std::function<void(double)>& at = {}) {
    const Duration dt = from_seconds(0.1);
    while (to_seconds(clock.now()) < end_s - 1e-9) {
      clock.advance(dt);
      behaviors.advance(clock.now(), dt);
      if (at) at(to_seconds(clock.now()));
      supervisor.step();
    }
  }

  [[nodiscard]] std::vector<std::string> marked() const {
    std::vector<std::string> out;
    const Engine* e = supervisor.engine("X0");
    REQUIRE(e != nullptr);
    for (PlaceIndex p = 0; p < e->marking().size(); ++p) {
      if (e->marking()[p] > 0) out.push_back(e->net().place(p).id + "=" + std::to_string(e->marking()[p]));
    }
    return out;
  }
};

std::string xml(const PetriNet& net) { return net_to_string(net, NetFormat::native_xml); }

// The running net with an extra place and transition: an operator's "hold" event parks the
// cleaning (P9), "resume" brings it back.
PetriNet edited_with_hold() {
  PetriNet net = pr_cleaning(5.0);
  net.add_place(place("P9", 0, "Held by the operator"));
  net.add_transition(transition("t9", "operator.hold"));
  net.add_transition(transition("t10", "operator.resume"));
  arcs(net, {{"P1", "t9"}, {"t9", "P9"}, {"P9", "t10"}, {"t10", "P1"}});
  return net;
}

}  // namespace

TEST_CASE("An accepted reload carries the marking over by place id and keeps the running behavior", "[processes][reload]") {
  Rig rig;
  rig.run_to(3.0);
  REQUIRE(rig.marked() == std::vector<std::string>{"P1=1", "P3=1"});
  REQUIRE(rig.supervisor.why_not_quiet("X0").empty());
  const std::size_t log_before = rig.behaviors.log.size();

  const ReloadResult r = rig.supervisor.reload("X0", xml(edited_with_hold()), "PrCleaning-edited.xml");
  INFO(r.diagnostics.str());
  REQUIRE(r.accepted);
  CHECK_FALSE(r.diagnostics.has_errors());
  CHECK(r.marking == "P1=1, P3=1");
  // The new net's initial marking (P0) does not count: the instance goes on where it was.
  CHECK(rig.marked() == std::vector<std::string>{"P1=1", "P3=1"});
  CHECK(rig.supervisor.engine("X0")->net().find_place("P9").has_value());
  CHECK(rig.supervisor.process("X0")->net().where.file.str() == "PrCleaning-edited.xml");
  CHECK(rig.supervisor.process("X0")->name() == "PrCleaning");
  // Same place, same binding: BhCleaning was neither stopped nor restarted (3 s of its 10 s done).
  CHECK(rig.behaviors.log.size() == log_before);
  CHECK(rig.behaviors.active("BhCleaning"));
  CHECK(rig.seen.lines == std::vector<std::string>{"t=3.000 reload X0 PrCleaning P1=1, P3=1"});

  // The edited net runs: its new transition takes the operator's event, and the behavior's
  // completion still ends the process when it is back on P1.
  rig.supervisor.post_event("operator.hold");
  rig.run_to(3.1);
  CHECK(rig.marked() == std::vector<std::string>{"P3=1", "P9=1"});
  CHECK_FALSE(rig.behaviors.active("BhCleaning"));
  rig.supervisor.post_event("operator.resume");
  rig.run_to(20.0);
  REQUIRE_FALSE(rig.seen.lines.empty());
  CHECK(rig.seen.lines.back() == "t=13.200 end X0 success P5");
}

TEST_CASE("A reload that changes a marked place's binding restarts that behavior with the new parameters", "[processes][reload]") {
  Rig rig;
  rig.run_to(2.0);
  PetriNet net = pr_cleaning(5.0);
  net.place(*net.find_place("P1")).behavior->params[1].value = "zigzag";  // pattern
  const ReloadResult r = rig.supervisor.reload("X0", xml(net), "zigzag.xml");
  INFO(r.diagnostics.str());
  REQUIRE(r.accepted);
  REQUIRE(rig.behaviors.log.size() >= 2);
  CHECK(rig.behaviors.log[rig.behaviors.log.size() - 2] == "t=2.000 deactivate BhCleaning");
  CHECK(rig.behaviors.log.back() == "t=2.000 activate BhCleaning(pattern=zigzag, section=A)");
  CHECK(rig.supervisor.active_behaviors() == std::vector<std::string>{"BhCleaning"});
}

TEST_CASE("A reload of a net that does not load is refused with the loader's located diagnostics", "[processes][reload]") {
  Rig rig;
  rig.run_to(1.0);
  const Engine* before = rig.supervisor.engine("X0");

  SECTION("malformed XML") {
    std::string text = xml(pr_cleaning(5.0));
    const auto at = text.find("</place>");
    REQUIRE(at != std::string::npos);
    text.erase(at, 8);  // a place left open
    const ReloadResult r = rig.supervisor.reload("X0", text, "edited.xml");
    CHECK_FALSE(r.accepted);
    CHECK_FALSE(r.not_quiet);
    REQUIRE(r.diagnostics.has_errors());
    CHECK(std::regex_search(r.diagnostics.str(), std::regex(R"(edited\.xml:\d+:\d+: error: )")));
  }
  SECTION("a behavior the robot does not have") {
    PetriNet net = pr_cleaning(5.0);
    net.place(*net.find_place("P1")).behavior->behavior = "BhClening";
    const ReloadResult r = rig.supervisor.reload("X0", xml(net), "typo.xml");
    CHECK_FALSE(r.accepted);
    CHECK(std::regex_search(r.diagnostics.str(), std::regex(R"(typo\.xml:\d+:\d+: error: .*BhClening)")));
  }
  SECTION("a run that does not exist") {
    const ReloadResult r = rig.supervisor.reload("X7", xml(pr_cleaning(5.0)), "edited.xml");
    CHECK_FALSE(r.accepted);
    CHECK(r.diagnostics.str().find("no process is running as 'X7' (running: X0)") != std::string::npos);
  }
  // Nothing changed.
  CHECK(rig.supervisor.engine("X0") == before);
  CHECK(rig.marked() == std::vector<std::string>{"P1=1", "P3=1"});
  CHECK(rig.seen.lines.empty());
}

TEST_CASE("A reload is refused when a marked place is missing from the new net", "[processes][reload]") {
  Rig rig;
  rig.run_to(1.0);
  // The localization state P3 renamed: its token would have nowhere to go.
  std::string text = xml(pr_cleaning(5.0));
  text = std::regex_replace(text, std::regex("\"P3\""), "\"P3b\"");
  const ReloadResult r = rig.supervisor.reload("X0", text, "renamed.xml");
  CHECK_FALSE(r.accepted);
  CHECK_FALSE(r.not_quiet);
  CHECK(r.diagnostics.str().find("error: place P3 holds 1 token in the running net (run X0) but is not in the new net") !=
        std::string::npos);
  CHECK(std::regex_search(r.diagnostics.str(), std::regex(R"(renamed\.xml:\d+:\d+: error: place P3)")));
  CHECK(rig.marked() == std::vector<std::string>{"P1=1", "P3=1"});
  CHECK(rig.behaviors.active("BhCleaning"));
}

TEST_CASE("A reload is refused while the run is not quiet and accepted once it is", "[processes][reload]") {
  Rig rig;
  SECTION("a delayed transition timing its delay") {
    rig.run_to(4.0, [&](double t) {
      if (t > 3.95) rig.supervisor.post_event("localizer.lost");  // P3 -> P4: t5 starts its 5 s
    });
    REQUIRE(rig.marked() == std::vector<std::string>{"P1=1", "P4=1"});
    const std::vector<std::string> why = rig.supervisor.why_not_quiet("X0");
    REQUIRE(why.size() == 1);
    CHECK(why[0] == "transition t5 is timing its delay of 5 s: a new net would start it again");
    const ReloadResult refused = rig.supervisor.reload("X0", xml(edited_with_hold()), "edited.xml");
    CHECK_FALSE(refused.accepted);
    CHECK(refused.not_quiet);
    CHECK(refused.diagnostics.str().find("edited.xml") != std::string::npos);
    CHECK(refused.diagnostics.str().find("run X0 is not at a quiet marking: transition t5 is timing its delay") != std::string::npos);
    CHECK_FALSE(rig.supervisor.engine("X0")->net().find_place("P9").has_value());

    rig.supervisor.post_event("localizer.ok");  // back to P3: t5 stops timing
    rig.run_to(4.5);
    CHECK(rig.supervisor.why_not_quiet("X0").empty());
    const ReloadResult accepted = rig.supervisor.reload("X0", xml(edited_with_hold()), "edited.xml");
    INFO(accepted.diagnostics.str());
    CHECK(accepted.accepted);
    CHECK(accepted.marking == "P1=1, P3=1");
  }
  SECTION("inside a step: a firing in progress") {
    rig.seen.reenter = &rig.supervisor;
    rig.seen.reenter_text = xml(edited_with_hold());
    rig.supervisor.post_event("localizer.lost");
    rig.run_to(0.1);
    REQUIRE(rig.seen.inside.has_value());
    CHECK_FALSE(rig.seen.inside->accepted);
    CHECK(rig.seen.inside->not_quiet);
    CHECK(rig.seen.inside->diagnostics.str().find("inside a step (a firing in progress)") != std::string::npos);
    CHECK_FALSE(rig.supervisor.engine("X0")->net().find_place("P9").has_value());
  }
  SECTION("a carried marking that is not quiet in the new net") {
    PetriNet net = pr_cleaning(5.0);
    net.add_place(place("P9"));
    net.add_transition(transition("t9"));  // immediate, takes the cleaning's token at once
    arcs(net, {{"P1", "t9"}, {"t9", "P9"}});
    const ReloadResult r = rig.supervisor.reload("X0", xml(net), "eager.xml");
    CHECK_FALSE(r.accepted);
    CHECK(r.diagnostics.str().find("transition t9 is enabled by the carried marking (P1=1, P3=1) and would fire at once") !=
          std::string::npos);
  }
}
