#include "tripodal/board/rplidar_a1.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>
#include <system_error>

namespace tripodal::board {
namespace {

constexpr std::array<std::string_view, 5> kFaultText{
    "no revolution (start flag) within the timeout: the lidar stopped spinning or sending",
    "the lidar's serial port is gone (unplugged?)",
    "the lidar does not answer (GET_INFO, GET_HEALTH or SCAN)",
    "the lidar answers garbage: no RPLIDAR response descriptor where one was due",
    "the lidar reports health status error (protection stop)",
};

// The A1's USB adapter: DTR asserted holds the motor, released lets it spin.
class DtrMotor final : public MotorSwitch {
 public:
  explicit DtrMotor(SerialPort& port) : port_(port) {}
  bool set_motor(bool on) noexcept override { return port_.set_dtr(!on); }

 private:
  SerialPort& port_;
};

std::string hex_prefix(std::span<const std::uint8_t> bytes) {
  std::string s;
  for (std::size_t i = 0; i < std::min<std::size_t>(bytes.size(), 8); ++i)
    s += fmt::format("{}{:02X}", i == 0 ? "" : " ", bytes[i]);
  if (bytes.size() > 8) s += " ...";
  return s;
}

std::string describe(const rplidar::Descriptor& d) {
  return fmt::format("length {} mode {} type 0x{:02X}", d.length, d.mode, d.type);
}

}  // namespace

std::string_view to_string(RplidarA1::State s) noexcept {
  switch (s) {
    case RplidarA1::State::starting:
      return "starting";
    case RplidarA1::State::awaiting_info:
      return "awaiting GET_INFO";
    case RplidarA1::State::awaiting_health:
      return "awaiting GET_HEALTH";
    case RplidarA1::State::awaiting_scan:
      return "awaiting SCAN";
    case RplidarA1::State::scanning:
      return "scanning";
    case RplidarA1::State::stalled:
      return "stalled";
    case RplidarA1::State::failed:
      return "failed";
  }
  return "?";
}

const ModuleManifest& RplidarA1::static_manifest() {
  static const ModuleManifest m =
      ManifestBuilder("RplidarA1", ModuleKind::resource)
          .description(
              "SLAMTEC RPLIDAR A1 on a serial port (115200 8N1, motor by DTR): one laser_scan per revolution (docs/lidar.md)")
          .output("laser_scan")
          .text("port", std::nullopt, "the lidar's tty: /dev/ttyUSB0, or the pseudo-terminal tripodal-board-sim --lidar makes")
          .number("timeout_s", 1.0, "s", "no revolution for this long is the resource's fault", 0.05, 60.0)
          .number("beams", 360.0, "", "bins of the published scan over a full turn", 8.0, 8192.0)
          .number("range_min_m", 0.15, "m", "returns nearer than this are dropped", 0.0, 100.0)
          .number("range_max_m", 12.0, "m", "returns farther than this are dropped", 0.1, 100.0)
          .number("rate_hz", 5.5, "Hz", "nominal revolutions per second (the scan's scan_time_s)", 0.5, 50.0)
          .build();
  return m;
}

RplidarConfig rplidar_config(const ParameterSet& p) {
  RplidarConfig c;
  c.timeout = from_seconds(p.number("timeout_s"));
  c.scan.beams = static_cast<std::uint32_t>(std::lround(p.number("beams")));
  c.scan.range_min_m = p.number("range_min_m");
  c.scan.range_max_m = p.number("range_max_m");
  c.scan.rate_hz = p.number("rate_hz");
  return c;
}

std::unique_ptr<RplidarA1> open_rplidar_resource(const std::string& name, const ParameterSet& p, const SourceLocation& where) {
  static const SteadyClock port_clock;  // the port's reads and the open's waits; polls bring the loop's time
  try {
    return RplidarA1::open(name, p.string("port"), rplidar_config(p), port_clock);
  } catch (const std::runtime_error& e) {
    throw ConfigError(where, "resource '" + name + "' (RplidarA1): " + e.what());
  }
}

RplidarA1::RplidarA1(std::string name, ByteStream& stream, const RplidarConfig& config, MotorSwitch* motor,
                     std::unique_ptr<ByteStream> owned)
    : LaserResource(std::move(name), config.timeout, static_manifest()),
      owned_(std::move(owned)),
      stream_(stream),
      config_(config),
      motor_(motor),
      assembler_(config.scan) {
  if (motor_ == nullptr) {
    if (auto* port = dynamic_cast<SerialPort*>(&stream_)) {
      own_motor_ = std::make_unique<DtrMotor>(*port);
      motor_ = own_motor_.get();
    }
  }
}

RplidarA1::~RplidarA1() {
  shutdown();
}

std::unique_ptr<RplidarA1> RplidarA1::open(std::string name, const std::filesystem::path& port, const RplidarConfig& config,
                                           const Clock& clock) {
  std::error_code ec;
  const auto status = std::filesystem::status(port, ec);
  if (!std::filesystem::exists(status)) {
    throw std::runtime_error(
        fmt::format("RPLIDAR port {} does not exist (is the lidar plugged in? a USB adapter shows as "
                    "/dev/ttyUSB0; the emulator's path is what tripodal-board-sim --lidar made)",
                    port.string()));
  }
  if (!std::filesystem::is_character_file(status)) {
    throw std::runtime_error(
        fmt::format("RPLIDAR port {} is not a tty (it is {}); expected a serial device such as /dev/ttyUSB0", port.string(),
                    std::filesystem::is_directory(status) ? "a directory" : "a regular file or other non-device"));
  }
  std::unique_ptr<SerialPort> serial;
  try {
    serial = std::make_unique<SerialPort>(port, clock, SerialSettings{rplidar::kBaud});
  } catch (const std::exception& e) {
    throw std::runtime_error(fmt::format("RPLIDAR port {} cannot be used as a tty: {}", port.string(), e.what()));
  }
  SerialPort& s = *serial;
  auto lidar = std::make_unique<RplidarA1>(std::move(name), s, config, nullptr, std::move(serial));
  const Duration budget = config.stop_settle + 3 * config.response_timeout;
  if (lidar->run_until_scanning(clock, clock.now() + budget) != State::scanning) {
    const std::string why =
        lidar->last_error().empty() ? fmt::format("not scanning after {:.2f} s", to_seconds(budget)) : lidar->last_error();
    throw std::runtime_error(fmt::format("RPLIDAR on {}: {}", port.string(), why));
  }
  lidar->rebase_ = true;  // the loop's clock may not be `clock`: its first poll re-anchors the times
  return lidar;
}

RplidarA1::State RplidarA1::run_until_scanning(const Clock& clock, Time deadline) noexcept {
  while (true) {
    const Time now = clock.now();
    step(now);
    if (state_ == State::scanning || state_ == State::failed || now >= deadline) return state_;
    clock.sleep_until(std::min(deadline, now + std::chrono::milliseconds(1)));
  }
}

void RplidarA1::shutdown() noexcept {
  if (!started_) return;
  send(rplidar::Command::stop);
  if (motor_ != nullptr) (void)motor_->set_motor(false);
  started_ = false;
}

std::vector<std::string> RplidarA1::take_faults() {
  std::vector<std::string> out;
  for (std::size_t i = 0; i < pending_.size(); ++i) {
    for (std::uint32_t n = pending_[i].exchange(0, std::memory_order_acq_rel); n > 0; --n) out.emplace_back(kFaultText[i]);
  }
  return out;
}

void RplidarA1::raise_fault(Fault fault) noexcept {
  pending_[static_cast<std::size_t>(fault)].fetch_add(1, std::memory_order_acq_rel);
  ++stats_.faults;
}

void RplidarA1::send(rplidar::Command cmd) noexcept {
  std::array<std::uint8_t, 4> out{};
  const std::size_t n = rplidar::encode_request(static_cast<std::uint8_t>(cmd), {}, out);
  (void)stream_.write(std::span<const std::uint8_t>(out.data(), n));
}

void RplidarA1::enter(State s, Time now) noexcept {
  state_ = s;
  entered_ = now;
  garbage_ = 0;
}

void RplidarA1::fail(Fault fault, std::string_view detail, Time now) noexcept {
  // A failure is reported once until the lidar scans again; the driver then starts over after
  // `timeout` (a lidar plugged in or power-cycled later comes back by itself).
  if (!reported_) {
    raise_fault(fault);
    reported_ = true;
  }
  try {
    error_.assign(detail);
  } catch (...) {
    error_.clear();
  }
  enter(fault == Fault::stalled ? State::stalled : State::failed, now);
}

void RplidarA1::consume(std::size_t n) noexcept {
  n = std::min(n, rx_size_);
  std::memmove(rx_.data(), rx_.data() + n, rx_size_ - n);
  rx_size_ -= n;
}

void RplidarA1::read_available() noexcept {
  while (rx_size_ < rx_.size()) {
    const std::ptrdiff_t n = stream_.read(std::span<std::uint8_t>(rx_.data() + rx_size_, rx_.size() - rx_size_), Time{});
    if (n < 0) {
      port_lost_ = true;
      return;
    }
    if (n == 0) return;
    rx_size_ += static_cast<std::size_t>(n);
  }
}

bool RplidarA1::take_descriptor(const rplidar::Descriptor& expected, std::string_view request, Time now) noexcept {
  // Anything before A5 5A is garbage: counted, and too much of it fails the request.
  std::size_t i = 0;
  while (i + 1 < rx_size_ && !(rx_[i] == rplidar::kDescriptorSync1 && rx_[i + 1] == rplidar::kDescriptorSync2)) ++i;
  if (i + 1 >= rx_size_ && rx_size_ > 0 && rx_[rx_size_ - 1] != rplidar::kDescriptorSync1) i = rx_size_;
  if (i > 0) {
    if (garbage_ == 0) {
      try {
        garbage_head_ = hex_prefix(std::span<const std::uint8_t>(rx_.data(), i));
      } catch (...) {
      }
    }
    garbage_ += i;
    consume(i);
  }
  if (garbage_ > config_.max_garbage_bytes) {
    try {
      fail(Fault::garbage,
           fmt::format("answered {} with {} bytes that hold no RPLIDAR response descriptor A5 5A (first: {}); "
                       "is this an RPLIDAR at 115200 baud?",
                       request, garbage_, garbage_head_),
           now);
    } catch (...) {
      fail(Fault::garbage, kFaultText[3], now);
    }
    return false;
  }
  if (rx_size_ < rplidar::kDescriptorBytes) {
    if (now - entered_ > config_.response_timeout) {
      try {
        fail(garbage_ > 0 ? Fault::garbage : Fault::no_answer,
             garbage_ > 0 ? fmt::format("answered {} with {} bytes of garbage (first: {}) and no response descriptor", request,
                                        garbage_, garbage_head_)
                          : fmt::format("no answer to {} within {:.2f} s: is the lidar connected, powered and at 115200 baud?",
                                        request, to_seconds(config_.response_timeout)),
             now);
      } catch (...) {
        fail(Fault::no_answer, kFaultText[2], now);
      }
    }
    return false;
  }
  const std::optional<rplidar::Descriptor> d =
      rplidar::decode_descriptor(std::span<const std::uint8_t, rplidar::kDescriptorBytes>(rx_.data(), rplidar::kDescriptorBytes));
  if (!d || *d != expected) {
    try {
      fail(Fault::garbage,
           fmt::format("answered {} with a response descriptor of {}, expected {}", request, d ? describe(*d) : std::string("?"),
                       describe(expected)),
           now);
    } catch (...) {
      fail(Fault::garbage, kFaultText[3], now);
    }
    return false;
  }
  consume(rplidar::kDescriptorBytes);
  return true;
}

void RplidarA1::on_poll(Time now) noexcept {
  step(now);
}

void RplidarA1::step(Time now) noexcept {
  if (rebase_) {
    rebase_ = false;
    entered_ = last_start_ = now;
    assembler_.restart();
  }
  if (!started_) {
    started_ = true;
    if (motor_ != nullptr && !motor_->set_motor(true)) motor_switchable_ = false;
    send(rplidar::Command::stop);  // a lidar still scanning from an earlier session stops
    rx_size_ = 0;
    enter(State::starting, now);
  }
  if (state_ == State::failed || state_ == State::stalled) {
    if (now - entered_ < config_.timeout) {
      if (!port_lost_) {
        read_available();  // drop what still comes
        rx_size_ = 0;
      }
      return;
    }
    if (port_lost_) {
      if (!stream_.reopen()) {
        enter(state_, now);
        return;
      }
      port_lost_ = false;
    }
    // Motor on again (whoever stopped it), the lidar out of any session, then the handshake.
    if (motor_ != nullptr && !motor_->set_motor(true)) motor_switchable_ = false;
    ++stats_.restarts;
    send(rplidar::Command::stop);
    rx_size_ = 0;
    enter(State::starting, now);
  }

  if (state_ == State::scanning) {
    std::array<std::uint8_t, 256> chunk{};
    while (true) {
      const std::ptrdiff_t n = stream_.read(chunk, Time{});
      if (n < 0) {
        port_lost_ = true;
        break;
      }
      if (n == 0) break;
      decoder_.feed(std::span<const std::uint8_t>(chunk.data(), static_cast<std::size_t>(n)), [&](const rplidar::Node& node) {
        if (node.start) last_start_ = now;
        if (assembler_.add(node, now)) {
          publish(assembler_.scan());
          ++stats_.scans;
          reported_ = false;
        }
      });
    }
    stats_.nodes = decoder_.stats().nodes;
    stats_.decoder_errors = decoder_.stats().errors;
    stats_.skipped_bytes = decoder_.stats().skipped_bytes;
    stats_.dropped = assembler_.dropped();
    if (port_lost_) {
      fail(Fault::port_lost, kFaultText[1], now);
    } else if (now - last_start_ >= config_.timeout) {
      try {
        fail(Fault::stalled,
             fmt::format("no revolution (start flag) for {:.2f} s: the lidar stopped spinning (motor off, DTR) or "
                         "sending",
                         to_seconds(now - last_start_)),
             now);
      } catch (...) {
        fail(Fault::stalled, kFaultText[0], now);
      }
    }
    return;
  }

  read_available();
  if (port_lost_) {
    fail(Fault::port_lost, kFaultText[1], now);
    return;
  }
  switch (state_) {
    case State::starting:
      rx_size_ = 0;  // what a lidar still scanning sent before it took STOP
      if (now - entered_ >= config_.stop_settle) {
        send(rplidar::Command::get_info);
        enter(State::awaiting_info, now);
        have_descriptor_ = false;
      }
      break;
    case State::awaiting_info:
      if (!have_descriptor_ && !(have_descriptor_ = take_descriptor(rplidar::kInfoDescriptor, "GET_INFO", now))) break;
      if (rx_size_ < rplidar::kInfoBytes) {
        if (now - entered_ > config_.response_timeout)
          fail(Fault::no_answer, "GET_INFO's answer stopped short of its 20 bytes", now);
        break;
      }
      info_ = rplidar::decode_info(std::span<const std::uint8_t, rplidar::kInfoBytes>(rx_.data(), rplidar::kInfoBytes));
      consume(rplidar::kInfoBytes);
      send(rplidar::Command::get_health);
      enter(State::awaiting_health, now);
      have_descriptor_ = false;
      break;
    case State::awaiting_health:
      if (!have_descriptor_ && !(have_descriptor_ = take_descriptor(rplidar::kHealthDescriptor, "GET_HEALTH", now))) break;
      if (rx_size_ < rplidar::kHealthBytes) {
        if (now - entered_ > config_.response_timeout)
          fail(Fault::no_answer, "GET_HEALTH's answer stopped short of its 3 bytes", now);
        break;
      }
      health_ = rplidar::decode_health(std::span<const std::uint8_t, rplidar::kHealthBytes>(rx_.data(), rplidar::kHealthBytes));
      consume(rplidar::kHealthBytes);
      if (health_.status == static_cast<std::uint8_t>(rplidar::HealthStatus::error)) {
        try {
          fail(Fault::health_error,
               fmt::format("health status error (error code 0x{:04X}): the A1 is in its protection stop; "
                           "power-cycle it or send RESET",
                           health_.error_code),
               now);
        } catch (...) {
          fail(Fault::health_error, kFaultText[4], now);
        }
        break;
      }
      if (health_.status > static_cast<std::uint8_t>(rplidar::HealthStatus::error)) {
        try {
          fail(Fault::garbage,
               fmt::format("answered GET_HEALTH with status {}, expected 0 (good), 1 (warning) or 2 (error)", health_.status),
               now);
        } catch (...) {
          fail(Fault::garbage, kFaultText[3], now);
        }
        break;
      }
      send(rplidar::Command::scan);
      enter(State::awaiting_scan, now);
      have_descriptor_ = false;
      break;
    case State::awaiting_scan:
      if (!take_descriptor(rplidar::kScanDescriptor, "SCAN", now)) break;
      decoder_.reset();
      assembler_.restart();
      enter(State::scanning, now);
      last_start_ = now;  // the motor's spin-up counts against the timeout
      decoder_.feed(std::span<const std::uint8_t>(rx_.data(), rx_size_), [&](const rplidar::Node& node) {
        if (node.start) last_start_ = now;
        (void)assembler_.add(node, now);
      });
      rx_size_ = 0;
      break;
    default:
      break;
  }
}

}  // namespace tripodal::board
