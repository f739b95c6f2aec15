// The DDS laser resource and the cmd_vel controller.
#include "tripodal/dds/robot_modules.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <numbers>

namespace tripodal::dds {

namespace {

std::vector<ParameterSpec> topic_parameters(std::string default_topic) {
  return {parameter::text("topic", std::move(default_topic), "ROS 2 topic name, without the rt/ prefix"),
          parameter::text("namespace", "", "ROS 2 namespace of the topic (a robot's name in a fleet); empty: none"),
          parameter::number("domain_id", 0.0, "", "DDS domain (ROS_DOMAIN_ID)", 0.0, 232.0),
          parameter::flag("loopback", true, "stay on 127.0.0.1 (false: Cyclone DDS's own network configuration)")};
}

std::string text_or(const ParameterSet& p, std::string_view name, const std::string& fallback) {
  return p.contains(name) ? p.string(name) : fallback;
}

// A module's participant is a ROS 2 node, "tripodal_<module name>" in its topic's namespace, so
// that `ros2 node list` and `ros2 topic info -v` show who reads the driver's topic.
void declare_module_node(Participant& participant, std::string_view module, const ParameterSet& p) {
  std::string name = "tripodal_";
  for (const char c : module) name += (std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_') ? c : '_';
  participant.declare_node(name, text_or(p, "namespace", ""));
}

}  // namespace

TopicBinding topic_binding(const ParameterSet& p, std::string_view default_topic) {
  TopicBinding b;
  b.topic = ros_topic(text_or(p, "topic", std::string(default_topic)), text_or(p, "namespace", ""));
  if (p.contains("domain_id")) b.participant.domain_id = static_cast<std::uint32_t>(p.number("domain_id"));
  if (p.contains("loopback") && !p.boolean("loopback")) b.participant.network = Network::system;
  return b;
}

// --- DdsLaserResource ------------------------------------------------------------------------

const ModuleManifest& DdsLaserResource::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("DdsLaser", ModuleKind::resource)
                                      .description("the latest sensor_msgs/LaserScan of a DDS topic (ROS 2 or tripodal)")
                                      .output("laser_scan")
                                      .parameters(topic_parameters("scan"))
                                      .number("max_age_s", 0.5, "s", "older than this the scan is stale; 0: never", 0.0)
                                      .number("deadline_s", 0.0, "s",
                                              "a fault when no scan comes within this (DDS deadline; the publisher must "
                                              "offer one at least as short); 0: none",
                                              0.0)
                                      .flag("reliable", false,
                                            "a reliable reader: every scan, the first too, but only reliable publishers "
                                            "match (false: best effort, ROS 2's sensor-data QoS, any publisher)")
                                      .build();
  return m;
}

namespace {

DdsLaserOptions laser_options(const ParameterSet& p) {
  DdsLaserOptions o;
  o.binding = topic_binding(p, "scan");
  o.max_age = from_seconds(p.contains("max_age_s") ? p.number("max_age_s") : 0.5);
  if (p.contains("deadline_s")) o.deadline = from_seconds(p.number("deadline_s"));
  o.reliable = p.contains("reliable") && p.boolean("reliable");
  return o;
}

}  // namespace

DdsLaserResource::DdsLaserResource(std::string name, const ParameterSet& parameters)
    : DdsLaserResource(std::move(name), laser_options(parameters)) {
  declare_module_node(*participant_, this->name(), parameters);
}

DdsLaserResource::DdsLaserResource(std::string name, DdsLaserOptions o)
    : LaserResource(std::move(name), o.max_age, static_manifest()), sender_stamp_(o.lock_step), on_scan_(std::move(o.on_scan)) {
  participant_ = std::make_unique<Participant>(o.binding.participant);
  EndpointOptions options{.kind = TopicKind::scan, .on_status = [this](const StatusEvent& e) { on_status(e); }};
  if (o.deadline > Duration{0} || o.lock_step || o.reliable) {
    Qos q = qos_for(TopicKind::scan, Role::subscriber);
    if (o.deadline > Duration{0}) q.deadline = o.deadline;
    if (o.lock_step || o.reliable) q.reliability = Reliability::reliable;
    options.qos = q;
  }
  subscriber_ = std::make_unique<Subscriber<msg::LaserScan>>(
      *participant_, o.binding.topic, options, [this](const msg::LaserScan& s) {
        {
          std::lock_guard lock(mutex_);
          pending_.angle_min_rad = s.angle_min;
          pending_.angle_max_rad = s.angle_max;
          pending_.angle_increment_rad = s.angle_increment;
          pending_.time_increment_s = s.time_increment;
          pending_.scan_time_s = s.scan_time;
          pending_.range_min_m = s.range_min;
          pending_.range_max_m = s.range_max;
          pending_.ranges_m.assign(s.ranges.begin(), s.ranges.end());
          pending_.intensities.assign(s.intensities.begin(), s.intensities.end());
          pending_stamp_ = tripodal_time(s.header.stamp);
          has_pending_.store(true, std::memory_order_release);
          silent_.store(false, std::memory_order_relaxed);
        }
        received_.fetch_add(1, std::memory_order_acq_rel);
        if (on_scan_) on_scan_();
      });
}

// The subscriber goes first: its callback uses the members below it.
DdsLaserResource::~DdsLaserResource() { subscriber_.reset(); }

// On a Cyclone DDS thread. A lost publisher while another still sends is no fault: only the
// laser's silence is.
void DdsLaserResource::on_status(const StatusEvent& e) {
  if (e.kind == StatusKind::liveliness_lost && e.current_count == 0) {
    silent_.store(true, std::memory_order_relaxed);
    faults_.report("the publisher of " + e.topic + " went silent (DDS liveliness lost: its process died, its lease ran out or it left)");
  } else if (e.kind == StatusKind::deadline_missed && !silent_.exchange(true, std::memory_order_relaxed)) {
    // Once per silence: the deadline is missed again every period until a scan comes.
    faults_.report("no scan on " + e.topic + " within its deadline (missed " + std::to_string(e.total_count) + " times)");
  }
}

const std::string& DdsLaserResource::topic() const noexcept { return subscriber_->topic(); }
std::size_t DdsLaserResource::matched_publishers() const { return subscriber_->matched_publishers(); }

void DdsLaserResource::on_poll(Time now) noexcept {
  if (!has_pending_.load(std::memory_order_acquire)) return;
  std::lock_guard lock(mutex_);
  // Swapping keeps both buffers' capacity: no allocation once the beam count is steady.
  LaserScan& latest = edit();
  std::swap(latest, pending_);
  // Another process's clock is not the loop's: the scan is as old as the news of it, unless the
  // sender's clock is the robot's own (lock-step).
  latest.stamp = sender_stamp_ ? std::min(pending_stamp_, now) : now;
  has_pending_.store(false, std::memory_order_relaxed);
  commit();
}

// --- DdsReadingResource ------------------------------------------------------------------------

namespace {

double yaw_of(const msg::Quaternion& q) {
  return std::atan2(2.0 * (q.w * q.z + q.x * q.y), 1.0 - 2.0 * (q.y * q.y + q.z * q.z));
}
Pose2D pose2d_of(const msg::Pose& p) { return {p.position.x, p.position.y, yaw_of(p.orientation)}; }

// What each reading type takes from its message, and its type's name, topic and QoS.
template <class Reading, class Msg>
struct ReadingTraits;

template <>
struct ReadingTraits<OdometryReading, msg::Odometry> {
  static constexpr std::string_view kType = "DdsOdometry";
  static constexpr std::string_view kTopic = "odom";
  static constexpr std::string_view kOutput = "odometry";
  static constexpr std::string_view kDescription = "the latest nav_msgs/Odometry of a DDS topic (a ROS 2 base driver's odom)";
  static constexpr TopicKind kKind = TopicKind::state;
  static void convert(const msg::Odometry& m, OdometryReading& r) {
    r.pose = pose2d_of(m.pose.pose);
    r.twist = {m.twist.twist.linear.x, m.twist.twist.linear.y, m.twist.twist.angular.z};
  }
};

template <>
struct ReadingTraits<GyroReading, msg::Imu> {
  static constexpr std::string_view kType = "DdsImu";
  static constexpr std::string_view kTopic = "imu";
  static constexpr std::string_view kOutput = "gyro";
  static constexpr std::string_view kDescription = "the yaw rate and yaw of the latest sensor_msgs/Imu of a DDS topic";
  static constexpr TopicKind kKind = TopicKind::scan;  // sensor data: best effort
  static void convert(const msg::Imu& m, GyroReading& r) {
    r.yaw_rate_rad_s = m.angular_velocity.z;
    // orientation_covariance[0] = -1: the IMU gives no orientation (ROS's convention)
    r.yaw_rad = m.orientation_covariance[0] < 0.0 ? 0.0 : yaw_of(m.orientation);
  }
};

template <>
struct ReadingTraits<PoseEstimate, msg::PoseWithCovarianceStamped> {
  static constexpr std::string_view kType = "DdsPose";
  static constexpr std::string_view kTopic = "amcl_pose";
  static constexpr std::string_view kOutput = "pose_estimate";
  static constexpr std::string_view kDescription =
      "the latest geometry_msgs/PoseWithCovarianceStamped of a DDS topic (a ROS 2 localizer's amcl_pose)";
  // Reliable, volatile: matches AMCL's transient local writer too, and gets its last pose at once.
  static constexpr TopicKind kKind = TopicKind::state;
  static void convert(const msg::PoseWithCovarianceStamped& m, PoseEstimate& r) {
    r.map_from_base = pose2d_of(m.pose.pose);
    constexpr std::array<std::size_t, 3> kRosIndex{0, 1, 5};  // x, y, yaw of ROS's 6 x 6
    for (std::size_t i = 0; i < 3; ++i) {
      for (std::size_t j = 0; j < 3; ++j) r.covariance[i * 3 + j] = m.pose.covariance[kRosIndex[i] * 6 + kRosIndex[j]];
    }
  }
};

}  // namespace

template <class Reading, class Msg>
const ModuleManifest& DdsReadingResource<Reading, Msg>::static_manifest() {
  using Traits = ReadingTraits<Reading, Msg>;
  static const ModuleManifest m = ManifestBuilder(std::string(Traits::kType), ModuleKind::resource)
                                      .description(std::string(Traits::kDescription))
                                      .output(std::string(Traits::kOutput))
                                      .parameters(topic_parameters(std::string(Traits::kTopic)))
                                      .number("max_age_s", 0.5, "s", "older than this the reading is stale; 0: never", 0.0)
                                      .flag("reliable", Traits::kKind != TopicKind::scan,
                                            "a reliable reader (only reliable publishers match); false: best effort, any "
                                            "publisher, a sample lost is not repaired")
                                      .build();
  return m;
}

template <class Reading, class Msg>
DdsReadingResource<Reading, Msg>::DdsReadingResource(std::string name, const ParameterSet& p)
    : TypedResource<Reading>(std::move(name), from_seconds(p.contains("max_age_s") ? p.number("max_age_s") : 0.5),
                             static_manifest()) {
  using Traits = ReadingTraits<Reading, Msg>;
  const TopicBinding b = topic_binding(p, Traits::kTopic);
  participant_ = std::make_unique<Participant>(b.participant);
  declare_module_node(*participant_, this->name(), p);
  EndpointOptions options{.kind = Traits::kKind, .on_status = [this](const StatusEvent& e) {
                            if (e.kind == StatusKind::liveliness_lost && e.current_count == 0) {
                              faults_.report("the publisher of " + e.topic + " went silent (DDS liveliness lost)");
                            }
                          }};
  Qos q = qos_for(Traits::kKind, Role::subscriber);
  q.reliability = (p.contains("reliable") ? p.boolean("reliable") : Traits::kKind != TopicKind::scan) ? Reliability::reliable
                                                                                                    : Reliability::best_effort;
  options.qos = q;
  subscriber_ = std::make_unique<Subscriber<Msg>>(*participant_, b.topic, options, [this](const Msg& m) {
    {
      std::lock_guard lock(mutex_);
      Traits::convert(m, pending_);
      has_pending_.store(true, std::memory_order_release);
    }
    received_.fetch_add(1, std::memory_order_acq_rel);
  });
}

template <class Reading, class Msg>
DdsReadingResource<Reading, Msg>::~DdsReadingResource() {
  subscriber_.reset();
}

template <class Reading, class Msg>
const std::string& DdsReadingResource<Reading, Msg>::topic() const noexcept {
  return subscriber_->topic();
}
template <class Reading, class Msg>
std::size_t DdsReadingResource<Reading, Msg>::matched_publishers() const {
  return subscriber_->matched_publishers();
}

template <class Reading, class Msg>
void DdsReadingResource<Reading, Msg>::on_poll(Time now) noexcept {
  if (!has_pending_.load(std::memory_order_acquire)) return;
  std::lock_guard lock(mutex_);
  Reading& latest = this->edit();
  latest = pending_;
  latest.stamp = now;  // the sender's clock is not the loop's
  has_pending_.store(false, std::memory_order_relaxed);
  this->commit();
}

template class DdsReadingResource<OdometryReading, msg::Odometry>;
template class DdsReadingResource<GyroReading, msg::Imu>;
template class DdsReadingResource<PoseEstimate, msg::PoseWithCovarianceStamped>;

// --- DdsCmdVelController -----------------------------------------------------------------------

const ModuleManifest& DdsCmdVelController::static_manifest() {
  static const ModuleManifest m = [] {
    auto specific = topic_parameters("cmd_vel");
    specific.push_back(parameter::flag("holonomic", false, "the base can move sideways (linear.y is sent)"));
    return controller_manifest("dds_cmd_vel",
                               "publishes the limited command as geometry_msgs/Twist for a base driven elsewhere",
                               std::move(specific));
  }();
  return m;
}

DdsCmdVelController::DdsCmdVelController(const ControllerConfig& config, HardwareInterface& /*hardware*/)
    : CController(config.period), config_(config), limiter_(config.limits) {
  Diagnostics d = validate(config_);
  if (d.has_errors()) throw ConfigError(std::move(d));
  holonomic_ = config.parameters.contains("holonomic") && config.parameters.boolean("holonomic");
  const TopicBinding b = topic_binding(config.parameters, "cmd_vel");
  participant_ = std::make_unique<Participant>(b.participant);
  declare_module_node(*participant_, config.name, config.parameters);
  publisher_ = std::make_unique<Publisher<msg::Twist>>(*participant_, b.topic, EndpointOptions{.kind = TopicKind::command});
}

DdsCmdVelController::~DdsCmdVelController() = default;

const std::string& DdsCmdVelController::topic() const noexcept { return publisher_->topic(); }
std::size_t DdsCmdVelController::matched_subscribers() const { return publisher_->matched_subscribers(); }

BaseCapabilities DdsCmdVelController::do_capabilities() const noexcept {
  BaseCapabilities c;
  const auto& l = config_.limits;
  c.max_vx_m_s = l.vx.max_velocity.value_or(c.max_vx_m_s);
  c.max_vy_m_s = holonomic_ ? l.vy.max_velocity.value_or(c.max_vy_m_s) : 0.0;
  c.max_wz_rad_s = l.wz.max_velocity.value_or(c.max_wz_rad_s);
  return c;
}

ControlStatus DdsCmdVelController::on_update(Time now, Duration period, const Twist2D& command, bool /*timed_out*/,
                                             Twist2D& limited, OdometryReading& odometry) noexcept {
  const double dt = to_seconds(period);
  Twist2D target = command;
  if (!holonomic_) target.vy_m_s = 0.0;
  bool clipped = false;
  limited = limiter_.apply(target, dt, clipped);
  bool written = true;
  try {
    publisher_->publish({{limited.vx_m_s, limited.vy_m_s, 0.0}, {0.0, 0.0, limited.wz_rad_s}});
  } catch (...) {
    written = false;  // Cyclone refused the write (out of resources, deleted entity)
  }
  // Dead reckoning of the commanded twist: the base's own odometry, if any, comes on its own topic.
  const double c = std::cos(odometry.pose.theta_rad);
  const double s = std::sin(odometry.pose.theta_rad);
  odometry.pose.x_m += (limited.vx_m_s * c - limited.vy_m_s * s) * dt;
  odometry.pose.y_m += (limited.vx_m_s * s + limited.vy_m_s * c) * dt;
  odometry.pose.theta_rad = std::remainder(odometry.pose.theta_rad + limited.wz_rad_s * dt, 2.0 * std::numbers::pi);
  odometry.twist = limited;
  odometry.stamp = now;
  if (!written) return ControlStatus::hardware_fault;
  return clipped ? ControlStatus::limited : ControlStatus::ok;
}

}  // namespace tripodal::dds
