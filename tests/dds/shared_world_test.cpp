// `tripodal sim-server --robots N`: one world stepped for several lock-step robots. The server is a
// process of its own; this test is its robots (one set of lock-step endpoints per robot, as the
// hardware "dds" has), and checks that each sees the others in its laser, is stopped by them, and
// that robots join and leave while the others run; and that a robot on the hardware dds has the
// simulator's other sensors (gyro, bumpers, cliff, battery) through the server.
#include <catch2/catch.hpp>
#include <chrono>
#include <cmath>
#include <condition_variable>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "dds_test_support.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/controllers/base_kinematics.hpp"
#include "tripodal/dds/dds_hardware.hpp"
#include "tripodal/dds/endpoint.hpp"
#include "tripodal/dds/qos.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/robot/robot_profile.hpp"

using namespace tripodal::dds;
using namespace tripodal::dds::test;
using namespace std::chrono_literals;

namespace {

const std::string kTool = TRIPODAL_TOOL;
const std::string kRobot = std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/psr2.yaml";
const std::string kWorld = std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/workspace.yaml";
constexpr double kPeriodS = 0.01;

// One lock-step robot of the shared world, without a robot: a step writer, the state and scan readers.
class Client {
 public:
  Client(Participant& p, const std::string& ns) : topics_(ns) {
    scan_ = std::make_unique<Subscriber<msg::LaserScan>>(p, topics_.scan, EndpointOptions{.kind = TopicKind::state},
                                                         [this](const msg::LaserScan& s) {
                                                           const std::lock_guard lock(mutex_);
                                                           scan_msg_ = s;
                                                           ++scans_;
                                                         });
    state_ = std::make_unique<Subscriber<msg::SimState>>(p, topics_.sim_state, EndpointOptions{.kind = TopicKind::state},
                                                         [this](const msg::SimState& s) {
                                                           const std::lock_guard lock(mutex_);
                                                           state_msg_ = s;
                                                           cv_.notify_all();
                                                         });
    step_ = std::make_unique<Publisher<msg::SimStep>>(p, topics_.sim_step, EndpointOptions{.kind = TopicKind::state});
    REQUIRE(step_->wait_for_subscribers(1, 10s));
    REQUIRE(state_->wait_for_publishers(1, 10s));
  }
  void leave() { step_.reset(); }

  // Asks for the next step (the robot's clock: step * 10 ms) driving with twist (vx, vy, wz).
  void ask(double vx = 0.0, double vy = 0.0) {
    ++step_no_;
    msg::SimStep s{};
    s.until = ros_time(tripodal::Time{} + std::chrono::nanoseconds(static_cast<std::int64_t>(step_no_) * 10'000'000));
    s.cmd_vel.linear.x = vx;
    s.cmd_vel.linear.y = vy;
    s.step = step_no_;
    step_->publish(s);
  }
  // Waits for the answer to the last step and every scan it counts.
  msg::SimState answer() {
    std::unique_lock lock(mutex_);
    REQUIRE(cv_.wait_for(lock, 10s, [&] { return state_msg_ && state_msg_->step == step_no_; }));
    const auto until = std::chrono::steady_clock::now() + 5s;
    while (scans_ < state_msg_->scans && std::chrono::steady_clock::now() < until) {
      lock.unlock();
      std::this_thread::sleep_for(1ms);
      lock.lock();
    }
    return *state_msg_;
  }
  // The range of the latest scan's beam nearest `bearing_rad` (the robot's frame; the laser at its centre).
  double range_at(double bearing_rad) {
    const std::lock_guard lock(mutex_);
    REQUIRE(scan_msg_.has_value());
    const msg::LaserScan& s = *scan_msg_;
    double a = bearing_rad - s.angle_min;
    while (a < 0.0) a += 2.0 * std::numbers::pi;
    const auto i = static_cast<std::size_t>(std::lround(a / s.angle_increment)) % s.ranges.size();
    return s.ranges[i];
  }

 private:
  BaseTopics topics_;
  std::mutex mutex_;
  std::condition_variable cv_;
  std::optional<msg::LaserScan> scan_msg_;
  std::uint32_t scans_ = 0;
  std::optional<msg::SimState> state_msg_;
  std::uint32_t step_no_ = 0;
  std::unique_ptr<Subscriber<msg::LaserScan>> scan_;
  std::unique_ptr<Subscriber<msg::SimState>> state_;
  std::unique_ptr<Publisher<msg::SimStep>> step_;
};

// Every client asks for a step, then every answer is awaited: one lock-step round of the world.
void step_round(const std::vector<Client*>& clients, std::map<Client*, std::pair<double, double>> drive = {}) {
  for (Client* c : clients) {
    const auto d = drive.find(c);
    c->ask(d == drive.end() ? 0.0 : d->second.first, d == drive.end() ? 0.0 : d->second.second);
  }
  for (Client* c : clients) (void)c->answer();
}

}  // namespace

TEST_CASE("dds: one world for three robots: each sees the others, is stopped by them, and robots come and go",
          "[dds][sim_server][shared_world]") {
  const std::string prefix = test_namespace() + "_r";
  const std::uint32_t domain = test_domain(45);
  ChildProcess server(kTool,
                      {"sim-server", "--robot", kRobot, "--world", kWorld, "--robots", "3", "--namespace", prefix, "--domain",
                       std::to_string(domain), "--wait-s", "60", "--lease-s", "1"},
                      "/tmp/" + test_namespace() + "_shared_server.log");
  ParticipantOptions po = test_options(45);
  Participant p(po);
  // The workspace's start pose is (0.8, 0.8, 0): robot1 there, robot2 1.6 m to its left (+y),
  // robot3 1.6 m ahead (+x) (fleet_starts: spacing 2 x 0.25 + kFleetStartGap_m, 1.1 m).
  Client r1(p, prefix + "1");
  Client r2(p, prefix + "2");
  // Two laser periods (5.5 Hz): the first scan was taken as the body was placed.
  for (int k = 0; k < 40; ++k) step_round({&r1, &r2});
  const double left = std::numbers::pi / 2;
  CHECK(r1.range_at(left) == Approx(1.6 - 0.25).margin(0.05));
  CHECK(r2.range_at(-left) == Approx(1.6 - 0.25).margin(0.05));
  // Nothing ahead of robot1 yet: robot3 has not come.
  const double ahead_alone = r1.range_at(0.0);
  CHECK(ahead_alone > 2.0);

  SECTION("a robot that joins is seen, one that drives into another is stopped, one that leaves is gone") {
    Client r3(p, prefix + "3");
    for (int k = 0; k < 40; ++k) step_round({&r1, &r2, &r3});
    CHECK(r1.range_at(0.0) == Approx(1.6 - 0.25).margin(0.05));
    CHECK(r3.range_at(std::numbers::pi) == Approx(1.6 - 0.25).margin(0.05));

    // robot1 drives at robot3 (+x, 0.3 m/s for 5 s, 1.1 m between them): it stops against it, one contact.
    for (int k = 0; k < 500; ++k) step_round({&r1, &r2, &r3}, {{&r1, {0.3, 0.0}}});
    r1.ask();
    const msg::SimState s1 = r1.answer();
    r2.ask();
    r3.ask();
    (void)r2.answer();
    const msg::SimState s3 = r3.answer();
    CHECK(s1.collisions == 1);
    CHECK(s1.x == Approx(s3.x - 0.5).margin(0.01));  // touching: centre to centre two radii
    CHECK(s3.collisions == 0);

    // robot2 leaves: robot1 no longer sees it.
    r2.leave();
    std::this_thread::sleep_for(500ms);  // its departure reaches the server
    for (int k = 0; k < 40; ++k) step_round({&r1, &r3});
    CHECK(r1.range_at(left) > 2.0);

    r1.leave();
    r3.leave();
    REQUIRE(server.wait(15s) == 0);
    const std::string out = server.output();
    INFO(out);
    CHECK(out.find(prefix + "3 joined at (2.40, 0.80)") != std::string::npos);
    CHECK(std::regex_search(out, std::regex(prefix + "2 left.*0 collisions")));
    CHECK(out.find("simulator: collision with robot 3") != std::string::npos);
    CHECK(out.find("sim-server ended: every robot left") != std::string::npos);
    CHECK(out.find("robot-robot contacts: 1;") != std::string::npos);
  }
}

TEST_CASE("dds: a robot on hardware dds has the simulator's gyro, bumpers, cliff and battery: its bumpers feel another robot",
          "[dds][sim_server][shared_world]") {
  const std::string prefix = test_namespace() + "_s";
  const std::uint32_t domain = test_domain(46);
  ChildProcess server(kTool,
                      {"sim-server", "--robot", kRobot, "--world", kWorld, "--robots", "2", "--namespace", prefix, "--domain",
                       std::to_string(domain), "--wait-s", "60", "--lease-s", "1"},
                      "/tmp/" + test_namespace() + "_sensors_server.log");
  const auto base =
      tripodal::base_controller_config(tripodal::load_robot_profile(kRobot), tripodal::builtin_plugins().controllers);
  REQUIRE(base.has_value());
  tripodal::HardwareRegistry registry{"hardware type"};
  register_dds_hardware(registry);
  tripodal::HardwareConfig config;
  config.type = "dds";
  config.where = tripodal::SourceLocation{"robot.yaml", 12, 3};
  config.base = &*base;
  config.parameters = tripodal::ParameterSet::resolve(DdsHardware::static_manifest(),
                                                      {{"namespace", tripodal::Value{prefix + "1"}},
                                                       {"domain_id", tripodal::Value{static_cast<double>(domain)}},
                                                       {"sensors", tripodal::Value{std::string("gyro, bumpers,cliff,battery")}}},
                                                      config.where);
  auto hw = registry.create_at(config.where, "dds", config);
  tripodal::ResourceTable table;
  hw->add_resources(table);
  const auto* gyro = table.find<tripodal::GyroReading>("gyro");
  const auto* bumpers = table.find<tripodal::BumperReading>("bumpers");
  const auto* cliff = table.find<tripodal::InfraredReading>("cliff");
  const auto* battery = table.find<tripodal::BatteryReading>("battery");
  REQUIRE(gyro != nullptr);
  REQUIRE(bumpers != nullptr);
  REQUIRE(cliff != nullptr);
  REQUIRE(battery != nullptr);

  ParticipantOptions po;
  po.domain_id = domain;  // the hardware's participant options: one Cyclone domain per process and id
  Participant p(po);
  Client r2(p, prefix + "2");  // 1.6 m to the left (+y) of robot 1, standing still
  tripodal::BaseKinematics kinematics(*base);
  std::vector<double> wheels(kinematics.wheel_count(), 0.0);
  std::vector<double> velocity(wheels.size()), position(wheels.size());
  const tripodal::Time t0{};
  // One lock-step period: robot 2 asks, robot 1 (the hardware) advances, robot 2 takes its answer.
  auto step = [&](int k) {
    r2.ask();
    hw->advance_to(t0 + std::chrono::milliseconds(10 * k));
    (void)r2.answer();
    REQUIRE(hw->wheels().read_wheel_states(velocity, position));
  };
  for (int k = 1; k <= 20; ++k) step(k);
  REQUIRE(battery->has_reading());
  const double charge_at_start = battery->latest().percentage;
  CHECK(charge_at_start > 0.9);
  CHECK_FALSE(battery->latest().charging);
  CHECK(gyro->has_reading());
  CHECK(std::abs(gyro->latest().yaw_rate_rad_s) < 0.02);  // standing still: the gyro's noise only
  CHECK(bumpers->latest().count == 4);                    // the workspace's PSR-2: 4 sectors
  CHECK(bumpers->latest().pressed_mask == 0);
  CHECK(cliff->latest().cliff == std::vector<std::uint8_t>{0, 0, 0});  // three sensors over the floor

  // Robot 1 drives left at 0.3 m/s into robot 2 (1.1 m between them): its bumpers press.
  kinematics.inverse(tripodal::Twist2D{0.0, 0.3, 0.0}, wheels);
  bool pressed = false;
  for (int k = 21; k <= 600 && !pressed; ++k) {
    REQUIRE(hw->wheels().write_wheel_velocities(wheels));
    step(k);
    pressed = bumpers->latest().pressed_mask != 0;
  }
  CHECK(pressed);
  CHECK(battery->latest().percentage < charge_at_start);  // driving drained it
  CHECK(gyro->latest().stamp > t0);
  auto& dds_hw = dynamic_cast<DdsHardware&>(*hw);
  CHECK(dds_hw.link_up());
  REQUIRE(dds_hw.truth().has_value());
  CHECK(dds_hw.truth()->map_from_base.y_m > 1.8);  // stopped against robot 2 at (0.8, 2.4), 0.5 m centre to centre
}

TEST_CASE("dds: hardware dds refuses an unknown sensor, at the profile's hardware entry", "[dds][sim_server]") {
  const auto base =
      tripodal::base_controller_config(tripodal::load_robot_profile(kRobot), tripodal::builtin_plugins().controllers);
  REQUIRE(base.has_value());
  tripodal::HardwareConfig config;
  config.type = "dds";
  config.where = tripodal::SourceLocation{"robot.yaml", 12, 3};
  config.base = &*base;
  config.parameters = tripodal::ParameterSet::resolve(DdsHardware::static_manifest(),
                                                      {{"sensors", tripodal::Value{std::string("gyro,sonar")}}}, config.where);
  CHECK_THROWS_WITH(DdsHardware(config),
                    Catch::Contains("robot.yaml:12:3: error: hardware 'dds' sensors: unknown sensor 'sonar'; "
                                    "expected some of gyro, bumpers, cliff, battery"));
}

// Jinny's neck and LED buttons through the sim-server (the exhibit hall's robot: a neck of
// +-40 deg at 60 deg/s, buttons hello, help, weather): the hardware dds exports the neck's
// position channel and its joint resource; a command written to the channel goes with the step,
// the neck turns to it in the server's world and its state comes back; a button pressed over DDS
// (another process's finger on rt/<ns>/tripodal/press_button) comes out of the hardware's button
// panel, once. Before, the hardware carried neither (the profile stayed on `sim`).
TEST_CASE("dds: a robot on hardware dds turns its neck and hears its buttons through the sim-server",
          "[dds][sim_server][shared_world]") {
  const std::string jinny = std::string(TRIPODAL_SOURCE_DIR) + "/configs/robots/jinny.yaml";
  const std::string hall = std::string(TRIPODAL_SOURCE_DIR) + "/configs/worlds/exhibit_hall.yaml";
  const std::string prefix = test_namespace() + "_j";
  const std::uint32_t domain = test_domain(47);
  ChildProcess server(kTool,
                      {"sim-server", "--robot", jinny, "--world", hall, "--robots", "1", "--namespace", prefix, "--domain",
                       std::to_string(domain), "--wait-s", "60", "--lease-s", "1"},
                      "/tmp/" + test_namespace() + "_joints_server.log");
  const auto base =
      tripodal::base_controller_config(tripodal::load_robot_profile(jinny), tripodal::builtin_plugins().controllers);
  REQUIRE(base.has_value());
  tripodal::HardwareConfig config;
  config.type = "dds";
  config.where = tripodal::SourceLocation{"robot.yaml", 12, 3};
  config.base = &*base;
  config.parameters = tripodal::ParameterSet::resolve(
      DdsHardware::static_manifest(),
      {{"namespace", tripodal::Value{prefix + "1"}}, {"domain_id", tripodal::Value{static_cast<double>(domain)}}}, config.where);
  const double limit = 40.0 * std::numbers::pi / 180.0;
  DdsHardware hw(config, {DdsJoint{"neck", -limit, limit, 0.0, 50.0}});
  const auto channel = hw.command_channels().find("neck");
  REQUIRE(channel.has_value());
  CHECK(hw.command_channels().spec(*channel).type == tripodal::ChannelType::joint_position);
  tripodal::ResourceTable table;
  hw.add_resources(table);
  const auto* neck = table.find<tripodal::JointReading>("neck");
  REQUIRE(neck != nullptr);

  int k = 0;
  auto step = [&] {
    ++k;
    hw.advance_to(tripodal::Time{} + std::chrono::milliseconds(10 * k));
  };
  for (int i = 0; i < 5; ++i) step();
  REQUIRE(neck->has_reading());
  CHECK(std::abs(neck->latest().position_rad) < 1e-9);
  CHECK(neck->latest().max_rad == Approx(limit));

  // The behavior loop's fused command: turn the head to 0.5 rad (about 0.48 s at 60 deg/s).
  hw.command_channels().set(*channel, tripodal::ChannelValue::of(0.5));
  for (int i = 0; i < 80; ++i) step();
  CHECK(hw.link_up());
  CHECK(neck->latest().target_rad == Approx(0.5));
  CHECK(neck->latest().position_rad == Approx(0.5).margin(1e-6));
  CHECK(neck->latest().stamp == tripodal::Time{} + std::chrono::milliseconds(10 * k));

  // A visitor presses "hello" (and a name the world has no button of, which is dropped).
  ParticipantOptions po;
  po.domain_id = domain;
  Participant p(po);
  Publisher<msg::String> press(p, ros_topic("tripodal/press_button", prefix + "1"), EndpointOptions{.kind = TopicKind::event});
  REQUIRE(press.wait_for_subscribers(1, 10s));
  press.publish(msg::String{"nosuch"});
  press.publish(msg::String{"hello"});
  std::vector<std::string> presses;
  for (int i = 0; i < 500 && presses.empty(); ++i) {
    step();
    presses = hw.take_button_presses();
    if (presses.empty()) std::this_thread::sleep_for(1ms);  // the press crosses DDS beside the steps
  }
  CHECK(presses == std::vector<std::string>{"hello"});
  for (int i = 0; i < 5; ++i) step();
  CHECK(hw.take_button_presses().empty());  // once
}
