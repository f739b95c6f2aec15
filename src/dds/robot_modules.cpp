// The DDS laser resource and the cmd_vel controller.
#include "tripodal/dds/robot_modules.hpp"

#include <algorithm>
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
                                      .build();
  return m;
}

namespace {

DdsLaserOptions laser_options(const ParameterSet& p) {
  DdsLaserOptions o;
  o.binding = topic_binding(p, "scan");
  o.max_age = from_seconds(p.contains("max_age_s") ? p.number("max_age_s") : 0.5);
  if (p.contains("deadline_s")) o.deadline = from_seconds(p.number("deadline_s"));
  return o;
}

}  // namespace

DdsLaserResource::DdsLaserResource(std::string name, const ParameterSet& parameters)
    : DdsLaserResource(std::move(name), laser_options(parameters)) {}

DdsLaserResource::DdsLaserResource(std::string name, DdsLaserOptions o)
    : LaserResource(std::move(name), o.max_age, static_manifest()), sender_stamp_(o.lock_step), on_scan_(std::move(o.on_scan)) {
  participant_ = std::make_unique<Participant>(o.binding.participant);
  EndpointOptions options{.kind = TopicKind::scan, .on_status = [this](const StatusEvent& e) { on_status(e); }};
  if (o.deadline > Duration{0} || o.lock_step) {
    Qos q = qos_for(TopicKind::scan, Role::subscriber);
    if (o.deadline > Duration{0}) q.deadline = o.deadline;
    if (o.lock_step) q.reliability = Reliability::reliable;
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
