// CResource: the base of sensor drivers and fusion in the reactive layer. A resource holds the
// latest timestamped reading of one kind; behaviors read it through the BehaviorContext and can
// tell fresh data from stale data by the injected clock's time.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>
#include <vector>

#include "tripodal/core/manifest.hpp"
#include "tripodal/core/snapshot.hpp"
#include "tripodal/core/time.hpp"
#include "tripodal/resources/readings.hpp"

namespace tripodal {

class CResource;

/// A copy of a resource for another thread: the sequencing layer's view of what the reactive loop
/// reads (Robot::start). The loop's thread publish()es the resource's latest reading into a
/// lock-free triple buffer (no lock; no allocation once the buffers have the reading's steady
/// size); the reader's thread refresh()es mirror() from the newest complete copy.
class ResourceMirror {
 public:
  virtual ~ResourceMirror() = default;
  ResourceMirror(const ResourceMirror&) = delete;
  ResourceMirror& operator=(const ResourceMirror&) = delete;
  /// The source's thread: hands over its latest reading when it changed since the last call.
  virtual void publish() noexcept = 0;
  /// The reader's thread: mirror() takes the newest handed-over reading; whether it changed.
  virtual bool refresh() = 0;
  /// The copy: same name, type, manifest, stamp and sequence as the source at its last hand-over.
  [[nodiscard]] virtual const CResource& mirror() const noexcept = 0;
  [[nodiscard]] virtual CResource& mirror() noexcept = 0;

 protected:
  ResourceMirror() = default;
  /// Gives `copy` the source's publication state (stamp, whether a reading exists, its sequence).
  static void set_published(CResource& copy, Time stamp, bool has_reading, std::size_t sequence) noexcept;
};

/// Base of every resource. Public non-virtual methods; drivers implement the protected hooks.
/// Threading: a resource is read and written on its control loop's thread. A driver that
/// receives data on another thread hands it over in on_poll() (called by the loop each cycle).
class CResource {
 public:
  virtual ~CResource() = default;
  CResource(const CResource&) = delete;
  CResource& operator=(const CResource&) = delete;

  /// The instance name ("laser", "odom"); behaviors look resources up by it.
  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  /// The static manifest of the resource type.
  [[nodiscard]] const ModuleManifest& manifest() const noexcept { return do_manifest(); }

  /// Called by the control loop at the start of every cycle: lets a driver publish what it
  /// received since the previous cycle. Never throws; must not allocate in steady state.
  void poll(Time now) noexcept { on_poll(now); }

  /// True once a reading has been published.
  [[nodiscard]] bool has_reading() const noexcept { return has_reading_; }
  /// Time stamp of the latest reading (the reading's own stamp).
  [[nodiscard]] Time stamp() const noexcept { return stamp_; }
  /// How old a reading may be and still count as fresh; 0 means it never goes stale.
  [[nodiscard]] Duration max_age() const noexcept { return max_age_; }
  void set_max_age(Duration max_age) noexcept { max_age_ = max_age; }
  /// Fresh: a reading exists and now - stamp <= max_age (or max_age is 0). A reading stamped in
  /// the future of `now` (clock skew between a driver and the loop) counts as fresh.
  [[nodiscard]] bool is_fresh(Time now) const noexcept {
    return has_reading_ && (max_age_.count() == 0 || now - stamp_ <= max_age_);
  }
  [[nodiscard]] bool is_stale(Time now) const noexcept { return !is_fresh(now); }
  /// Number of readings published so far.
  [[nodiscard]] std::size_t sequence() const noexcept { return sequence_; }

  /// The type of the reading this resource holds (for typed lookups).
  [[nodiscard]] const std::type_info& reading_type() const noexcept { return do_reading_type(); }

  /// A mirror of this resource for another thread (ResourceMirror); nullptr when its reading is
  /// not a copyable value (a link's own state). Every TypedResource has one.
  [[nodiscard]] std::unique_ptr<ResourceMirror> make_mirror() const { return do_make_mirror(); }

 protected:
  friend class ResourceMirror;
  virtual std::unique_ptr<ResourceMirror> do_make_mirror() const { return nullptr; }
  CResource(std::string name, Duration max_age) : name_(std::move(name)), max_age_(max_age) {}
  virtual const ModuleManifest& do_manifest() const noexcept = 0;
  virtual const std::type_info& do_reading_type() const noexcept = 0;
  /// Driver hook, default does nothing (data pushed by publish() from a simulator or replay).
  virtual void on_poll(Time /*now*/) noexcept {}
  /// Records that a reading stamped `stamp` was published.
  void mark_published(Time stamp) noexcept {
    stamp_ = stamp;
    has_reading_ = true;
    ++sequence_;
  }

 private:
  std::string name_;
  Duration max_age_;
  Time stamp_{};
  bool has_reading_ = false;
  std::size_t sequence_ = 0;
};

/// Static manifests of the generic typed resources, one per reading kind (type name and output
/// information name): "OdometryResource"/"odometry", "LaserResource"/"laser_scan",
/// "SonarResource"/"sonar", "InfraredResource"/"infrared", "BumperResource"/"bumpers",
/// "BatteryResource"/"battery", "GyroResource"/"gyro", "JointResource"/"joint_state".
template <class Reading>
const ModuleManifest& resource_manifest() noexcept;

/// A resource holding the latest reading of type `Reading`, fed by a driver, the simulator or a
/// trace replay through publish(). Publishing copies into storage kept from earlier readings, so
/// readings of a steady size (a laser's beam count) allocate nothing after the first one.
template <class Reading>
class TypedResource : public CResource {
 public:
  /// `manifest` (kept by reference) defaults to the generic one of the reading kind; an
  /// application's own reading type passes its resource type's manifest.
  explicit TypedResource(std::string name, Duration max_age = Duration{0},
                         const ModuleManifest& manifest = resource_manifest<Reading>())
      : CResource(std::move(name), max_age), manifest_(&manifest) {}

  /// Stores `reading` as the latest (copy-assigning: vector capacity is reused).
  void publish(const Reading& reading) {
    latest_ = reading;
    mark_published(reading.stamp);
  }
  /// The latest reading; a default-constructed one before the first publish().
  [[nodiscard]] const Reading& latest() const noexcept { return latest_; }
  /// Writable access for a driver that fills the reading in place, followed by commit().
  [[nodiscard]] Reading& edit() noexcept { return latest_; }
  void commit() noexcept { mark_published(latest_.stamp); }

 protected:
  const std::type_info& do_reading_type() const noexcept final { return typeid(Reading); }
  const ModuleManifest& do_manifest() const noexcept override { return *manifest_; }
  std::unique_ptr<ResourceMirror> do_make_mirror() const override;

 private:
  const ModuleManifest* manifest_;
  Reading latest_{};
};

/// The mirror of a TypedResource<Reading>: a plain TypedResource of the same name and manifest.
template <class Reading>
class TypedResourceMirror final : public ResourceMirror {
 public:
  explicit TypedResourceMirror(const TypedResource<Reading>& source)
      : source_(source), copy_(source.name(), source.max_age(), source.manifest()) {}
  void publish() noexcept override {
    if (source_.sequence() == handed_) return;
    handed_ = source_.sequence();
    Entry& e = buffer_.back();
    e.reading = source_.latest();  // copy-assignment: the buffer's capacity is reused
    e.stamp = source_.stamp();
    e.has_reading = source_.has_reading();
    e.sequence = handed_;
    buffer_.publish();
  }
  bool refresh() override {
    if (!buffer_.fetch()) return false;
    const Entry& e = buffer_.front();
    copy_.edit() = e.reading;
    set_published(copy_, e.stamp, e.has_reading, e.sequence);
    return true;
  }
  [[nodiscard]] const CResource& mirror() const noexcept override { return copy_; }
  [[nodiscard]] CResource& mirror() noexcept override { return copy_; }

 private:
  struct Entry {
    Reading reading{};
    Time stamp{};
    bool has_reading = false;
    std::size_t sequence = 0;
  };
  const TypedResource<Reading>& source_;
  std::size_t handed_ = 0;  // the source's sequence last handed over (the writer's)
  TripleBuffer<Entry> buffer_;
  TypedResource<Reading> copy_;  // the reader's
};

template <class Reading>
std::unique_ptr<ResourceMirror> TypedResource<Reading>::do_make_mirror() const {
  return std::make_unique<TypedResourceMirror<Reading>>(*this);
}

using OdometryResource = TypedResource<OdometryReading>;
using LaserResource = TypedResource<LaserScan>;
using SonarResource = TypedResource<SonarReading>;
using InfraredResource = TypedResource<InfraredReading>;
using BumperResource = TypedResource<BumperReading>;
using BatteryResource = TypedResource<BatteryReading>;
using GyroResource = TypedResource<GyroReading>;
using JointResource = TypedResource<JointReading>;

template <> const ModuleManifest& resource_manifest<OdometryReading>() noexcept;
template <> const ModuleManifest& resource_manifest<LaserScan>() noexcept;
template <> const ModuleManifest& resource_manifest<SonarReading>() noexcept;
template <> const ModuleManifest& resource_manifest<InfraredReading>() noexcept;
template <> const ModuleManifest& resource_manifest<BumperReading>() noexcept;
template <> const ModuleManifest& resource_manifest<BatteryReading>() noexcept;
template <> const ModuleManifest& resource_manifest<GyroReading>() noexcept;
template <>
const ModuleManifest& resource_manifest<JointReading>() noexcept;

class ResourceTable;

/// The sequencing layer's copy of a ResourceTable on the wall-clock runtime: a mirror of every
/// resource that has one (ResourceMirror), in a table of its own. publish() on the thread that
/// writes the source table (the reactive loop's), refresh() and table() on the reader's thread.
class ResourceSnapshot {
 public:
  /// Mirrors the resources of `source` present now; `source` must outlive the snapshot.
  explicit ResourceSnapshot(const ResourceTable& source);
  ~ResourceSnapshot();
  ResourceSnapshot(const ResourceSnapshot&) = delete;
  ResourceSnapshot& operator=(const ResourceSnapshot&) = delete;
  /// Writer: hands over every resource's reading that changed. Lock-free, allocation-free once warm.
  void publish() noexcept;
  /// Reader: every mirror takes the newest reading handed over. Returns how many changed.
  std::size_t refresh();
  /// The mirrors, by the sources' names (a resource without a mirror is absent).
  [[nodiscard]] const ResourceTable& table() const noexcept { return *table_; }

 private:
  std::vector<std::unique_ptr<ResourceMirror>> mirrors_;
  std::unique_ptr<ResourceTable> table_;
};

/// The resources a control loop owns or references, looked up by name and reading type.
/// Lookups are for activation time (behaviors keep the pointer); the table does not own.
class ResourceTable {
 public:
  /// Adds `resource` (not owned; must outlive the table). Throws std::invalid_argument when a
  /// resource of the same name is already present.
  void add(CResource& resource);
  [[nodiscard]] CResource* find(std::string_view name) const noexcept;
  /// The resource named `name` holding `Reading`s; nullptr when absent or of another type.
  template <class Reading>
  [[nodiscard]] const TypedResource<Reading>* find(std::string_view name) const noexcept {
    CResource* r = find(name);
    if (r == nullptr || r->reading_type() != typeid(Reading)) return nullptr;
    return static_cast<const TypedResource<Reading>*>(r);
  }
  /// The first resource (in order of addition) holding `Reading`s; nullptr when none.
  template <class Reading>
  [[nodiscard]] const TypedResource<Reading>* first() const noexcept {
    for (CResource* r : resources_) {
      if (r->reading_type() == typeid(Reading)) return static_cast<const TypedResource<Reading>*>(r);
    }
    return nullptr;
  }
  /// Polls every resource in order of addition.
  void poll_all(Time now) noexcept {
    for (CResource* r : resources_) r->poll(now);
  }
  [[nodiscard]] std::size_t size() const noexcept { return resources_.size(); }
  [[nodiscard]] CResource& at(std::size_t i) const noexcept { return *resources_[i]; }

 private:
  std::vector<CResource*> resources_;
};

}  // namespace tripodal
