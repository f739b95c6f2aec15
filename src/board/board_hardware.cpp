#include "tripodal/board/board_hardware.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <typeinfo>

#include "tripodal/board/tcp_stream.hpp"

namespace tripodal::board {

const ModuleManifest& tank_resource_manifest() noexcept {
  static const ModuleManifest m = ManifestBuilder("TankResource", ModuleKind::resource)
                                      .description("the disinfectant tank's level (the liquid level module)")
                                      .output("tank")
                                      .build();
  return m;
}

// Runs the link once per control cycle: the loop polls its resources at the start of each cycle.
// Its reading is the link's state as a value (BoardLinkReading), mirrored to the sequencing layer.
class BoardHardware::LinkResource final : public TypedResource<BoardLinkReading> {
 public:
  explicit LinkResource(BoardHardware& hw) : TypedResource<BoardLinkReading>("board_link", Duration{0}, manifest()), hw_(hw) {}

  static const ModuleManifest& manifest() {
    static const ModuleManifest m = ManifestBuilder("BoardLink", ModuleKind::resource)
                                        .description("the control board's UART link: one exchange per control period")
                                        .output("board_link")
                                        .build();
    return m;
  }

 protected:
  void on_poll(Time now) noexcept override {
    hw_.cycle(now);
    const BoardLink& l = hw_.link_;
    BoardLinkReading& r = edit();
    r.stamp = now;
    r.synchronised = l.synchronised();
    r.has_drive = l.has_drive();
    r.buttons = l.has_drive() ? l.drive().buttons : 0;
    r.drive_status = l.has_drive() ? l.drive().status : 0;
    r.drive_stamp = l.drive_stamp();
    r.has_battery = l.has_battery();
    r.battery = l.battery();
    r.has_tank = l.has_tank();
    r.tank_empty = l.tank_empty();
    r.tank_percent = l.tank_percent();
    r.lost_at = l.link_lost_at();
    r.stats = l.stats();
    r.decoder_errors = l.decoder_stats().errors();
    r.pending_actuator_commands = l.pending_actuator_commands();
    commit();
  }

 private:
  BoardHardware& hw_;
};

const ModuleManifest& BoardHardware::static_manifest() {
  static const ModuleManifest m = hardware_manifest(
      "board", "a differential base behind the disinfection robot's control board (UART or TCP, docs/board-protocol.md)",
      {"odometry", "battery", "tank", "sonar", "cliff", "bumpers", "board_link", "laser_scan"},
      {ParameterSpec{"port",
                     ValueType::string,
                     Value{std::string()},
                     "",
                     "the board's tty (e.g. /dev/ttyUSB0), or tcp://HOST:PORT for its ESP8266 Wi-Fi link",
                     {},
                     {}},
       ParameterSpec{"protocol",
                     ValueType::string,
                     Value{std::string("thesis")},
                     "",
                     "the board's protocol profile: thesis, tripodal-v1 or a YAML file (configs/board/)",
                     {},
                     {}},
       ParameterSpec{"baud", ValueType::number, Value{115200.0}, "bit/s", "line rate", 9600.0, 921600.0},
       ParameterSpec{"pulses_per_m", ValueType::number, Value{5000.0}, "1/m", "encoder pulses per metre of wheel travel", 1.0,
                     1e6},
       ParameterSpec{"response_timeout_s", ValueType::number, Value{0.01}, "s", "a response later than this is missed", 0.001,
                     1.0},
       ParameterSpec{"max_missed", ValueType::number, Value{1.0}, "", "consecutive missed responses that lose the link", 1.0,
                     100.0},
       ParameterSpec{"lidar_port",
                     ValueType::string,
                     Value{std::string()},
                     "",
                     "the RPLIDAR A1's tty (e.g. /dev/ttyUSB1, or the path tripodal-board-sim --lidar made): the laser "
                     "resource 'laser' (docs/lidar.md); empty: no lidar",
                     {},
                     {}},
       ParameterSpec{"lidar_timeout_s", ValueType::number, Value{1.0}, "s",
                     "no lidar revolution for this long is the laser's fault", 0.05, 60.0},
       ParameterSpec{"lidar_beams", ValueType::number, Value{360.0}, "", "bins of the laser scan over a full turn", 8.0,
                     8192.0}});
  static const ModuleManifest with_channels = [] {
    ModuleManifest r = m;
    // In this order: BoardHardware::apply_channels() goes by index (kUvLamp ...).
    r.command_channels = {ChannelSpec{"uv_lamp", ChannelType::digital, ChannelValue::of(false), false, Duration{0}, 0.0, 0.0, "",
                                      "the UV lamp (command 0x31)"},
                          ChannelSpec{"atomizer", ChannelType::analog, ChannelValue::of(0.0), false, Duration{0}, 0.0, 1.0, "",
                                      "the atomizer's dry fog, on above 0 (command 0x30)"},
                          ChannelSpec{"atomizer_fan", ChannelType::digital, ChannelValue::of(false), false, Duration{0}, 0.0, 0.0,
                                      "", "the fan that carries the fog, with the atomizer only (command 0x30)"},
                          ChannelSpec{"voice", ChannelType::track, ChannelValue::of(0.0), false, Duration{0}, 0.0, 255.0, "",
                                      "the WT2003S track to play, played when it changes to a track > 0 (command 0x32)"},
                          ChannelSpec{"lcd", ChannelType::text, ChannelValue::of_text(""), false, Duration{0}, 0.0, 0.0, "",
                                      "the LCD's first line, sent when it changes (command 0x33)"}};
    return r;
  }();
  return with_channels;
}

namespace {
enum ChannelIndex : std::size_t { kUvLamp, kAtomizer, kAtomizerFan, kVoice, kLcd };
}  // namespace

BoardHardware::BoardHardware(ByteStream& stream, const BoardHardwareConfig& config, std::unique_ptr<ByteStream> owned)
    : owned_(std::move(owned)),
      config_(config),
      link_(stream, config.link),
      link_resource_(std::make_unique<LinkResource>(*this)) {
  for (const ChannelSpec& c : static_manifest().command_channels) applied_.at(export_channel(c)) = c.safe;
}

BoardHardware::~BoardHardware() = default;

bool BoardHardware::write_wheel_velocities(std::span<const double> wheel_rad_s) noexcept {
  if (wheel_rad_s.size() != 2 || !std::isfinite(wheel_rad_s[0]) || !std::isfinite(wheel_rad_s[1])) return false;
  const auto mm_s = [&](double rad_s) {
    return static_cast<std::int16_t>(std::clamp(std::lround(rad_s * config_.wheel_radius_m * 1000.0), -32768L, 32767L));
  };
  speeds_ = WheelSpeeds{mm_s(wheel_rad_s[0]), mm_s(wheel_rad_s[1])};
  return link_.synchronised();
}

bool BoardHardware::read_wheel_states(std::span<double> velocity_rad_s, std::span<double> position_rad) noexcept {
  if (velocity_rad_s.size() != 2 || position_rad.size() != 2 || !link_.has_drive() || !link_.synchronised()) return false;
  // Synchronised again after a loss: the board may have restarted (power cycle, its process
  // replaced), its encoders counting from 0 again. The wheels' positions go on from where they
  // were, from the first DRIVE answered after that SYNC, so that odometry does not jump. (The
  // first synchronisation keeps the board's own counts.)
  if (link_.stats().resyncs != resyncs_seen_) {
    resyncs_seen_ = link_.stats().resyncs;
    rebase_pending_ = positions_read_;
  }
  if (rebase_pending_ && link_.drive_stamp() <= link_.synchronised_at()) {
    position_rad[0] = position_[0];
    position_rad[1] = position_[1];
    velocity_rad_s[0] = velocity_rad_s[1] = 0.0;
    return true;
  }
  const EncoderState& e = link_.drive().encoders;
  const double per_rad = config_.pulses_per_m * config_.wheel_radius_m;  // pulses per radian of wheel
  const std::array<double, 2> raw{e.left_pulses / per_rad, e.right_pulses / per_rad};
  if (rebase_pending_) {
    rebase_pending_ = false;
    for (std::size_t i = 0; i < 2; ++i) offset_[i] = position_[i] - raw[i];
  }
  for (std::size_t i = 0; i < 2; ++i) position_[i] = position_rad[i] = raw[i] + offset_[i];
  positions_read_ = true;
  velocity_rad_s[0] = e.left_mm_s / 1000.0 / config_.wheel_radius_m;
  velocity_rad_s[1] = e.right_mm_s / 1000.0 / config_.wheel_radius_m;
  return true;
}

void BoardHardware::apply_channels() noexcept {
  const CommandChannels& ch = command_channels();
  auto changed = [&](std::size_t i) noexcept { return !(ch.value(i) == applied_[i]); };
  if (changed(kUvLamp)) {
    const bool on = ch.value(kUvLamp).on();
    if (link_.queue(Command::uv_lamp, std::array<std::uint8_t, 1>{static_cast<std::uint8_t>(on ? 1 : 0)}))
      applied_[kUvLamp] = ch.value(kUvLamp);
  }
  if (changed(kAtomizer) || changed(kAtomizerFan)) {
    const bool fog = ch.value(kAtomizer).number > 0.0;
    const bool fan = fog && ch.value(kAtomizerFan).on();
    if (link_.queue(Command::atomizer, std::array<std::uint8_t, 2>{static_cast<std::uint8_t>(fog ? 1 : 0),
                                                                   static_cast<std::uint8_t>(fan ? 1 : 0)})) {
      applied_[kAtomizer] = ch.value(kAtomizer);
      applied_[kAtomizerFan] = ch.value(kAtomizerFan);
    }
  }
  if (changed(kVoice)) {
    const double track = ch.value(kVoice).number;
    // A track plays once, when the channel changes to it; back to 0 plays nothing.
    if (track < 1.0 || link_.queue(Command::voice, std::array<std::uint8_t, 1>{static_cast<std::uint8_t>(track)})) {
      applied_[kVoice] = ch.value(kVoice);
    }
  }
  if (changed(kLcd)) {
    const std::string_view text = ch.value(kLcd).text();
    std::array<std::uint8_t, 1 + kChannelTextCapacity> payload{};  // line 0, then the text
    std::copy(text.begin(), text.end(), payload.begin() + 1);
    if (link_.queue(Command::lcd_text, std::span<const std::uint8_t>(payload.data(), 1 + text.size())))
      applied_[kLcd] = ch.value(kLcd);
  }
}

void BoardHardware::cycle(Time now) noexcept {
  apply_channels();
  link_.cycle(now, speeds_);
  publish(now);
}

void BoardHardware::publish(Time now) noexcept {
  if (link_.has_drive() && link_.drive_stamp() == now) {
    const std::uint32_t bits = link_.drive().sensors;
    BumperReading& b = bumpers_.edit();
    b.stamp = now;
    b.count = 8;
    b.pressed_mask = (bits >> kBumpShift) & kSegmentMask;
    bumpers_.commit();
    InfraredReading& c = cliff_.edit();
    c.stamp = now;
    const std::size_t n = link_.cliff_count() > 0 ? link_.cliff_count() : 3;
    c.cliff.resize(n);  // the count is fixed after the first reading: no allocation after it
    for (std::size_t i = 0; i < n; ++i) c.cliff[i] = static_cast<std::uint8_t>((bits >> (kCliffShift + i)) & 1U);
    const auto ir = link_.infrared_mm();
    c.wall_ranges_m.resize(ir.size() > n ? ir.size() - n : 0);
    for (std::size_t i = 0; i < c.wall_ranges_m.size(); ++i) {
      const std::uint16_t mm = ir[n + i];
      c.wall_ranges_m[i] = mm == kNoEcho ? std::numeric_limits<float>::infinity() : static_cast<float>(mm) / 1000.0F;
    }
    cliff_.commit();
  }
  if (link_.has_battery()) {
    BatteryReading& b = battery_.edit();
    const BatteryState& s = link_.battery();
    b.stamp = now;
    b.percentage = s.percent / 100.0;
    b.voltage_v = s.voltage_mv / 1000.0;
    b.charging = s.charging;
    battery_.commit();
  }
  if (link_.has_tank()) {
    TankReading& t = tank_.edit();
    t.stamp = now;
    t.percent = link_.tank_percent();
    t.empty = link_.tank_empty();
    tank_.commit();
  }
  const auto us = link_.ultrasonic_mm();
  if (!us.empty()) {
    SonarReading& r = ultrasonic_.edit();
    r.stamp = now;
    r.range_min_m = 0.02;
    r.range_max_m = 4.5;
    r.field_of_view_rad = 0.26;
    r.ranges_m.resize(us.size());
    for (std::size_t i = 0; i < us.size(); ++i) {
      r.ranges_m[i] = us[i] == kNoEcho ? std::numeric_limits<float>::infinity() : static_cast<float>(us[i]) / 1000.0F;
    }
    ultrasonic_.commit();
  }
}

void BoardHardware::on_add_resources(ResourceTable& table) {
  table.add(*link_resource_);  // first: the link runs before the others are read
  table.add(battery_);
  table.add(tank_);
  table.add(ultrasonic_);
  table.add(cliff_);
  table.add(bumpers_);
  if (lidar_) table.add(*lidar_);
}

BoardHardwareConfig board_hardware_config(const HardwareConfig& c) {
  if (c.base == nullptr || c.base->type != "differential") {
    throw ConfigError(c.where, "hardware 'board' drives a differential base; expected a base controller of type 'differential'");
  }
  BoardHardwareConfig config;
  config.wheel_radius_m = c.base->differential.wheel_radius_m;
  config.pulses_per_m = c.parameters.number("pulses_per_m");
  config.link.response_timeout = from_seconds(c.parameters.number("response_timeout_s"));
  config.link.max_missed = static_cast<std::uint32_t>(c.parameters.number("max_missed"));
  const std::string& protocol = c.parameters.string("protocol");
  try {
    config.link.protocol = resolve_protocol_profile(protocol, c.profile_dir);
  } catch (const ConfigError& e) {
    // The profile's own errors are located in its file; say which robot entry named it.
    Diagnostics d = e.diagnostics();
    d.note(c.where, "protocol profile '" + protocol + "' named by hardware 'board' here");
    throw ConfigError(std::move(d));
  }
  return config;
}

void register_board_hardware(HardwareRegistry& registry) {
  registry.add(BoardHardware::static_manifest(), [](const HardwareConfig& c) -> std::unique_ptr<CHardware> {
    const BoardHardwareConfig config = board_hardware_config(c);
    const std::string& port = c.parameters.string("port");
    if (port.empty()) throw ConfigError(c.where, "hardware 'board' needs its port: parameters: {port: /dev/ttyUSB0}");
    // The port's reads are bounded by its own steady clock; the link never waits on them.
    static const SteadyClock port_clock;
    std::unique_ptr<ByteStream> stream;
    try {
      if (is_tcp_port(port)) {
        // The backup channel (seed 001 section 2.x: the ESP8266 on the control board): the same
        // frames over a TCP byte stream; reconnected like a reopened tty.
        stream = std::make_unique<TcpStream>(port, port_clock);
      } else {
        stream = std::make_unique<SerialPort>(port, port_clock,
                                              SerialSettings{static_cast<std::uint32_t>(c.parameters.number("baud"))});
      }
    } catch (const std::runtime_error& e) {
      // "serial port /dev/ttyUSB0: open: No such file or directory", located at the profile's entry.
      throw ConfigError(c.where, std::string("hardware 'board', port: ") + e.what());
    }
    ByteStream& s = *stream;
    auto hw = std::make_unique<BoardHardware>(s, config, std::move(stream));
    if (const std::string& lidar_port = c.parameters.string("lidar_port"); !lidar_port.empty()) {
      RplidarConfig lidar;
      lidar.timeout = from_seconds(c.parameters.number("lidar_timeout_s"));
      lidar.scan.beams = static_cast<std::uint32_t>(std::lround(c.parameters.number("lidar_beams")));
      try {
        hw->attach_lidar(RplidarA1::open("laser", lidar_port, lidar, port_clock));
      } catch (const std::runtime_error& e) {
        throw ConfigError(c.where, std::string("hardware 'board', lidar_port: ") + e.what());
      }
    }
    return hw;
  });
}

}  // namespace tripodal::board
