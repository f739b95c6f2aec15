// A robot on DDS, configured by its profile's dds: section: the PSR-2 on the built-in simulator
// seen and commanded by a test participant on loopback; the section's errors; a DdsLaser whose
// publisher leaves becoming the resource's fault and a fault event.
#include "tripodal/dds/robot_bridge.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cmath>
#include <fstream>
#include <optional>
#include <sstream>
#include <thread>

#include "dds_test_support.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/dds/robot_modules.hpp"
#include "tripodal/resources/resource_faults.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/sim/world.hpp"

using namespace tripodal;
using namespace tripodal::dds;
using namespace tripodal::dds::test;
using namespace std::chrono_literals;

namespace {

const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";

std::string read_text(const std::filesystem::path& f) {
  std::ifstream in(f);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

bool has_event(const std::vector<msg::Event>& events, std::string_view kind, std::string_view source = {}) {
  return std::any_of(events.begin(), events.end(),
                     [&](const msg::Event& e) { return e.kind == kind && (source.empty() || e.source == source); });
}

std::string events_text(const std::vector<msg::Event>& events) {
  std::string out;
  for (const msg::Event& e : events) out += e.source + " " + e.kind + ": " + e.detail + "\n";
  return out;
}

// What the supervisor saw, to show the fault went its way (report_module_fault, "<name>.fault").
struct FaultLog final : SupervisorObserver {
  std::vector<std::string> faults, dropped;
  void on_fault(std::string_view source, std::string_view reason, Time) override {
    faults.push_back(std::string(source) + ": " + std::string(reason));
  }
  void on_event_dropped(std::string_view event, Time) override { dropped.emplace_back(event); }
};

// A resource of a remote device whose faults the test injects (as DdsLaser's come from DDS).
class RemoteDevice final : public TypedResource<GyroReading>, public ResourceFaultSource {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m =
        ManifestBuilder("RemoteDevice", ModuleKind::resource).description("a device behind a link").output("remote_status").build();
    return m;
  }
  explicit RemoteDevice(std::string name) : TypedResource<GyroReading>(std::move(name), Duration{0}, static_manifest()) {}
  std::vector<std::string> take_faults() override { return faults.take(); }
  ResourceFaultQueue faults;
};

}  // namespace

TEST_CASE("dds: a robot with a dds: section publishes its state and takes a task over DDS", "[dds]") {
  const std::uint32_t domain = test_domain(30);
  const std::string ns = test_namespace();
  // The PSR-2 profile as shipped, plus its dds: section; the participant lease is the test
  // participant's (one Cyclone domain per process and id, one configuration).
  const std::string yaml = read_text(kConfigs / "robots/psr2.yaml") + "\ndds:\n  domain_id: " + std::to_string(domain) +
                           "\n  namespace: " + ns + "\n  participant_lease_s: 1\n  period_s: 0.1\n";
  const RobotProfile profile = load_robot_profile_from_string(yaml, "psr2-dds.yaml", kConfigs / "robots");
  REQUIRE(profile.dds);
  CHECK(profile.dds->publish == std::vector<std::string>{"odom", "pose", "map", "events", "markings", "tf", "clock"});

  RobotPlugins plugins;
  register_all(plugins, std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml")));
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);

  // The test's participant: subscribers before the bridge exists, so nothing volatile is missed.
  Participant peer(test_options(30));
  Subscriber<msg::Odometry> odom(peer, ros_topic("odom", ns), {.kind = TopicKind::state});
  Subscriber<msg::PoseWithCovarianceStamped> pose(peer, ros_topic("amcl_pose", ns), {.kind = TopicKind::state});
  Subscriber<msg::Event> events(peer, ros_topic("tripodal/events", ns), {.kind = TopicKind::event});
  Subscriber<msg::Event> markings(peer, ros_topic("tripodal/markings", ns), {.kind = TopicKind::state});
  Publisher<msg::TaskCommand> tasks(peer, ros_topic("tripodal/task", ns), {.kind = TopicKind::command});

  RobotBridge bridge(*robot, clock, *profile.dds);
  CHECK(bridge.topic("odom") == ros_topic("odom", ns));
  CHECK(bridge.topic("task") == ros_topic("tripodal/task", ns));
  REQUIRE(tasks.wait_for_subscribers(1, 5s));
  REQUIRE(odom.wait_for_publishers(1, 5s));
  REQUIRE(events.wait_for_publishers(1, 5s));

  std::vector<msg::Odometry> odoms;
  std::vector<msg::PoseWithCovarianceStamped> poses;
  std::vector<msg::Event> seen, marks;
  auto collect = [&] {
    for (auto& o : odom.take()) odoms.push_back(o);
    for (auto& p : pose.take()) poses.push_back(p);
    for (auto& e : events.take()) seen.push_back(e);
    for (auto& m : markings.take()) marks.push_back(m);
  };
  // Simulated time in steps of 0.1 s, the bridge between them as `tripodal run` drives it; the
  // loop gives the samples on their way a little wall time.
  auto run_until = [&](auto done, int max_steps) {
    for (int i = 0; i < max_steps; ++i) {
      robot->run_for(100ms);
      bridge.update();
      std::this_thread::sleep_for(2ms);
      collect();
      if (done()) return true;
    }
    return false;
  };

  REQUIRE(run_until([&] { return odoms.size() >= 5; }, 100));
  // Frames carry the namespace as a tf prefix, as on /tf.
  CHECK(odoms.back().header.frame_id == ns + "/odom");
  CHECK(odoms.back().child_frame_id == ns + "/base_link");
  CHECK(ros_seconds(odoms.back().header.stamp) > ros_seconds(odoms.front().header.stamp));  // the robot's clock
  CHECK_FALSE(robot->planner().busy());

  // The map is transient-local: a subscriber that comes after it was published still gets it.
  Subscriber<msg::OccupancyGrid> map(peer, ros_topic("map", ns), {.kind = TopicKind::map});
  const std::optional<msg::OccupancyGrid> grid = map.take_one(5s);
  REQUIRE(grid);
  CHECK(grid->header.frame_id == ns + "/map");
  CHECK(grid->info.width > 0);
  CHECK(grid->data.size() == static_cast<std::size_t>(grid->info.width) * grid->info.height);
  CHECK(bridge.count("map") == 1);

  msg::TaskCommand start{ros_time(1.0), "psr2", 41, "start", "clean the room 3211"};
  tasks.publish(start);
  const bool started = run_until([&] { return has_event(seen, "task_started") && has_event(seen, "process_started"); }, 100);
  INFO(events_text(seen));
  REQUIRE(started);
  CHECK(robot->planner().busy());
  CHECK(robot->planner().report().command == "clean the room 3211");
  CHECK(has_event(seen, "command_accepted", "task_command/41"));
  CHECK(bridge.count("task") == 1);
  for (const msg::Event& e : seen) CHECK(e.robot == "psr2");
  // The running nets' markings: the task's high-level net among them.
  REQUIRE(run_until([&] { return has_event(marks, "marking", "task"); }, 50));
  // The localizer's estimate, once it trusts it.
  CHECK(run_until([&] { return !poses.empty(); }, 100));
  if (!poses.empty()) {
    const msg::PoseWithCovarianceStamped& p = poses.back();
    CHECK(p.header.frame_id == ns + "/map");
    // The scan-matching localizer's covariance, on ROS's (x, y, z, roll, pitch, yaw) axes: the
    // planar variances positive (a clear match: a standard deviation under 10 cm), symmetric, and
    // nothing on the axes a ground robot does not move along.
    const auto& c = p.pose.covariance;
    CHECK(c[0] > 0.0);
    CHECK(c[7] > 0.0);
    CHECK(c[35] > 0.0);
    CHECK(c[0] < 0.1 * 0.1);
    CHECK(c[7] < 0.1 * 0.1);
    CHECK(c[1] == c[6]);
    CHECK(c[5] == c[30]);
    CHECK(c[11] == c[31]);
    for (const std::size_t i : {2, 3, 4, 12, 14, 21, 28}) CHECK(c[i] == 0.0);
  }

  // A command for another robot, an unknown one, then cancel: each answered on the events topic.
  tasks.publish({ros_time(2.0), "psr9", 42, "start", "clean the room 3212"});
  REQUIRE(run_until([&] { return has_event(seen, "command_refused", "task_command/42"); }, 50));
  tasks.publish({ros_time(3.0), "", 43, "dance", ""});
  REQUIRE(run_until([&] { return has_event(seen, "command_refused", "task_command/43"); }, 50));
  CHECK(robot->planner().busy());
  tasks.publish({ros_time(4.0), "", 44, "cancel", ""});
  const bool cancelled = run_until([&] { return has_event(seen, "task_failed"); }, 50);
  INFO(events_text(seen));
  CHECK(cancelled);
  CHECK(has_event(seen, "command_accepted", "task_command/44"));
  CHECK_FALSE(robot->planner().busy());
}

TEST_CASE("dds: the robot's frames on /tf and /tf_static, its time on /clock, amcl_pose latched", "[dds]") {
  const std::uint32_t domain = test_domain(34);
  const std::string ns = test_namespace();
  const std::string yaml = read_text(kConfigs / "robots/psr2.yaml") + "\ndds:\n  domain_id: " + std::to_string(domain) +
                           "\n  namespace: " + ns + "\n  participant_lease_s: 1\n  period_s: 0.1\n  tasks: false\n" +
                           "  frames: {front_laser: [0.2, 0.0, 0.0]}\n";
  const RobotProfile profile = load_robot_profile_from_string(yaml, "psr2-dds.yaml", kConfigs / "robots");
  RobotPlugins plugins;
  register_all(plugins, std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml")));
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);

  Participant peer(test_options(34));
  const Qos latched{Reliability::reliable, Durability::transient_local, 1, {}, Liveliness::automatic, {}};
  Subscriber<msg::TFMessage> tf(peer, "rt/tf", {.kind = TopicKind::state});
  Subscriber<msg::Clock> clock_in(peer, "rt/clock", {.qos = qos_for(TopicKind::scan, Role::subscriber)});
  RobotBridge bridge(*robot, clock, *profile.dds, RobotBridgeOptions{.simulated_time = true});
  REQUIRE(tf.wait_for_publishers(1, 5s));
  REQUIRE(clock_in.wait_for_publishers(1, 5s));

  std::vector<msg::TFMessage> tfs;
  std::vector<msg::Clock> clocks;
  bool localized = false;
  for (int i = 0; i < 200 && !(localized && tfs.size() >= 3); ++i) {
    robot->run_for(100ms);
    bridge.update();
    std::this_thread::sleep_for(2ms);
    for (auto& m : tf.take()) tfs.push_back(m);
    for (auto& c : clock_in.take()) clocks.push_back(c);
    localized = robot->navigation().localized;
  }
  REQUIRE(localized);
  // The samples of the last update, on their way.
  for (int i = 0; i < 100 && (clocks.empty() || tfs.empty() || clocks.back().clock != ros_time(clock.now())); ++i) {
    std::this_thread::sleep_for(5ms);
    for (auto& m : tf.take()) tfs.push_back(m);
    for (auto& c : clock_in.take()) clocks.push_back(c);
  }
  REQUIRE_FALSE(clocks.empty());
  CHECK(clocks.back().clock == ros_time(clock.now()));  // the robot's simulated time
  CHECK(bridge.count("clock") >= clocks.size());

  // The last /tf: map -> odom -> base_link composes to the localizer's map_from_base, odom ->
  // base_link is the odometry.
  REQUIRE_FALSE(tfs.empty());
  const msg::TFMessage& last = tfs.back();
  REQUIRE(last.transforms.size() == 2);
  const msg::TransformStamped& map_odom = last.transforms[0];
  const msg::TransformStamped& odom_base = last.transforms[1];
  CHECK(map_odom.header.frame_id == ns + "/map");
  CHECK(map_odom.child_frame_id == ns + "/odom");
  CHECK(odom_base.header.frame_id == ns + "/odom");
  CHECK(odom_base.child_frame_id == ns + "/base_link");
  auto pose_of = [](const msg::Transform& t) {
    return Pose2D{t.translation.x, t.translation.y, 2.0 * std::atan2(t.rotation.z, t.rotation.w)};
  };
  const Pose2D odom_from_base = robot->resources().first<OdometryReading>()->latest().pose;
  CHECK(pose_of(odom_base.transform).x_m == Approx(odom_from_base.x_m).margin(1e-9));
  CHECK(pose_of(odom_base.transform).y_m == Approx(odom_from_base.y_m).margin(1e-9));
  const Pose2D map_from_base = compose(pose_of(map_odom.transform), pose_of(odom_base.transform));
  const Pose2D expected = robot->navigation().map_from_base;
  CHECK(map_from_base.x_m == Approx(expected.x_m).margin(1e-9));
  CHECK(map_from_base.y_m == Approx(expected.y_m).margin(1e-9));
  CHECK(wrap_angle(map_from_base.theta_rad - expected.theta_rad) == Approx(0.0).margin(1e-9));

  // Latched, as tf2's static broadcaster and Nav2's AMCL: subscribers that come late, asking for
  // transient local, get the sensors' frames and the last pose (a volatile writer refuses them).
  Subscriber<msg::TFMessage> tf_static(peer, "rt/tf_static", {.qos = latched});
  const auto statics = tf_static.take_one(5s);
  REQUIRE(statics);
  REQUIRE(statics->transforms.size() == 1);
  CHECK(statics->transforms[0].header.frame_id == ns + "/base_link");
  CHECK(statics->transforms[0].child_frame_id == ns + "/front_laser");
  CHECK(statics->transforms[0].transform.translation.x == 0.2);
  Subscriber<msg::PoseWithCovarianceStamped> amcl(peer, ros_topic("amcl_pose", ns), {.qos = latched});
  const auto pose = amcl.take_one(5s);
  REQUIRE(pose);
  CHECK(pose->header.frame_id == ns + "/map");
}

TEST_CASE("dds: a pause command holds the run until resume", "[dds]") {
  const std::uint32_t domain = test_domain(31);
  const std::string ns = test_namespace();
  const RobotProfile profile = load_robot_profile_from_string(
      "robot: {name: idle}\ndds: {domain_id: " + std::to_string(domain) + ", namespace: " + ns +
          ", participant_lease_s: 1, publish: [events]}\n",
      "idle.yaml", kConfigs / "robots");
  RobotPlugins plugins = builtin_plugins();
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);
  Participant peer(test_options(31));
  Subscriber<msg::Event> events(peer, ros_topic("tripodal/events", ns), {.kind = TopicKind::event});
  Publisher<msg::TaskCommand> tasks(peer, ros_topic("tripodal/task", ns), {.kind = TopicKind::command});
  RobotBridge bridge(*robot, clock, *profile.dds);
  REQUIRE(tasks.wait_for_subscribers(1, 5s));
  CHECK_THROWS_WITH(bridge.topic("scan"), Catch::Contains("no topic 'scan'"));

  auto wait_count = [&](std::uint64_t n) {
    for (int i = 0; i < 500 && bridge.count("task") < n; ++i) {
      std::this_thread::sleep_for(2ms);
      bridge.update();
    }
    return bridge.count("task") >= n;
  };
  CHECK_FALSE(bridge.paused());
  tasks.publish({ros_time(1.0), "idle", 1, "pause", ""});
  REQUIRE(wait_count(1));
  CHECK(bridge.paused());
  tasks.publish({ros_time(2.0), "idle", 2, "resume", ""});
  REQUIRE(wait_count(2));
  CHECK_FALSE(bridge.paused());
  // Nothing but events was asked for.
  CHECK(bridge.count("odom") == 0);
  CHECK(bridge.count("markings") == 0);
  const std::optional<msg::Event> first = events.take_one(5s);
  REQUIRE(first);
  CHECK(first->kind == "command_accepted");
  CHECK(first->detail == "pause: paused");
}

TEST_CASE("dds: a malformed dds: section is refused, located", "[dds]") {
  auto errors_of = [](const std::string& dds) -> std::string {
    try {
      (void)load_robot_profile_from_string("robot: {name: bot}\ndds: " + dds + "\n", "bot.yaml", kConfigs / "robots");
    } catch (const ConfigError& e) {
      return e.what();
    }
    return "no error";
  };
  CHECK_THAT(errors_of("{domain_id: 300}"), Catch::Contains("bot.yaml:2:18: error: dds domain_id: expected a whole number from 0 to 232, got '300'"));
  CHECK_THAT(errors_of("{namespace: 1st/robot}"),
             Catch::Contains("bot.yaml:2:18: error: dds namespace '1st/robot' is not a ROS 2 namespace"));
  CHECK_THAT(errors_of("{namespace: 'a b'}"), Catch::Contains("dds namespace 'a b' is not a ROS 2 namespace"));
  CHECK_THAT(errors_of("{publish: [odom, scans]}"),
             Catch::Contains("bot.yaml:2:23: error: dds publish: expected one of odom, pose, map, events, markings, tf, clock; got 'scans'"));
  CHECK_THAT(errors_of("{frames: {laser: [0.1, 0]}}"),
             Catch::Contains("bot.yaml:2:23: error: dds frames laser: expected [x_m, y_m, theta_rad], got a list of 2 items"));
  CHECK_THAT(errors_of("{frames: {'a/b': [0, 0, 0]}}"), Catch::Contains("bot.yaml:2:16: error: dds frames: 'a/b' is not a frame name"));
  CHECK_THAT(errors_of("{publish: [odom, map, odom]}"),
             Catch::Contains("bot.yaml:2:28: error: dds publish lists 'odom' twice (first at bot.yaml:2:17)"));
  CHECK_THAT(errors_of("{domain: 3}"), Catch::Contains("bot.yaml:2:7: error: unknown key 'domain' in dds; expected one of: domain_id"));
  CHECK_THAT(errors_of("[odom]"), Catch::Contains("bot.yaml:2:6: error: dds: expected a map, got a list"));
  CHECK_THAT(errors_of("{period_s: 0}"), Catch::Contains("bot.yaml:2:17: error: dds period_s: expected seconds from 1e-06 to 9e+09, got '0'"));
  CHECK_THAT(errors_of("{loopback: maybe}"), Catch::Contains("dds loopback: expected true or false, got 'maybe'"));
  CHECK_THAT(errors_of("{tasks: 3}"), Catch::Contains("dds tasks: expected true or false"));
  // Every error of one section at once.
  const std::string all = errors_of("{domain_id: -1, publish: [odom, odom], participant_lease_s: fast}");
  CHECK_THAT(all, Catch::Contains("dds domain_id"));
  CHECK_THAT(all, Catch::Contains("twice"));
  CHECK_THAT(all, Catch::Contains("dds participant_lease_s: expected seconds from 1e-06 to"));
  // The default namespace is the robot's name, which must then be one.
  try {
    (void)load_robot_profile_from_string("robot: {name: PSR-2}\ndds: {domain_id: 3}\n", "psr.yaml", kConfigs / "robots");
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK_THAT(e.what(), Catch::Contains("psr.yaml:2:6: error: dds: the robot's name 'PSR-2' is not a ROS 2 namespace"));
  }
  const RobotProfile ok = load_robot_profile_from_string(
      "robot: {name: bot}\ndds: {domain_id: 7, namespace: /fleet/bot_1, loopback: false, publish: [events], tasks: false,\n"
      "      frames: {laser: [0.2, -0.1, 3.14], sonar_1: [0, 0, 0]}}\n", "ok.yaml",
      kConfigs / "robots");
  REQUIRE(ok.dds);
  CHECK(ok.dds->domain_id == 7);
  CHECK(ok.dds->ros_namespace == "/fleet/bot_1");
  CHECK_FALSE(ok.dds->loopback);
  CHECK(ok.dds->publish == std::vector<std::string>{"events"});
  CHECK_FALSE(ok.dds->tasks);
  CHECK(ok.dds->where.line == 2);
  REQUIRE(ok.dds->frames.size() == 2);
  CHECK(ok.dds->frames[0].name == "laser");
  CHECK(ok.dds->frames[0].base_from_frame == Pose2D{0.2, -0.1, 3.14});
  CHECK(ok.dds->frames[1].name == "sonar_1");
  CHECK_FALSE(load_robot_profile_from_string("robot: {name: bot}\n", "none.yaml", kConfigs / "robots").dds);
}

TEST_CASE("dds: a DdsLaser whose publisher leaves is the resource's fault, a fault event on DDS", "[dds]") {
  const std::uint32_t domain = test_domain(32);
  const std::string ns = test_namespace();
  // The modules' participants have the default options; the bridge's and the test's follow them.
  const RobotProfile profile = load_robot_profile_from_string(
      "robot: {name: lidar}\n"
      "resources:\n  - {name: laser, type: DdsLaser, parameters: {namespace: " + ns + ", domain_id: " + std::to_string(domain) + "}}\n"
      "dds: {domain_id: " + std::to_string(domain) + ", namespace: " + ns + ", publish: [events], tasks: false}\n",
      "lidar.yaml", kConfigs / "robots");
  RobotPlugins plugins = builtin_plugins();
  register_dds_modules(plugins.resources, plugins.controllers);
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);
  FaultLog log;
  robot->supervisor().add_observer(log);
  RobotBridge bridge(*robot, clock, *profile.dds);
  auto* laser = dynamic_cast<DdsLaserResource*>(robot->resources().find("laser"));
  REQUIRE(laser != nullptr);

  ParticipantOptions po;
  po.domain_id = domain;
  Participant peer(po);
  Subscriber<msg::Event> events(peer, ros_topic("tripodal/events", ns), {.kind = TopicKind::event});
  std::optional<Publisher<msg::LaserScan>> scans;
  scans.emplace(peer, ros_topic("scan", ns), EndpointOptions{.kind = TopicKind::scan});
  REQUIRE(scans->wait_for_subscribers(1, 5s));
  scans->publish(sample_scan());
  for (int i = 0; i < 500 && !laser->has_reading(); ++i) {
    std::this_thread::sleep_for(2ms);
    laser->poll(clock.now());
  }
  REQUIRE(laser->has_reading());
  robot->run_for(200ms);
  bridge.update();
  CHECK(log.faults.empty());

  // The laser's publisher leaves: its liveliness is lost at once (a killed process: within its
  // participant lease, tests/dds/two_process_test.cpp), and the next sequencing period reports it.
  const auto left = std::chrono::steady_clock::now();
  scans.reset();
  std::optional<msg::Event> fault;
  while (!fault && std::chrono::steady_clock::now() - left < 5s) {
    robot->run_for(50ms);
    bridge.update();
    for (const msg::Event& e : events.take()) {
      if (e.kind == "fault") fault = e;
    }
    std::this_thread::sleep_for(2ms);
  }
  const double took_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - left).count();
  REQUIRE(fault);
  CHECK(took_s < 1.0);
  CHECK(fault->source == "laser");
  CHECK(fault->severity == 2);
  CHECK_THAT(fault->detail, Catch::Contains("went silent") && Catch::Contains(ros_topic("scan", ns)));
  REQUIRE(log.faults.size() == 1);
  CHECK_THAT(log.faults.front(), Catch::StartsWith("laser: the publisher of"));
  // No process runs: the supervisor posted "laser.fault" and nothing consumed it.
  CHECK(std::find(log.dropped.begin(), log.dropped.end(), "laser.fault") != log.dropped.end());
  // Once per silence: more periods bring no second fault.
  robot->run_for(500ms);
  CHECK(log.faults.size() == 1);
  robot->supervisor().remove_observer(log);
}

// The rest of the way of a resource's fault: a running process fails with it, and the planner's
// recovery rules decide; the bridge tells a peer each step.
TEST_CASE("dds: a resource's fault during a task fails its process and the planner's recovery runs", "[dds]") {
  const std::uint32_t domain = test_domain(33);
  const std::string ns = test_namespace();
  const std::string message = "module remote failed: link lost";
  const std::filesystem::path rules = std::filesystem::temp_directory_path() / ("tripodal_dds_recovery_" + ns + ".yaml");
  {
    std::ofstream out(rules);
    out << read_text(kConfigs / "tasks/recovery.yaml") << "  - fault: \"" << message << "\"\n    insert:\n      - PrWait: {}\n"
        << "    then: retry\n    max_retries: 1\n";
  }
  std::string yaml = read_text(kConfigs / "robots/psr2.yaml");
  const std::string shipped = "recovery: ../tasks/recovery.yaml";
  REQUIRE(yaml.find(shipped) != std::string::npos);
  yaml.replace(yaml.find(shipped), shipped.size(), "recovery: " + rules.string());
  yaml += "resources:\n  - {name: remote, type: RemoteDevice}\ndds: {domain_id: " + std::to_string(domain) + ", namespace: " + ns +
          ", participant_lease_s: 1, publish: [events]}\n";
  const RobotProfile profile = load_robot_profile_from_string(yaml, "psr2-remote.yaml", kConfigs / "robots");

  RobotPlugins plugins;
  register_all(plugins, std::make_shared<sim::World>(sim::load_world(kConfigs / "worlds/workspace.yaml")));
  plugins.resources.add(RemoteDevice::static_manifest(),
                        [](const ResourceConfig& c) -> std::unique_ptr<CResource> { return std::make_unique<RemoteDevice>(c.name); });
  SimClock clock;
  const auto robot = Robot::assemble(profile, plugins, clock);
  std::filesystem::remove(rules);  // read by assemble()
  auto* remote = dynamic_cast<RemoteDevice*>(robot->resources().find("remote"));
  REQUIRE(remote != nullptr);

  Participant peer(test_options(33));
  Subscriber<msg::Event> events(peer, ros_topic("tripodal/events", ns), {.kind = TopicKind::event});
  RobotBridge bridge(*robot, clock, *profile.dds);
  REQUIRE(events.wait_for_publishers(1, 5s));
  std::vector<msg::Event> seen;
  auto run_until = [&](auto done, int max_steps) {
    for (int i = 0; i < max_steps; ++i) {
      robot->run_for(100ms);
      bridge.update();
      std::this_thread::sleep_for(2ms);
      for (auto& e : events.take()) seen.push_back(e);
      if (done()) return true;
    }
    return false;
  };

  REQUIRE(robot->command("clean the room 3211").accepted);
  REQUIRE(run_until([&] { return has_event(seen, "process_started"); }, 50));
  remote->faults.report("link lost");  // as a middleware's thread would
  const bool recovered = run_until([&] { return has_event(seen, "recovery"); }, 50);
  INFO(events_text(seen));
  REQUIRE(recovered);
  CHECK(has_event(seen, "fault", "remote"));
  CHECK(has_event(seen, "process_failed"));
  const auto failed = std::find_if(seen.begin(), seen.end(), [](const msg::Event& e) { return e.kind == "process_failed"; });
  CHECK_THAT(failed->detail, Catch::Contains(message));
  const auto recovery = std::find_if(seen.begin(), seen.end(), [](const msg::Event& e) { return e.kind == "recovery"; });
  CHECK_THAT(recovery->detail, Catch::Contains("PrWait"));
  REQUIRE_FALSE(robot->planner().report().recoveries.empty());
  CHECK(robot->planner().busy());  // the task goes on with the new plan
}
