#include "tripodal/testing/trace_hardware.hpp"

#include <stdexcept>
#include <utility>

#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal/trace/trace_reader.hpp"

namespace tripodal::testing {

namespace {

std::size_t wheel_count_of(const ControllerConfig& base) noexcept {
  return base.type == "differential" ? 2u : base.holonomic.wheels.size();
}

}  // namespace

TraceHardware::TraceHardware(TraceHardwareOptions options, const ControllerConfig& base, ModuleManifest manifest)
    : options_(std::move(options)),
      manifest_(std::move(manifest)),
      source_(options_.trace),
      summary_(trace::summarize_trace(source_.trace())),
      resources_(summary_.channels, options_.resource_max_age, options_.skip),
      wheels_(wheel_count_of(base), base.period) {
  if (!options_.localization_channel.empty() &&
      trace::find_channel(summary_.channels, options_.localization_channel, trace::ChannelKind::kOdometry) == nullptr) {
    throw std::invalid_argument("hardware 'trace': " + options_.trace.string() + " has no odometry channel '" +
                                options_.localization_channel + "' for the localization");
  }
  replay_ = std::make_unique<trace::TraceReplay>(std::make_unique<trace::TraceReader>(source_.trace()));
}

std::optional<Pose2D> TraceHardware::recorded_pose(Time t) const {
  if (localization_ == nullptr || !localization_->has_reading() || localization_->stamp() > t) return std::nullopt;
  return localization_->latest().pose;
}

const navi::OccupancyGrid& TraceHardware::world_map() const noexcept {
  return options_.world ? options_.world->grid : empty_map_;
}

const navi::RegionMap& TraceHardware::world_regions() const noexcept {
  return options_.world ? options_.world->regions : empty_regions_;
}

void TraceHardware::on_add_resources(ResourceTable& table) {
  resources_.add_to(table);
  if (!options_.localization_channel.empty()) localization_ = table.find<OdometryReading>(options_.localization_channel);
}

void TraceHardware::on_advance_to(Time now) noexcept {
  if (!error_.empty() || replay_->finished()) return;
  try {
    replay_->advance_to(now, resources_);
  } catch (const std::exception& e) {
    // The records before the corrupt one were delivered; the robot goes on without new readings
    // (its resources go stale) and the test kit reports the error.
    error_ = e.what();
  }
}

ModuleManifest trace_hardware_manifest(std::vector<std::string> outputs) {
  return hardware_manifest(
      "trace",
      "a recorded trace replayed open loop: its sensor channels as resources, ideal wheels that move nothing, a "
      "channel of recorded poses as the localizer's ground truth",
      std::move(outputs),
      {ParameterSpec{"trace", ValueType::string, std::nullopt, "", "the trace file, relative to the robot profile", {}, {}},
       ParameterSpec{"localization", ValueType::string, Value{std::string()}, "",
                     "odometry channel of recorded map_from_base poses (the localizer's ground truth)", {}, {}},
       ParameterSpec{"world", ValueType::string, Value{std::string()}, "",
                     "world file whose map the robot takes when its profile names none, relative to the profile", {}, {}},
       ParameterSpec{"max_age_s", ValueType::number, Value{0.0}, "s", "max age of every replayed reading; 0: never stale",
                     0.0, std::nullopt}});
}

void register_trace_hardware(HardwareRegistry& registry, std::vector<std::string> outputs,
                             const std::shared_ptr<const sim::World>& world) {
  if (outputs.empty()) outputs = sim::SimHardware::static_manifest().outputs;
  ModuleManifest manifest = trace_hardware_manifest(std::move(outputs));
  registry.add(manifest, [manifest, world](const HardwareConfig& c) -> std::unique_ptr<CHardware> {
    if (c.base == nullptr) throw ConfigError(c.where, "hardware 'trace' needs the robot's base controller (its wheel count)");
    TraceHardwareOptions o;
    o.trace = c.profile_dir / c.parameters.string("trace");
    o.localization_channel = c.parameters.string("localization");
    o.resource_max_age = from_seconds(c.parameters.number("max_age_s"));
    o.world = world;
    if (const std::string& file = c.parameters.string("world"); !file.empty()) {
      o.world = std::make_shared<const sim::World>(sim::load_world(c.profile_dir / file));
    }
    try {
      return std::make_unique<TraceHardware>(std::move(o), *c.base, manifest);
    } catch (const std::invalid_argument& e) {
      throw ConfigError(c.where, e.what());
    }
  });
}

}  // namespace tripodal::testing
