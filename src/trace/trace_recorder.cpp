#include "tripodal/trace/trace_recorder.hpp"

#include <stdexcept>
#include <typeinfo>

namespace tripodal::trace {

namespace {

bool kind_of_type(const std::type_info& t, ChannelKind& kind) noexcept {
  if (t == typeid(LaserScan)) kind = ChannelKind::kLaser;
  else if (t == typeid(OdometryReading)) kind = ChannelKind::kOdometry;
  else if (t == typeid(SonarReading)) kind = ChannelKind::kSonar;
  else if (t == typeid(InfraredReading)) kind = ChannelKind::kInfrared;
  else if (t == typeid(BumperReading)) kind = ChannelKind::kBumper;
  else if (t == typeid(BatteryReading)) kind = ChannelKind::kBattery;
  else if (t == typeid(GyroReading)) kind = ChannelKind::kGyro;
  else return false;
  return true;
}

template <class Reading>
void write_latest(TraceWriter& w, ChannelId channel, const CResource& r) {
  w.write(channel, static_cast<const TypedResource<Reading>&>(r).latest());
}

}  // namespace

ChannelId TraceRecorder::watch(const CResource& resource) {
  ChannelKind kind{};
  if (!kind_of_type(resource.reading_type(), kind)) {
    throw std::invalid_argument("TraceRecorder: resource '" + resource.name() + "' holds " +
                                resource.reading_type().name() + ", which a trace does not carry");
  }
  const ChannelId id = writer_.add_channel(resource.name(), kind);
  // Readings published before watching are written at the next record() too: the replay then
  // starts from the same state the live behaviors saw.
  watched_.push_back(Watched{&resource, id, kind, 0});
  return id;
}

std::size_t TraceRecorder::watch_all(const ResourceTable& table) {
  std::size_t left_out = 0;
  for (std::size_t i = 0; i < table.size(); ++i) {
    ChannelKind kind{};
    if (!kind_of_type(table.at(i).reading_type(), kind)) {
      ++left_out;
      continue;
    }
    watch(table.at(i));
  }
  return left_out;
}

ChannelId TraceRecorder::record_commands(std::string_view channel) {
  commands_ = writer_.add_channel(channel, ChannelKind::kCommand);
  has_commands_ = true;
  return commands_;
}

ChannelId TraceRecorder::record_events(std::string_view channel) {
  events_ = writer_.add_channel(channel, ChannelKind::kEvent);
  has_events_ = true;
  return events_;
}

std::size_t TraceRecorder::record(Time /*now*/) {
  std::size_t written = 0;
  for (Watched& w : watched_) {
    const CResource& r = *w.resource;
    if (!r.has_reading() || r.sequence() == w.sequence) continue;
    switch (w.kind) {
      case ChannelKind::kLaser: write_latest<LaserScan>(writer_, w.channel, r); break;
      case ChannelKind::kOdometry: write_latest<OdometryReading>(writer_, w.channel, r); break;
      case ChannelKind::kSonar: write_latest<SonarReading>(writer_, w.channel, r); break;
      case ChannelKind::kInfrared: write_latest<InfraredReading>(writer_, w.channel, r); break;
      case ChannelKind::kBumper: write_latest<BumperReading>(writer_, w.channel, r); break;
      case ChannelKind::kBattery: write_latest<BatteryReading>(writer_, w.channel, r); break;
      case ChannelKind::kGyro: write_latest<GyroReading>(writer_, w.channel, r); break;
      case ChannelKind::kCommand:
      case ChannelKind::kEvent: break;
    }
    w.sequence = r.sequence();
    ++written;
  }
  readings_ += written;
  return written;
}

void TraceRecorder::record_command(Time stamp, const Twist2D& command, std::string_view source) {
  if (!has_commands_) throw std::logic_error("TraceRecorder: record_command() before record_commands()");
  command_.stamp = stamp;
  command_.twist = command;
  command_.source.assign(source);
  writer_.write(commands_, command_);
}

void TraceRecorder::record_event(Time stamp, std::string_view name) {
  if (!has_events_) throw std::logic_error("TraceRecorder: record_event() before record_events()");
  event_.stamp = stamp;
  event_.name.assign(name);
  writer_.write(events_, event_);
}

}  // namespace tripodal::trace
