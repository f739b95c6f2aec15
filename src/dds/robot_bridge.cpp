// The robot on DDS: its state out as ROS 2 messages, task commands in (docs/distribution.md).
#include "tripodal/dds/robot_bridge.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <map>
#include <mutex>
#include <typeinfo>
#include <optional>
#include <vector>

#include "tripodal/dds/endpoint.hpp"
#include "tripodal/navi/grid_maps.hpp"
#include "tripodal/planner/plan.hpp"
#include "tripodal/planner/planner.hpp"
#include "tripodal/processes/process_supervisor.hpp"

namespace tripodal::dds {

namespace {

msg::Quaternion yaw_quaternion(double theta_rad) {
  return {0.0, 0.0, std::sin(theta_rad / 2.0), std::cos(theta_rad / 2.0)};
}

msg::Pose pose_of(const Pose2D& p) { return {{p.x_m, p.y_m, 0.0}, yaw_quaternion(p.theta_rad)}; }

// "PrCleaning(section=A)": a plan of one step in the planner's own words (planner/plan.hpp).
std::string step_text(const ProcessStep& s) { return to_string(Plan{{}, {}, {PlanStage{{s}}}}); }

enum Severity : std::uint8_t { kInfo = 0, kWarning = 1, kError = 2 };

msg::Transform transform_of(const Pose2D& p) { return {{p.x_m, p.y_m, 0.0}, yaw_quaternion(p.theta_rad)}; }

// amcl_pose as Nav2's AMCL offers it: its subscribers (Nav2, rviz2's default for the topic) ask
// for transient local and are refused by a volatile writer.
constexpr Qos kPoseQos{Reliability::reliable, Durability::transient_local, 1, {}, Liveliness::automatic, {}};
// tf2's static broadcaster: every static transform in one latched sample.
constexpr Qos kStaticTfQos{Reliability::reliable, Durability::transient_local, 1, {}, Liveliness::automatic, {}};
// tf2's dynamic broadcaster: ROS 2's default profile.
constexpr Qos kTfQos{Reliability::reliable, Durability::volatile_, 100, {}, Liveliness::automatic, {}};
// /clock: a reliable writer serves the readers of rclcpp's clock QoS (best effort, keep last 1)
// and reliable ones alike; only the latest time matters.
constexpr Qos kClockQos{Reliability::reliable, Durability::volatile_, 1, {}, Liveliness::automatic, {}};

}  // namespace

struct RobotBridge::Impl final : TaskObserver, SupervisorObserver {
  Robot& robot;
  const Clock& clock;
  DdsSection section;
  RobotBridgeOptions options;
  std::string robot_name;

  std::unique_ptr<Participant> participant;
  std::optional<Publisher<msg::Odometry>> odom;
  std::optional<Publisher<msg::PoseWithCovarianceStamped>> pose;
  std::optional<Publisher<msg::OccupancyGrid>> map;
  std::optional<Publisher<msg::Event>> events;
  std::optional<Publisher<msg::Event>> markings;
  std::optional<Subscriber<msg::TaskCommand>> tasks;
  std::optional<Publisher<msg::TFMessage>> tf;
  std::optional<Publisher<msg::TFMessage>> tf_static;
  std::optional<Publisher<msg::Clock>> clock_out;

  // Commands arrive on a Cyclone DDS thread and are carried out on the robot's, in update().
  std::mutex inbox_mutex;
  std::vector<msg::TaskCommand> inbox;

  std::atomic<std::uint64_t> n_odom{0}, n_pose{0}, n_map{0}, n_events{0}, n_markings{0}, n_tasks{0}, n_tf{0}, n_tf_static{0},
      n_clock{0};
  std::optional<Time> last_clock;
  bool paused = false;
  std::optional<Time> next_periodic;
  Time last_pose_stamp{Duration{-1}};
  std::pair<int, int> map_size{0, 0};
  bool markings_changed = true;
  std::map<std::string, std::string, std::less<>> last_firing;  // run -> transition id

  Impl(Robot& r, const Clock& c, const DdsSection& s, const RobotBridgeOptions& o)
      : robot(r), clock(c), section(s), options(o), robot_name(r.description().name) {
    ParticipantOptions po;
    po.domain_id = s.domain_id;
    po.network = s.loopback ? Network::loopback : Network::system;
    if (s.participant_lease) po.participant_lease = std::chrono::duration_cast<std::chrono::milliseconds>(*s.participant_lease);
    if (!s.security_identity.empty()) po.security = fleet_identity(s.security_keys, s.security_identity);
    participant = std::make_unique<Participant>(po);
    participant->declare_node("tripodal", s.ros_namespace);
    if (s.publishes("odom")) odom.emplace(*participant, name("odom"), EndpointOptions{.kind = TopicKind::state});
    if (s.publishes("pose")) pose.emplace(*participant, name("pose"), EndpointOptions{.kind = TopicKind::state, .qos = kPoseQos});
    if (s.publishes("tf")) {
      tf.emplace(*participant, name("tf"), EndpointOptions{.kind = TopicKind::state, .qos = kTfQos});
      tf_static.emplace(*participant, name("tf_static"), EndpointOptions{.kind = TopicKind::map, .qos = kStaticTfQos});
    }
    if (s.publishes("clock") && o.simulated_time) {
      clock_out.emplace(*participant, name("clock"), EndpointOptions{.kind = TopicKind::state, .qos = kClockQos});
    }
    if (s.publishes("map")) map.emplace(*participant, name("map"), EndpointOptions{.kind = TopicKind::map});
    if (s.publishes("events")) events.emplace(*participant, name("events"), EndpointOptions{.kind = TopicKind::event});
    if (s.publishes("markings")) markings.emplace(*participant, name("markings"), EndpointOptions{.kind = TopicKind::state});
    if (s.tasks) {
      tasks.emplace(*participant, name("task"), EndpointOptions{.kind = TopicKind::command}, [this](const msg::TaskCommand& t) {
        std::lock_guard lock(inbox_mutex);
        inbox.push_back(t);
      });
    }
    robot.planner().add_observer(*this);
    robot.supervisor().add_observer(*this);
    if (tf_static) publish_static_frames();
  }

  ~Impl() override {
    tasks.reset();  // no more callbacks into the inbox
    robot.supervisor().remove_observer(*this);
    robot.planner().remove_observer(*this);
  }
  Impl(const Impl&) = delete;
  Impl& operator=(const Impl&) = delete;

  [[nodiscard]] std::string name(std::string_view which) const {
    const std::string_view ns = section.ros_namespace;
    if (which == "odom") return ros_topic("odom", ns);
    if (which == "pose") return ros_topic("amcl_pose", ns);
    if (which == "map") return ros_topic("map", ns);
    if (which == "events") return ros_topic("tripodal/events", ns);
    if (which == "markings") return ros_topic("tripodal/markings", ns);
    if (which == "task") return ros_topic("tripodal/task", ns);
    // tf and the clock are global in ROS 2: the robot's frames carry its namespace instead.
    if (which == "tf") return ros_topic("tf");
    if (which == "tf_static") return ros_topic("tf_static");
    if (which == "clock") return ros_topic("clock");
    throw std::invalid_argument("RobotBridge: no topic '" + std::string(which) +
                                "'; expected odom, pose, map, events, markings, task, tf, tf_static or clock");
  }

  [[nodiscard]] std::string frame(std::string_view f) const {
    std::string_view ns = section.ros_namespace;
    while (!ns.empty() && ns.front() == '/') ns.remove_prefix(1);
    while (!ns.empty() && ns.back() == '/') ns.remove_suffix(1);
    return ns.empty() ? std::string(f) : std::string(ns) + "/" + std::string(f);
  }

  // base_link -> each sensor of the profile: the section's frames (their mounts), then every laser
  // resource not among them at the base's origin, named after the resource.
  void publish_static_frames() {
    msg::TFMessage m;
    const msg::Time t = stamp(clock.now());
    std::vector<std::string> named;
    for (const DdsFrame& f : section.frames) {
      m.transforms.push_back({{t, frame("base_link")}, frame(f.name), transform_of(f.base_from_frame)});
      named.push_back(f.name);
    }
    const ResourceTable& table = robot.resources();
    for (std::size_t i = 0; i < table.size(); ++i) {
      const CResource& r = table.at(i);
      if (r.reading_type() != typeid(LaserScan)) continue;
      if (std::find(named.begin(), named.end(), r.name()) != named.end()) continue;
      m.transforms.push_back({{t, frame("base_link")}, frame(r.name()), transform_of(Pose2D{})});
    }
    tf_static->publish(m);
    ++n_tf_static;
  }

  [[nodiscard]] msg::Time stamp(Time t) const { return ros_time(to_seconds(t)); }

  // From observers, which must not throw into the planner or supervisor: a write DDS refuses is lost.
  void event(Time t, std::string source, std::string kind, std::string detail, std::uint8_t severity) {
    if (!events) return;
    try {
      events->publish(msg::Event{stamp(t), robot_name, std::move(source), std::move(kind), std::move(detail), severity});
      ++n_events;
    } catch (const DdsError&) {
    }
  }

  // --- TaskObserver: the task's life cycle -------------------------------------------------------
  void on_command_refused(std::string_view command, std::string_view answer, Time now) override {
    event(now, "planner", "command_refused", std::string(command) + ": " + std::string(answer), kWarning);
  }
  void on_task_started(const TaskReport& task, const Plan& /*plan*/, Time now) override {
    event(now, "planner", "task_started", task.command + " (plan " + task.initial_plan + ")", kInfo);
  }
  void on_process_started(const ProcessRecord& p) override {
    event(p.started, p.run, "process_started", step_text(p.step), kInfo);
  }
  void on_process_succeeded(const ProcessRecord& p) override {
    event(p.finished.value_or(clock.now()), p.run, "process_succeeded", step_text(p.step), kInfo);
  }
  void on_process_failed(const ProcessRecord& p) override {
    event(p.finished.value_or(clock.now()), p.run, "process_failed", step_text(p.step) + ": " + p.message, kWarning);
  }
  void on_recovery(const RecoveryRecord& r) override { event(r.time, r.failed_process, "recovery", r.reason, kWarning); }
  void on_task_succeeded(const TaskReport& task) override {
    event(task.finished.value_or(clock.now()), "planner", "task_succeeded", task.command, kInfo);
  }
  void on_task_failed(const TaskReport& task) override {
    event(task.finished.value_or(clock.now()), "planner", "task_failed", task.command + ": " + task.reason, kError);
  }

  // --- SupervisorObserver: faults and the nets' markings -------------------------------------------
  void on_fault(std::string_view source, std::string_view reason, Time now) override {
    event(now, std::string(source), "fault", std::string(reason), kError);
  }
  void on_run_started(std::string_view, const CProcess&, const ParameterValues&, Time) override { markings_changed = true; }
  void on_run_finished(const ProcessResult&) override { markings_changed = true; }
  void on_firing(std::string_view run, const PetriNet&, const Firing& firing) override {
    last_firing[std::string(run)] = std::string(firing.transition_id);
    markings_changed = true;
  }

  // --- commands ----------------------------------------------------------------------------------
  void carry_out(const msg::TaskCommand& c) {
    ++n_tasks;
    const Time now = clock.now();
    const std::string source = "task_command/" + std::to_string(c.id);
    auto answer = [&](bool accepted, const std::string& text) {
      event(now, source, accepted ? "command_accepted" : "command_refused", c.command + ": " + text, accepted ? kInfo : kWarning);
    };
    if (!c.robot.empty() && c.robot != robot_name) {
      answer(false, "for robot '" + c.robot + "', this is '" + robot_name + "'");
    } else if (c.command == "start") {
      const CommandAnswer a = robot.command(c.task);
      answer(a.accepted, a.text);
    } else if (c.command == "cancel") {
      if (!robot.planner().busy()) {
        answer(false, "no task is running");
      } else {
        robot.planner().cancel("cancelled over DDS (" + source + ")");
        answer(true, "cancelled");
      }
    } else if (c.command == "pause" || c.command == "resume") {
      paused = c.command == "pause";
      answer(true, paused ? "paused" : "resumed");
    } else {
      answer(false, "unknown command '" + c.command + "'; expected start, cancel, pause or resume");
    }
  }

  // --- state out ---------------------------------------------------------------------------------
  void publish_odometry(Time now) {
    const ResourceTable& table = robot.resources();
    const TypedResource<OdometryReading>* r = table.find<OdometryReading>("odometry");
    if (r == nullptr) r = table.first<OdometryReading>();
    if (r == nullptr || !r->has_reading()) return;
    const OdometryReading& o = r->latest();
    msg::Odometry m;
    m.header = {stamp(now), frame("odom")};
    m.child_frame_id = frame("base_link");
    m.pose.pose = pose_of(o.pose);
    m.twist.twist = {{o.twist.vx_m_s, o.twist.vy_m_s, 0.0}, {0.0, 0.0, o.twist.wz_rad_s}};
    odom->publish(m);
    ++n_odom;
  }

  // A new estimate of the localizer (the navigation data's pose stamp moved), when it trusts it.
  void publish_pose() {
    const NavigationData& nav = robot.navigation();
    if (!nav.localized || nav.pose_stamp == last_pose_stamp) return;
    last_pose_stamp = nav.pose_stamp;
    msg::PoseWithCovarianceStamped m;
    m.header = {stamp(nav.pose_stamp), frame("map")};
    m.pose.pose = pose_of(nav.map_from_base);
    // The planar (x, y, theta) covariance into ROS's 6 x 6 over (x, y, z, roll, pitch, yaw), row
    // major: theta is yaw (index 5); the rest stays zero, as amcl leaves it.
    constexpr std::array<std::size_t, 3> kRosIndex{0, 1, 5};
    for (std::size_t r = 0; r < 3; ++r) {
      for (std::size_t c = 0; c < 3; ++c) m.pose.covariance[kRosIndex[r] * 6 + kRosIndex[c]] = nav.pose_covariance[r * 3 + c];
    }
    pose->publish(m);
    ++n_pose;
  }

  void publish_map(Time now) {
    const auto* maps = robot.module<navi::CGridMaps>();
    if (maps == nullptr) return;
    const navi::OccupancyGrid* g = nullptr;
    try {
      g = &maps->grid();
    } catch (const std::logic_error&) {
      return;  // no map yet (live mapping before its first scan)
    }
    if (g->size() == 0 || std::pair{g->width(), g->height()} == map_size) return;
    map_size = {g->width(), g->height()};
    msg::OccupancyGrid m;
    m.header = {stamp(now), frame("map")};
    m.info.map_load_time = stamp(now);
    m.info.resolution = static_cast<float>(g->resolution_m());
    m.info.width = static_cast<std::uint32_t>(g->width());
    m.info.height = static_cast<std::uint32_t>(g->height());
    m.info.origin = pose_of(g->origin());
    m.data = g->values();
    map->publish(m);
    ++n_map;
  }

  // One sample per running net (the task's high-level net is "task"): its marked places.
  void publish_markings(Time now) {
    if (!markings_changed) return;
    markings_changed = false;
    auto one = [&](const std::string& run, const Engine& e) {
      std::string marked;
      const auto m = e.marking();
      for (std::size_t i = 0; i < m.size(); ++i) {
        if (m[i] > 0) marked += (marked.empty() ? "" : ", ") + e.net().places()[i].id + "=" + std::to_string(m[i]);
      }
      const auto lf = last_firing.find(run);
      const std::string detail = e.net().id + ": " + marked + (lf == last_firing.end() ? "" : "; last " + lf->second);
      markings->publish(msg::Event{stamp(now), robot_name, run, "marking", detail, kInfo});
      ++n_markings;
    };
    if (const Engine* e = robot.planner().net_engine()) one("task", *e);
    for (const std::string& run : robot.supervisor().running_runs()) {
      if (const Engine* e = robot.supervisor().engine(run)) one(run, *e);
    }
  }

  // odom -> base_link from the odometry, and map -> odom when the localizer trusts its estimate
  // (map_from_odom = map_from_base * inverse(odom_from_base)), both stamped with the odometry's time.
  void publish_tf(Time now) {
    const ResourceTable& table = robot.resources();
    const TypedResource<OdometryReading>* r = table.find<OdometryReading>("odometry");
    if (r == nullptr) r = table.first<OdometryReading>();
    if (r == nullptr || !r->has_reading()) return;
    const OdometryReading& o = r->latest();
    msg::TFMessage m;
    const NavigationData& nav = robot.navigation();
    if (nav.localized) {
      m.transforms.push_back({{stamp(now), frame("map")}, frame("odom"), transform_of(compose(nav.map_from_base, inverse(o.pose)))});
    }
    m.transforms.push_back({{stamp(now), frame("odom")}, frame("base_link"), transform_of(o.pose)});
    tf->publish(m);
    ++n_tf;
  }

  void publish_clock(Time now) {
    if (last_clock && *last_clock == now) return;
    last_clock = now;
    clock_out->publish(msg::Clock{stamp(now)});
    ++n_clock;
  }

  void update() {
    std::vector<msg::TaskCommand> commands;
    {
      std::lock_guard lock(inbox_mutex);
      commands.swap(inbox);
    }
    for (const msg::TaskCommand& c : commands) carry_out(c);
    const Time now = clock.now();
    // Every update: a use_sim_time node's timers and tf lookups run on it.
    if (clock_out) publish_clock(now);
    if (map) publish_map(now);
    if (next_periodic && now < *next_periodic) return;
    next_periodic = now + section.period;
    if (odom) publish_odometry(now);
    if (tf) publish_tf(now);
    if (pose) publish_pose();
    if (markings) publish_markings(now);
  }
};

RobotBridge::RobotBridge(Robot& robot, const Clock& clock, const DdsSection& section, const RobotBridgeOptions& options)
    : impl_(std::make_unique<Impl>(robot, clock, section, options)) {}

RobotBridge::~RobotBridge() = default;

void RobotBridge::update() { impl_->update(); }
bool RobotBridge::paused() const noexcept { return impl_->paused; }
std::string RobotBridge::topic(std::string_view which) const { return impl_->name(which); }
std::string RobotBridge::frame(std::string_view name) const { return impl_->frame(name); }

std::uint64_t RobotBridge::count(std::string_view which) const noexcept {
  if (which == "odom") return impl_->n_odom;
  if (which == "pose") return impl_->n_pose;
  if (which == "map") return impl_->n_map;
  if (which == "events") return impl_->n_events;
  if (which == "markings") return impl_->n_markings;
  if (which == "task") return impl_->n_tasks;
  if (which == "tf") return impl_->n_tf;
  if (which == "tf_static") return impl_->n_tf_static;
  if (which == "clock") return impl_->n_clock;
  return 0;
}

}  // namespace tripodal::dds
