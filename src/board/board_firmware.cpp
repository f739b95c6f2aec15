#include "tripodal/board/board_firmware.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace tripodal::board {
namespace {

std::uint16_t to_mm(float metres) noexcept {
  if (!std::isfinite(metres) || metres < 0.0F || metres * 1000.0F >= 65535.0F) return kNoEcho;
  return static_cast<std::uint16_t>(std::lround(metres * 1000.0F));
}

std::int16_t to_mm_s(double m_s) noexcept {
  return static_cast<std::int16_t>(std::clamp(std::lround(m_s * 1000.0), -32768L, 32767L));
}

}  // namespace

double SpeedPid::update(double required_m_s, double measured_m_s) noexcept {
  const double e = required_m_s - measured_m_s;
  speed_current_error_p = e;
  speed_current_error_i += e;
  speed_current_error_d = e - previous_error;
  previous_error = e;
  const double u = kp * speed_current_error_p + ki * speed_current_error_i + kd * speed_current_error_d;
  if (u > 1.0 || u < -1.0) {
    // Saturated PWM: the sum would only wind up; keep it where it was (conditional integration).
    speed_current_error_i -= e;
    return std::clamp(u, -1.0, 1.0);
  }
  return u;
}

void SpeedPid::reset() noexcept {
  speed_current_error_p = speed_current_error_i = speed_current_error_d = previous_error = 0.0;
}

BoardFirmware::BoardFirmware(const FirmwareConfig& config, ByteStream& link, BoardPlant& plant, Time start)
    : config_(config),
      protocol_(config.protocol ? config.protocol : resolve_protocol_profile("", {})),
      profile_(*protocol_),
      link_(link),
      plant_(plant),
      decoder_(profile_.frame, FrameSide::requests),
      now_(start), last_request_(start), next_motor_(start),
      next_battery_(start), soc_(config.battery_initial), tank_l_(config.tank_initial_l) {
  config_.ultrasonic_count = std::min(config_.ultrasonic_count, kMaxUltrasonic);
  config_.cliff_count = std::min(config_.cliff_count, kMaxInfrared);
  config_.wall_count = std::min(config_.wall_count, kMaxInfrared - config_.cliff_count);
  for (Motor& m : motors_) m.pid = config_.pid;
  // The reading "before the first" is the flat floor the data section assumes: a robot switched on
  // over a drop sees it at the first measurement.
  cliff_threshold_adc_ = cliff_adc_threshold(config_);
  cliff_adc_.fill(cliff_sensor_adc(config_.cliff_floor_m));
  sample_battery();
}

void BoardFirmware::run_until(Time now) noexcept {
  while (now_ + config_.tick <= now) {
    now_ += config_.tick;
    tick();
  }
}

void BoardFirmware::on_receive(Time now) noexcept {
  run_until(now);
  receive();
}

bool serve_until(BoardFirmware& firmware, int fd, const Clock& clock, Time deadline) noexcept {
  const Time now = clock.now();
  if (now >= deadline) return false;
  if (!wait_readable(fd, clock.wall_duration(deadline - now))) {
    // A wake-up without bytes before the deadline (a signal, a hung-up line): the rest of the wait
    // as a sleep, so a caller looping until its tick never spins. After the usual timeout the
    // deadline has passed: no second system call, once per tick.
    if (clock.now() < deadline) clock.sleep_until(deadline);
    return false;
  }
  firmware.on_receive(clock.now());
  return true;
}

void BoardFirmware::tick() noexcept {
  ++tick_ms_;
  receive();
  device_loop();
}

void BoardFirmware::receive() noexcept {
  while (true) {
    // Deadline 0: the firmware's loop polls the UART, it never waits on it.
    const std::ptrdiff_t n = link_.read(rx_, Time{});
    if (n <= 0) {
      if (decoder_.partial() && now_ - last_byte_ >= config_.frame_idle_timeout) abandon_idle_frame();
      return;
    }
    last_byte_ = now_;
    std::span<const std::uint8_t> in(rx_.data(), static_cast<std::size_t>(n));
    while (true) {
      const FrameDecoder::Result r = decoder_.decode(in);
      const DecoderStats& s = decoder_.stats();
      // Section 3.3.3: a compromised packet is answered with its error code.
      const std::uint64_t errors = s.checksum + s.oversize;
      if (errors != decoder_errors_seen_) {
        const bool overflow = decoder_.last_error().kind == DecodeErrorKind::oversize;
        decoder_errors_seen_ = errors;
        answer_error(overflow ? ErrorCode::overflow : ErrorCode::checksum, 0);
      }
      if (r.frame) handle(decoder_.frame());
      in = in.subspan(r.consumed);
      if (!r.frame && in.empty()) break;
    }
  }
}

// A truncated frame gets no answer (the host times its request out); the frames found in its bytes
// are answered as usual, and the errors found on the way are not answered late.
void BoardFirmware::abandon_idle_frame() noexcept {
  FrameDecoder::Result r = decoder_.abandon_partial();
  while (r.frame) {
    handle(decoder_.frame());
    r = decoder_.decode({});
  }
  decoder_errors_seen_ = decoder_.stats().checksum + decoder_.stats().oversize;
}

void BoardFirmware::handle(const FrameView& frame) noexcept {
  last_request_ = now_;  // the link watchdog's "last decoded packet"
  const std::span<const std::uint8_t> body = frame.body;
  // Figure 3-5: SYNC echoed unchanged, then synchronisation, TYPE, the command table.
  const std::optional<std::uint8_t> sync_id = profile_.id(Command::sync);
  if (body.size() >= 2 && sync_id && body[1] == *sync_id) {
    // Section 3.3.3: the unchanged packet back (a profile without the echo answers with Resp).
    if (profile_.sync_echo) {
      if (!link_.write(frame.bytes)) return;
    } else {
      const std::size_t n = encode_response(*sync_id, {}, tx_, profile_.frame);
      if (n == 0 || !link_.write(std::span<const std::uint8_t>(tx_.data(), n))) return;
    }
    // A SYNC (re)starts the session: a master that synchronises again has lost track of the
    // board, so the wheels stop until it drives them again.
    stop_motors();
    if (!synchronised_) ++counters_.resyncs;
    synchronised_ = true;
    link_lost_ = false;
    ++counters_.requests;
    return;
  }
  const std::uint8_t cmd = body.size() >= 2 ? body[1] : 0;
  if (!synchronised_) return answer_error(ErrorCode::not_synchronised, cmd);
  if (body[0] != profile_.frame.type_byte) return answer_error(ErrorCode::wrong_type, cmd);
  if (body.size() < 2) return answer_error(ErrorCode::bad_payload, 0);  // TYPE without CMD
  const std::optional<Command> command = profile_.command_of(cmd);
  if (!command) return answer_error(ErrorCode::unknown_command, cmd);
  serve(*command, cmd, body.subspan(2));
}

void BoardFirmware::answer(std::uint8_t resp, std::span<const std::uint8_t> payload) noexcept {
  const std::size_t n = encode_response(resp, payload, tx_, profile_.frame);
  if (n > 0 && link_.write(std::span<const std::uint8_t>(tx_.data(), n)) && resp != profile_.error_resp) ++counters_.requests;
}

void BoardFirmware::answer_error(ErrorCode code, std::uint8_t cmd) noexcept {
  const std::array<std::uint8_t, 2> payload{profile_.code(code), cmd};
  ++counters_.error_responses;
  answer(profile_.error_resp, payload);
}

void BoardFirmware::serve(Command cmd, std::uint8_t c, std::span<const std::uint8_t> payload) noexcept {
  std::array<std::uint8_t, 64> out{};
  ByteWriter w(out);
  // A profile whose layouts differ from the model's (order, types, scales): payloads transcoded.
  const CommandSpec* spec = profile_.spec(cmd);
  std::array<std::uint8_t, kMaxLength> staged{};
  if (spec != nullptr && spec->request_transcoded) {
    const std::ptrdiff_t n = transcode(spec->request, builtin_command(cmd).request, payload, staged);
    if (n < 0) return answer_error(ErrorCode::bad_payload, c);
    payload = std::span<const std::uint8_t>(staged.data(), static_cast<std::size_t>(n));
  }
  const auto expect = [&](std::size_t size) {
    if (payload.size() == size) return true;
    answer_error(ErrorCode::bad_payload, c);
    return false;
  };
  const auto set_speeds = [&](const WheelSpeeds& s) {
    // The emergency stop holds the motors whatever the master asks.
    const bool hold = emergency_stop();
    motors_[0].required_m_s = hold ? 0.0 : s.left_mm_s / 1000.0;
    motors_[1].required_m_s = hold ? 0.0 : s.right_mm_s / 1000.0;
  };
  switch (cmd) {
    case Command::sync: break;  // handled before the table
    case Command::status:
      if (!expect(0)) return;
      pack(w, BoardStatus{status_flags(), tick_ms_, static_cast<std::uint16_t>(counters_.requests),
                          static_cast<std::uint16_t>(decoder_.stats().errors())});
      break;
    case Command::set_wheel_speeds:
      if (!expect(4)) return;
      set_speeds(*unpack_wheel_speeds(payload));
      break;
    case Command::read_encoders:
      if (!expect(0)) return;
      pack(w, encoders());
      break;
    case Command::drive:
      if (!expect(4)) return;
      set_speeds(*unpack_wheel_speeds(payload));
      pack(w, DriveState{encoders(), sensor_bitmap(), buttons_, status_flags()});
      break;
    case Command::battery:
      if (!expect(0)) return;
      pack(w, battery_);
      break;
    case Command::ultrasonic:
      if (!expect(0)) return;
      w.u8(static_cast<std::uint8_t>(config_.ultrasonic_count));
      for (std::size_t i = 0; i < config_.ultrasonic_count; ++i) w.u16(to_mm(sensors_.ultrasonic_m[i]));
      break;
    case Command::infrared:
      if (!expect(0)) return;
      w.u8(static_cast<std::uint8_t>(config_.cliff_count));
      w.u8(static_cast<std::uint8_t>(config_.wall_count));
      for (std::size_t i = 0; i < config_.cliff_count; ++i) w.u16(to_mm(sensors_.cliff_floor_m[i]));
      for (std::size_t i = 0; i < config_.wall_count; ++i) w.u16(to_mm(sensors_.wall_m[i]));
      break;
    case Command::bump:
      if (!expect(0)) return;
      w.u32(sensor_bitmap());
      break;
    case Command::liquid_level: {
      if (!expect(0)) return;
      const double fraction = std::clamp(tank_l_ / config_.tank_l, 0.0, 1.0);
      w.u8(static_cast<std::uint8_t>(std::lround(fraction * 100.0)));
      w.u8(tank_l_ <= 0.0 ? 1 : 0);
      break;
    }
    case Command::buttons:
      if (!expect(0)) return;
      w.u8(buttons_);
      w.u8(pressed_);
      pressed_ = 0;
      break;
    case Command::atomizer:
      if (!expect(2)) return;
      // Figure 3-12: no atomizing without disinfectant in the tank.
      atomizer_ = payload[0] != 0 && tank_l_ > 0.0;
      fan_ = payload[1] != 0;
      break;
    case Command::uv_lamp:
      if (!expect(1)) return;
      uv_lamp_ = payload[0] != 0;
      break;
    case Command::voice:
      if (!expect(1)) return;
      voice_track_ = payload[0];
      ++counters_.voice_prompts;
      break;
    case Command::lcd_text: {
      if (payload.empty() || payload.size() > kMaxLcdText + 1 || payload[0] >= lcd_.size()) {
        answer_error(ErrorCode::bad_payload, c);
        return;
      }
      auto& line = lcd_[payload[0]];
      line.fill('\0');
      std::memcpy(line.data(), payload.data() + 1, payload.size() - 1);
      break;
    }
  }
  if (spec != nullptr && spec->response_transcoded) {
    const std::ptrdiff_t n = transcode(builtin_command(cmd).response, spec->response, w.written(), staged);
    if (n >= 0) answer(c, std::span<const std::uint8_t>(staged.data(), static_cast<std::size_t>(n)));
    return;
  }
  answer(c, w.written());
}

std::string_view BoardFirmware::lcd_line(std::size_t line) const noexcept {
  if (line >= lcd_.size()) return {};
  return std::string_view(lcd_[line].data());
}

void BoardFirmware::set_buttons(std::uint8_t held) noexcept {
  pressed_ |= static_cast<std::uint8_t>(held & ~buttons_);
  buttons_ = held;
  if (emergency_stop()) stop_motors();  // brakes at once, not at the next motor period
}

void BoardFirmware::stop_motors() noexcept {
  for (Motor& m : motors_) {
    m.required_m_s = 0.0;
    m.duty = 0.0;
    m.pid.reset();
  }
}

void BoardFirmware::device_loop() noexcept {
  // Section 3.4.4: the tick of the last decoded packet against the tick now.
  if (synchronised_ && now_ - last_request_ > config_.link_timeout) {
    synchronised_ = false;
    link_lost_ = true;
    link_lost_at_ = now_;
    ++counters_.watchdog_trips;
    stop_motors();
  }
  const double dt = to_seconds(config_.tick);
  const double voltage = kBatteryEmptyV + (kBatteryFullV - kBatteryEmptyV) * soc_;
  const double vmax = config_.max_wheel_speed_m_s * voltage / kBatteryFullV;
  const double alpha = std::min(1.0, dt / config_.motor_time_constant_s);
  double motor_load = 0.0;
  for (Motor& m : motors_) {
    const double target = soc_ > 0.0 ? m.duty * vmax : 0.0;
    m.speed_m_s += (target - m.speed_m_s) * alpha;
    m.travel_pulses += m.speed_m_s * dt * config_.pulses_per_m;
    const double whole = std::trunc(m.travel_pulses);
    m.pulses = static_cast<std::int32_t>(static_cast<std::uint32_t>(m.pulses) + static_cast<std::uint32_t>(static_cast<std::int64_t>(whole)));
    m.travel_pulses -= whole;
    motor_load += std::abs(m.duty);
  }
  plant_.drive(now_, motors_[0].speed_m_s, motors_[1].speed_m_s);
  if (now_ >= next_motor_) {
    next_motor_ += config_.motor_period;
    update_motors();
    plant_.sense(now_, sensors_);
    judge_cliffs();
  }

  current_a_ = config_.idle_current_a + motor_load * config_.motor_current_a + (uv_lamp_ ? config_.uv_lamp_current_a : 0.0) +
               (atomizer_ ? config_.atomizer_current_a : 0.0) + (fan_ ? config_.fan_current_a : 0.0);
  const double capacity_as = config_.battery_capacity_ah * 3600.0;
  // On the charger the pack takes what the charger gives beyond the load (constant current, no
  // taper near full): 5.2 A into 10.4 Ah with the boards' 0.4 A is empty to full in 2.2 h.
  drawn_as_ += current_a_ * dt;
  const double net_a = (charging_ ? config_.charger_current_a : 0.0) - current_a_;
  soc_ = std::clamp(soc_ + net_a * dt / capacity_as, 0.0, 1.0);
  if (now_ >= next_battery_) {
    next_battery_ += config_.battery_period;
    sample_battery();
  }
  if (atomizer_) {
    const double used = std::min(tank_l_, config_.atomizer_l_per_h * dt / 3600.0);
    tank_l_ -= used;
    used_l_ += used;
    if (tank_l_ <= 0.0) {
      tank_l_ = 0.0;
      atomizer_ = false;  // dry: the sheet must not run empty
    }
  }
}

void BoardFirmware::update_motors() noexcept {
  const double period_s = to_seconds(config_.motor_period);
  for (Motor& m : motors_) {
    const std::int32_t delta = static_cast<std::int32_t>(static_cast<std::uint32_t>(m.pulses) - static_cast<std::uint32_t>(m.pulses_at_period));
    m.pulses_at_period = m.pulses;
    m.measured_m_s = delta / config_.pulses_per_m / period_s;
    const bool reversing = m.required_m_s * m.measured_m_s < 0.0 && std::abs(m.measured_m_s) > 0.02;
    if (m.required_m_s == 0.0 || reversing) {
      // Section 3.4.5: to stop, or before changing direction, the motor stops first.
      m.duty = 0.0;
      m.pid.reset();
    } else {
      m.duty = m.pid.update(m.required_m_s, m.measured_m_s);
    }
  }
}

void BoardFirmware::sample_battery() noexcept {
  battery_.percent = static_cast<std::uint8_t>(std::lround(std::clamp(soc_, 0.0, 1.0) * 100.0));
  battery_.charging = charging_;
  battery_.voltage_mv = static_cast<std::uint16_t>(std::lround((kBatteryEmptyV + (kBatteryFullV - kBatteryEmptyV) * soc_) * 1000.0));
}

std::uint16_t cliff_sensor_adc(double distance_m) noexcept {
  // V = a / (d + b) through (2 cm, 2.0 V) and (15 cm, 0.4 V); beyond 15 cm the reading stays at
  // its far end, as there is nothing nearer to see.
  constexpr double kA = 0.065, kB = 0.0125, kMin = 0.02, kMax = 0.15, kVref = 3.3;
  const double d = std::isnan(distance_m) ? kMax : std::clamp(distance_m, kMin, kMax);
  return static_cast<std::uint16_t>(std::lround(kA / (d + kB) / kVref * 4095.0));
}

int cliff_adc_threshold(const FirmwareConfig& config) noexcept {
  return static_cast<int>(cliff_sensor_adc(config.cliff_floor_m)) - static_cast<int>(cliff_sensor_adc(config.cliff_threshold_m));
}

void BoardFirmware::judge_cliffs() noexcept {
  for (std::size_t i = 0; i < config_.cliff_count; ++i) {
    const std::uint16_t now = cliff_sensor_adc(sensors_.cliff_floor_m[i]);
    const int difference = static_cast<int>(cliff_adc_[i]) - static_cast<int>(now);  // > 0: the floor went farther
    const std::uint32_t bit = 1U << (kCliffShift + i);
    if (difference > cliff_threshold_adc_) cliff_bits_ |= bit;
    if (-difference > cliff_threshold_adc_) cliff_bits_ &= ~bit;
    cliff_adc_[i] = now;
  }
}

std::uint32_t BoardFirmware::sensor_bitmap() const noexcept {
  return (static_cast<std::uint32_t>(sensors_.bumps) << kBumpShift) | cliff_bits_;
}

std::uint8_t BoardFirmware::status_flags() const noexcept {
  std::uint8_t f = 0;
  if (synchronised_) f |= kStatusSynchronised;
  if (link_lost_) f |= kStatusLinkLost;
  if (emergency_stop()) f |= kStatusEmergencyStop;
  if (uv_lamp_) f |= kStatusUvLamp;
  if (atomizer_) f |= kStatusAtomizer;
  return f;
}

EncoderState BoardFirmware::encoders() const noexcept {
  return EncoderState{motors_[0].pulses, motors_[1].pulses, to_mm_s(motors_[0].measured_m_s), to_mm_s(motors_[1].measured_m_s)};
}

}  // namespace tripodal::board
