#include "tripodal/resources/resource.hpp"

#include <stdexcept>

namespace tripodal {

namespace {
ModuleManifest make_resource_manifest(std::string name, std::string output, std::string description) {
  ModuleManifest m;
  m.name = std::move(name);
  m.layer = Layer::reactive;
  m.kind = ModuleKind::resource;
  m.description = std::move(description);
  m.outputs = {std::move(output)};
  m.parameters = {{"max_age_s", ValueType::number, Value{0.0}, "s",
                   "a reading older than this is stale; 0 = never stale", 0.0, std::nullopt}};
  return m;
}
}  // namespace

template <>
const ModuleManifest& resource_manifest<OdometryReading>() noexcept {
  static const ModuleManifest m =
      make_resource_manifest("OdometryResource", "odometry", "wheel or fused odometry: odom_from_base and body twist");
  return m;
}
template <>
const ModuleManifest& resource_manifest<LaserScan>() noexcept {
  static const ModuleManifest m =
      make_resource_manifest("LaserResource", "laser_scan", "2D laser scanner (fields as sensor_msgs/LaserScan)");
  return m;
}
template <>
const ModuleManifest& resource_manifest<SonarReading>() noexcept {
  static const ModuleManifest m = make_resource_manifest("SonarResource", "sonar", "ring of ultrasonic range finders");
  return m;
}
template <>
const ModuleManifest& resource_manifest<InfraredReading>() noexcept {
  static const ModuleManifest m =
      make_resource_manifest("InfraredResource", "infrared", "infrared cliff detectors and wall ranges");
  return m;
}
template <>
const ModuleManifest& resource_manifest<BumperReading>() noexcept {
  static const ModuleManifest m = make_resource_manifest("BumperResource", "bumpers", "bumper switches");
  return m;
}
template <>
const ModuleManifest& resource_manifest<BatteryReading>() noexcept {
  static const ModuleManifest m =
      make_resource_manifest("BatteryResource", "battery", "battery voltage, current, charge, charging");
  return m;
}
template <>
const ModuleManifest& resource_manifest<GyroReading>() noexcept {
  static const ModuleManifest m = make_resource_manifest("GyroResource", "gyro", "yaw-rate gyro");
  return m;
}
template <>
const ModuleManifest& resource_manifest<JointReading>() noexcept {
  static const ModuleManifest m = make_resource_manifest(
      "JointResource", "joint_state", "a neck or arm joint's state: position, speed, the command it follows, limits");
  return m;
}

void ResourceTable::add(CResource& resource) {
  if (find(resource.name()) != nullptr) {
    throw std::invalid_argument("a resource named '" + resource.name() + "' is already in the table");
  }
  resources_.push_back(&resource);
}

CResource* ResourceTable::find(std::string_view name) const noexcept {
  for (CResource* r : resources_) {
    if (r->name() == name) return r;
  }
  return nullptr;
}

}  // namespace tripodal

namespace tripodal {

void ResourceMirror::set_published(CResource& copy, Time stamp, bool has_reading, std::size_t sequence) noexcept {
  copy.stamp_ = stamp;
  copy.has_reading_ = has_reading;
  copy.sequence_ = sequence;
}

ResourceSnapshot::ResourceSnapshot(const ResourceTable& source) : table_(std::make_unique<ResourceTable>()) {
  for (std::size_t i = 0; i < source.size(); ++i) {
    std::unique_ptr<ResourceMirror> m = source.at(i).make_mirror();
    if (!m) continue;
    table_->add(m->mirror());
    mirrors_.push_back(std::move(m));
  }
}

ResourceSnapshot::~ResourceSnapshot() = default;

void ResourceSnapshot::publish() noexcept {
  for (auto& m : mirrors_) m->publish();
}

std::size_t ResourceSnapshot::refresh() {
  std::size_t changed = 0;
  for (auto& m : mirrors_) changed += m->refresh() ? 1 : 0;
  return changed;
}

}  // namespace tripodal
