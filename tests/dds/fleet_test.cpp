// The fleet planner (tripodal/dds/fleet.hpp): the balanced assignment, the follow-up of the robots'
// events, the reassignment of a silent robot's units and the one result, on a SimClock without DDS;
// then DdsFleet with stand-in robots on loopback DDS (a robot that leaves is a silent robot).
#include "tripodal/dds/fleet.hpp"

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <map>
#include <mutex>
#include <optional>
#include <thread>

#include "dds_test_support.hpp"
#include "tripodal/dds/endpoint.hpp"

namespace tripodal::dds {
namespace {

using namespace std::chrono_literals;

std::vector<FleetRobot> robots_at_origin(int n) {
  std::vector<FleetRobot> r;
  for (int k = 1; k <= n; ++k) r.push_back({"robot" + std::to_string(k), 0.0, 0.0});
  return r;
}

FleetUnit unit(const std::string& name, double area, double x = 0.0, double y = 0.0) {
  return {name, "clean the section " + name, area, x, y};
}

double load(const std::vector<std::size_t>& mine, const std::vector<FleetUnit>& units) {
  double a = 0.0;
  for (const std::size_t u : mine) a += units[u].area_m2;
  return a;
}

TEST_CASE("fleet: four sections of similar area go one to each of four robots") {
  const std::vector<FleetUnit> units{unit("A", 75), unit("B", 80), unit("C", 70), unit("D", 79)};
  const auto plan = assign_units(units, robots_at_origin(4));
  REQUIRE(plan.size() == 4);
  for (const auto& mine : plan) CHECK(mine.size() == 1);
  CHECK(plan[0] == std::vector<std::size_t>{1});  // largest first, to the first of the idle robots
  CHECK(plan[1] == std::vector<std::size_t>{3});
  CHECK(plan[2] == std::vector<std::size_t>{0});
  CHECK(plan[3] == std::vector<std::size_t>{2});
}

TEST_CASE("fleet: the assignment balances the area, not the count") {
  const std::vector<FleetUnit> units{unit("a", 10), unit("b", 10), unit("c", 40), unit("d", 10), unit("e", 10)};
  const auto plan = assign_units(units, robots_at_origin(2));
  CHECK(plan[0] == std::vector<std::size_t>{2});
  CHECK(plan[1].size() == 4);
  CHECK(load(plan[0], units) == 40.0);
  CHECK(load(plan[1], units) == 40.0);
}

TEST_CASE("fleet: on equal loads the nearest robot takes the unit") {
  const std::vector<FleetRobot> robots{{"west", 0.0, 0.0}, {"east", 10.0, 0.0}};
  const std::vector<FleetUnit> units{unit("near_east", 5, 9.0, 0.0), unit("near_west", 5, 1.0, 0.0)};
  const auto plan = assign_units(units, robots);
  CHECK(plan[0] == std::vector<std::size_t>{1});
  CHECK(plan[1] == std::vector<std::size_t>{0});
}

TEST_CASE("fleet: robots that are not eligible get nothing, and bad input is refused") {
  const std::vector<FleetUnit> units{unit("A", 1), unit("B", 1), unit("C", 1)};
  const bool eligible[] = {false, true, true};
  const auto plan = assign_units(units, robots_at_origin(3), eligible);
  CHECK(plan[0].empty());
  CHECK(plan[1].size() + plan[2].size() == 3);
  CHECK_THROWS_WITH(assign_units(units, {}), Catch::Contains("no robots"));
  const std::vector<FleetUnit> flat{unit("A", 1), unit("Z", 0)};
  CHECK_THROWS_WITH(assign_units(flat, robots_at_origin(1)), Catch::Contains("unit 'Z' has area 0.0 m2; expected > 0"));
  const bool none[] = {false};
  CHECK_THROWS_WITH(assign_units(units, robots_at_origin(1), none), Catch::Contains("no eligible robot"));
  SimClock clock;
  CHECK_THROWS_WITH(FleetPlanner(robots_at_origin(2), {}, clock), Catch::Contains("no units"));
  CHECK_THROWS_WITH(FleetPlanner(robots_at_origin(2), {unit("A", 1), unit("A", 2)}, clock), Catch::Contains("unit 'A' is listed twice"));
}

// Plays the robots' side: answers a start like RobotBridge does (accepted, then the task's life cycle).
void accept(FleetPlanner& p, const FleetCommand& c) {
  p.robot_event(c.robot, "command_accepted", "task_command/" + std::to_string(c.id), "start: understood");
  p.robot_event(c.robot, "task_started", "planner", c.task + " (plan ...)");
}
void succeed(FleetPlanner& p, const std::string& robot, const std::string& task) { p.robot_event(robot, "task_succeeded", "planner", task); }

TEST_CASE("fleet: a silent robot's unit in hand and its queue go to the others, and the work is done") {
  SimClock clock;
  // A 100 to robot1; B 60 to robot2; C 50 to robot3; D 40 to robot3 (least load, 50).
  FleetPlanner p(robots_at_origin(3), {unit("A", 100), unit("B", 60), unit("C", 50), unit("D", 40)}, clock);
  CHECK(p.queue_of("robot3") == std::vector<std::string>{"C", "D"});
  CHECK(p.poll().empty());  // nobody on DDS yet
  for (const char* r : {"robot1", "robot2", "robot3"}) p.robot_ready(r);
  std::vector<FleetCommand> cmds = p.poll();
  REQUIRE(cmds.size() == 3);
  std::map<std::string, FleetCommand> by;
  for (const FleetCommand& c : cmds) {
    CHECK(c.command == "start");
    by[c.robot] = c;
    accept(p, c);
  }
  CHECK(by["robot1"].unit == "A");
  CHECK(by["robot3"].task == "clean the section C");
  CHECK(p.poll().empty());  // everybody busy, every command answered

  clock.advance(10s);
  p.robot_silent("robot3", "liveliness lost");
  CHECK_FALSE(p.alive("robot3"));
  CHECK(p.queue_of("robot3").empty());
  // C (50) to the least loaded, robot2 (60 < 100); then D (40): robot1 100 < robot2 110.
  CHECK(p.queue_of("robot2") == std::vector<std::string>{"B", "C"});
  CHECK(p.queue_of("robot1") == std::vector<std::string>{"A", "D"});
  p.robot_silent("robot3", "again");  // once only

  clock.advance(5s);
  succeed(p, "robot2", "clean the section B");
  cmds = p.poll();
  REQUIRE(cmds.size() == 1);
  CHECK(cmds[0].robot == "robot2");
  CHECK(cmds[0].unit == "C");
  CHECK(cmds[0].id > by["robot3"].id);
  accept(p, cmds[0]);
  succeed(p, "robot1", "clean the section A");
  cmds = p.poll();
  REQUIRE(cmds.size() == 1);
  CHECK(cmds[0].unit == "D");
  accept(p, cmds[0]);
  clock.advance(5s);
  CHECK_FALSE(p.finished());
  succeed(p, "robot2", "clean the section C");
  succeed(p, "robot1", "clean the section D");
  CHECK(p.finished());

  const FleetResult r = p.result();
  CHECK(r.succeeded);
  CHECK(r.done() == 4);
  CHECK(r.duration_s == 20.0);
  REQUIRE(r.reassignments.size() == 2);
  CHECK(r.reassignments[0].unit == "C");
  CHECK(r.reassignments[0].from == "robot3");
  CHECK(r.reassignments[0].to == "robot2");
  CHECK(r.reassignments[0].at_s == 10.0);
  CHECK(r.reassignments[0].reason == "robot3 went silent (liveliness lost)");
  CHECK(r.units[2].robot == "robot2");
  CHECK(r.units[2].assigned == std::vector<std::string>{"robot3", "robot2"});
  CHECK(r.units[2].started_s == 15.0);
  CHECK(r.units[2].finished_s == 20.0);
  REQUIRE(r.silent.size() == 1);
  CHECK(r.silent[0] == "robot3 at 10.0 s: liveliness lost");
  const std::string text = r.text();
  CHECK_THAT(text, Catch::Contains("unit C (clean the section C): done by robot2, 15.0-20.0 s; given to robot3, then robot2"));
  CHECK_THAT(text, Catch::Contains("reassigned C from robot3 to robot2 at 10.0 s: robot3 went silent (liveliness lost)"));
  CHECK_THAT(text, Catch::Contains("fleet succeeded: 4 of 4 units done in 20.0 s, 2 reassignments, 0 failed"));
  // fleet.json as a reader parses it: the same result, field by field.
  const nlohmann::json j = nlohmann::json::parse(r.json());
  CHECK(j.at("succeeded") == true);
  CHECK(j.at("duration_s") == 20.0);
  REQUIRE(j.at("units").size() == 4);
  CHECK(j.at("units")[2].at("name") == "C");
  CHECK(j.at("units")[2].at("state") == "done");
  CHECK(j.at("units")[2].at("robot") == "robot2");
  CHECK(j.at("units")[2].at("assigned") == nlohmann::json{"robot3", "robot2"});
  CHECK(j.at("units")[2].at("started_s") == 15.0);
  REQUIRE(j.at("reassignments").size() == 2);
  CHECK(j.at("reassignments")[0] ==
        nlohmann::json{{"unit", "C"}, {"from", "robot3"}, {"to", "robot2"}, {"at_s", 10.0}, {"reason", "robot3 went silent (liveliness lost)"}});
  CHECK(j.at("silent") == nlohmann::json{"robot3 at 10.0 s: liveliness lost"});
  const std::vector<std::string> log = p.take_log();
  CHECK(std::find(log.begin(), log.end(), "10.0 s  robot3 went silent (liveliness lost)") != log.end());
  CHECK(p.take_log().empty());
}

TEST_CASE("fleet: refusals and failures are the unit's result, and answers to other commands are ignored") {
  SimClock clock;
  FleetPlanner p(robots_at_origin(2), {unit("A", 2), unit("B", 1), unit("C", 1)}, clock);
  p.robot_ready("robot1");
  p.robot_ready("robot2");
  std::vector<FleetCommand> cmds = p.poll();
  REQUIRE(cmds.size() == 2);
  const FleetCommand a = cmds[0].unit == "A" ? cmds[0] : cmds[1];
  const FleetCommand b = cmds[0].unit == "A" ? cmds[1] : cmds[0];
  p.robot_event(a.robot, "command_refused", "task_command/999", "start: not mine");  // another command's answer
  CHECK(p.queue_of(a.robot) == std::vector<std::string>{"A"});
  p.robot_event(a.robot, "command_refused", "task_command/" + std::to_string(a.id), "start: not understood");
  accept(p, b);
  p.robot_event(b.robot, "task_failed", "planner", "clean the section B: no recovery rule for fault \"path blocked\" of PrAutoMove");
  // robot1 (A refused) has nothing left: it takes C from robot2's queue; robot2, with nothing left
  // to take, is paused
  cmds = p.poll();
  REQUIRE(cmds.size() == 2);
  CHECK(cmds[0].robot == a.robot);
  CHECK(cmds[0].command == "start");
  CHECK(cmds[0].unit == "C");
  CHECK(cmds[1].robot == b.robot);
  CHECK(cmds[1].command == "pause");
  accept(p, cmds[0]);
  CHECK(p.poll().empty());  // paused once
  succeed(p, cmds[0].robot, "clean the section C");
  CHECK(p.finished());
  const FleetResult r = p.result();
  CHECK_FALSE(r.succeeded);
  CHECK(r.units[0].state == "failed");
  CHECK(r.units[0].detail == "refused: start: not understood");
  CHECK(r.units[1].state == "failed");
  CHECK(r.units[1].detail == "no recovery rule for fault \"path blocked\" of PrAutoMove");
  CHECK(r.units[2].state == "done");
  CHECK(r.reason == "failed: A, B");
  REQUIRE(r.reassignments.size() == 1);
  CHECK(r.reassignments[0].unit == "C");
  CHECK(r.reassignments[0].from == b.robot);
  CHECK(r.reassignments[0].to == a.robot);
  CHECK(r.reassignments[0].reason == a.robot + " had nothing left to do");
  CHECK(r.units[2].assigned == std::vector<std::string>{b.robot, a.robot});
  CHECK_THAT(r.text(), Catch::Contains("fleet did not finish: 1 of 3 units done"));
}

TEST_CASE("fleet: an unanswered start goes again with its id, and a robot that never comes is silent") {
  SimClock clock;
  FleetOptions o;
  o.startup_timeout = 30s;
  o.answer_timeout = 5s;
  FleetPlanner p(robots_at_origin(2), {unit("A", 1), unit("B", 1)}, clock, o);
  p.robot_ready("robot1");
  CHECK(p.ready("robot1"));
  CHECK_FALSE(p.ready("robot2"));
  std::vector<FleetCommand> cmds = p.poll();
  REQUIRE(cmds.size() == 1);
  const FleetCommand first = cmds[0];
  CHECK(p.busy_since_s("robot1") == 0.0);
  clock.advance(4s);
  CHECK(p.poll().empty());
  clock.advance(1s);
  cmds = p.poll();
  REQUIRE(cmds.size() == 1);
  CHECK(cmds[0].id == first.id);
  CHECK(cmds[0].unit == first.unit);
  CHECK(p.busy_since_s("robot1") == 0.0);  // given at 0 s, sent again at 5 s
  accept(p, cmds[0]);
  clock.advance(25s);
  CHECK(p.poll().empty());
  CHECK_FALSE(p.alive("robot2"));  // 30 s without a reader of its task topic
  CHECK(p.queue_of("robot1") == std::vector<std::string>{first.unit, first.unit == "A" ? "B" : "A"});
  REQUIRE(p.result().silent.size() == 1);
  CHECK(p.result().silent[0] == "robot2 at 30.0 s: not on DDS within 30.0 s");
}

TEST_CASE("fleet: an idle robot is paused, and resumed before a unit reassigned to it") {
  SimClock clock;
  FleetPlanner p(robots_at_origin(2), {unit("A", 2), unit("B", 1)}, clock);
  p.robot_ready("robot1");
  p.robot_ready("robot2");
  for (const FleetCommand& c : p.poll()) accept(p, c);
  succeed(p, "robot2", "clean the section B");
  std::vector<FleetCommand> cmds = p.poll();
  REQUIRE(cmds.size() == 1);
  CHECK(cmds[0].robot == "robot2");
  CHECK(cmds[0].command == "pause");
  p.robot_silent("robot1", "liveliness lost");
  cmds = p.poll();
  REQUIRE(cmds.size() == 2);
  CHECK(cmds[0].command == "resume");
  CHECK(cmds[1].command == "start");
  CHECK(cmds[1].unit == "A");
  CHECK(cmds[1].robot == "robot2");
  CHECK(cmds[1].id > cmds[0].id);
}

TEST_CASE("fleet: a robot silent for less than the grace time keeps its units, then loses them") {
  SimClock clock;
  FleetOptions o;
  o.silence_grace = 10s;
  o.pause_idle = false;
  o.take_when_idle = false;
  FleetPlanner p(robots_at_origin(2), {unit("A", 100), unit("B", 60), unit("C", 50)}, clock, o);
  p.robot_ready("robot1");
  p.robot_ready("robot2");
  for (const FleetCommand& c : p.poll()) accept(p, c);
  CHECK(p.queue_of("robot2") == std::vector<std::string>{"B", "C"});
  p.robot_silent("robot2", "liveliness lost");
  clock.advance(9s);
  CHECK(p.poll().empty());
  CHECK(p.alive("robot2"));
  CHECK(p.queue_of("robot2") == std::vector<std::string>{"B", "C"});
  p.robot_back("robot2");  // a partition of 9 s: nothing changes
  clock.advance(5s);
  CHECK(p.poll().empty());
  CHECK(p.queue_of("robot2") == std::vector<std::string>{"B", "C"});
  p.robot_silent("robot2", "liveliness lost");
  clock.advance(10s);
  CHECK(p.poll().empty());  // robot1 still busy with A
  CHECK_FALSE(p.alive("robot2"));
  CHECK(p.queue_of("robot1") == std::vector<std::string>{"A", "B", "C"});
  const FleetResult r = p.result();
  REQUIRE(r.reassignments.size() == 2);
  CHECK(r.reassignments[0].at_s == Approx(24.0));
}

TEST_CASE("fleet: a robot back from a partition keeps the unit it had in hand, and no unit is done twice") {
  SimClock clock;
  FleetOptions o;
  o.silence_grace = 2s;
  o.pause_idle = false;
  o.take_when_idle = false;  // who does C is not this test's matter
  // A 100 to robot1; B 60 and C 50 to robot2.
  FleetPlanner p(robots_at_origin(2), {unit("A", 100), unit("B", 60), unit("C", 50)}, clock, o);
  p.robot_ready("robot1");
  p.robot_ready("robot2");
  for (const FleetCommand& c : p.poll()) accept(p, c);
  clock.advance(10s);
  p.robot_silent("robot1", "liveliness lost");
  clock.advance(2s);
  (void)p.take_log();
  CHECK(p.poll().empty());
  CHECK(p.queue_of("robot2") == std::vector<std::string>{"B", "C", "A"});

  SECTION("back before the other began it: taken back from its queue") {
    clock.advance(20s);
    p.robot_back("robot1");
    CHECK(p.alive("robot1"));
    CHECK(p.queue_of("robot1") == std::vector<std::string>{"A"});
    CHECK(p.queue_of("robot2") == std::vector<std::string>{"B", "C"});
    CHECK(p.poll().empty());  // robot1 is not sent A again: it is on it
    succeed(p, "robot1", "clean the section A");
    succeed(p, "robot2", "clean the section B");
    for (const FleetCommand& c : p.poll()) accept(p, c);
    succeed(p, "robot2", "clean the section C");
    REQUIRE(p.finished());
    const FleetResult r = p.result();
    CHECK(r.succeeded);
    CHECK(r.units[0].robot == "robot1");
    CHECK(r.done_twice == 0);
    CHECK(r.cancelled == 0);
    REQUIRE(r.back.size() == 1);
    CHECK(r.back[0] == "robot1 at 32.0 s (silent 22.0 s)");
    CHECK(r.reassignments.back().reason == "robot1 is back with it in hand");
  }
  SECTION("both on it: the first to finish keeps it, the other is told to cancel") {
    succeed(p, "robot2", "clean the section B");
    for (const FleetCommand& c : p.poll()) accept(p, c);
    succeed(p, "robot2", "clean the section C");
    std::vector<FleetCommand> cmds = p.poll();
    REQUIRE(cmds.size() == 1);
    CHECK(cmds[0].unit == "A");
    accept(p, cmds[0]);
    p.robot_back("robot1");
    succeed(p, "robot1", "clean the section A");
    cmds = p.poll();
    REQUIRE(cmds.size() == 1);
    CHECK(cmds[0].robot == "robot2");
    CHECK(cmds[0].command == "cancel");
    p.robot_event("robot2", "task_failed", "planner", "clean the section A: cancelled");  // its answer: no effect
    REQUIRE(p.finished());
    const FleetResult r = p.result();
    CHECK(r.succeeded);
    CHECK(r.units[0].robot == "robot1");
    CHECK(r.done_twice == 0);
    CHECK(r.cancelled == 1);
  }
  SECTION("the other finished it first: the returning robot's success is counted as work done twice") {
    succeed(p, "robot2", "clean the section B");
    for (const FleetCommand& c : p.poll()) accept(p, c);
    succeed(p, "robot2", "clean the section C");
    for (const FleetCommand& c : p.poll()) accept(p, c);
    succeed(p, "robot2", "clean the section A");
    p.robot_back("robot1");
    succeed(p, "robot1", "clean the section A");
    const FleetResult r = p.result();
    CHECK(r.succeeded);
    CHECK(r.units[0].robot == "robot2");
    CHECK(r.done_twice == 1);
    CHECK_THAT(r.text(), Catch::Contains("work done twice: 1 units"));
  }
}

TEST_CASE("fleet: a robot whose process ended is not back") {
  SimClock clock;
  FleetPlanner p(robots_at_origin(2), {unit("A", 100), unit("B", 60)}, clock);
  p.robot_ready("robot1");
  p.robot_ready("robot2");
  for (const FleetCommand& c : p.poll()) accept(p, c);
  p.robot_gone("robot1");
  p.robot_silent("robot1", "liveliness lost");
  p.robot_back("robot1");
  CHECK_FALSE(p.alive("robot1"));
  CHECK(p.queue_of("robot2") == std::vector<std::string>{"B", "A"});
}

TEST_CASE("fleet: when every robot is silent the fleet ends without the rest") {
  SimClock clock;
  FleetPlanner p(robots_at_origin(2), {unit("A", 1), unit("B", 1)}, clock);
  p.robot_ready("robot1");
  p.robot_ready("robot2");
  for (const FleetCommand& c : p.poll()) accept(p, c);
  p.robot_silent("robot1", "liveliness lost");
  CHECK_FALSE(p.finished());
  CHECK(p.queue_of("robot2").size() == 2);
  p.robot_silent("robot2", "liveliness lost");
  CHECK(p.finished());
  const FleetResult r = p.result();
  CHECK_FALSE(r.succeeded);
  CHECK(r.reason == "not done: A, B (no robot left)");
  CHECK(r.units[0].state == "not done");
}

// A stand-in for `tripodal run` with a dds: section: takes starts on rt/<ns>/tripodal/task and
// answers on rt/<ns>/tripodal/events as RobotBridge does, the task done at once.
struct FakeRobot {
  std::string ns;
  std::optional<Publisher<msg::Event>> events;
  std::optional<Subscriber<msg::TaskCommand>> tasks;
  std::mutex m;
  std::vector<msg::TaskCommand> got;

  FakeRobot(Participant& p, std::string name, bool finish) : ns(std::move(name)) {
    events.emplace(p, ros_topic("tripodal/events", ns), EndpointOptions{.kind = TopicKind::event});
    tasks.emplace(p, ros_topic("tripodal/task", ns), EndpointOptions{.kind = TopicKind::command}, [this, finish](const msg::TaskCommand& c) {
      {
        std::lock_guard lock(m);
        got.push_back(c);
      }
      events->publish({{}, "psr2", "task_command/" + std::to_string(c.id), "command_accepted", c.command + ": ok", 0});
      if (c.command != "start") return;
      events->publish({{}, "psr2", "planner", "task_started", c.task + " (plan ...)", 0});
      if (finish) events->publish({{}, "psr2", "planner", "task_succeeded", c.task, 0});
    });
  }
  std::size_t starts() {
    std::lock_guard lock(m);
    return static_cast<std::size_t>(std::count_if(got.begin(), got.end(), [](const msg::TaskCommand& c) { return c.command == "start"; }));
  }
};

TEST_CASE("fleet: on DDS, stand-in robots get their units, and one that leaves mid-task has its unit reassigned") {
  const std::string base = test::test_namespace();
  std::vector<FleetRobot> robots{{base + "_r1", 0, 0}, {base + "_r2", 0, 0}};
  SteadyClock clock;
  FleetPlanner planner(robots, {unit("A", 2), unit("B", 1)}, clock);
  const ParticipantOptions po = test::test_options(40);
  DdsFleet fleet(planner, robots, DdsFleetOptions{.domain_id = po.domain_id, .participant_lease = po.participant_lease});
  Participant robots_side(po);
  FakeRobot r1(robots_side, robots[0].name, true);
  auto r2 = std::make_unique<FakeRobot>(robots_side, robots[1].name, false);  // B never ends: it is lost

  const auto until = std::chrono::steady_clock::now() + 10s;
  bool left = false;
  while (!planner.finished() && std::chrono::steady_clock::now() < until) {
    fleet.update();
    if (!left && r2->starts() > 0) {
      std::this_thread::sleep_for(100ms);
      r2->events.reset();  // its event writer leaves: liveliness lost at once
      left = true;
    }
    std::this_thread::sleep_for(10ms);
  }
  fleet.update();
  REQUIRE(planner.finished());
  const FleetResult r = planner.result();
  INFO(r.text());
  CHECK(r.succeeded);
  CHECK(r.units[0].robot == robots[0].name);
  CHECK(r.units[1].robot == robots[0].name);
  REQUIRE(r.reassignments.size() == 1);
  CHECK(r.reassignments[0].unit == "B");
  CHECK(r.reassignments[0].from == robots[1].name);
  CHECK(r.reassignments[0].reason == robots[1].name + " went silent (liveliness lost)");
  CHECK(r1.starts() == 2);
}

}  // namespace
}  // namespace tripodal::dds
