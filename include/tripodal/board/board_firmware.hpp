// The control board's firmware as a simulation (seed 001, sections 3.2-3.4): what the STM32 does
// on its side of the UART, tick by tick, so the host side can be tested against it byte for byte
// (in process, or behind a pseudo-terminal in tripodal-board-sim). The world it senses and moves
// in is a BoardPlant: the embedded simulator's (sim/sim_board.hpp) in a run, a stub in tests.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

#include "tripodal/board/commands.hpp"
#include "tripodal/board/frame.hpp"
#include "tripodal/board/protocol_profile.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal::board {

/// What the board's sensors see now, filled by the plant (ranges in metres; +inf: no return).
struct PlantSensors {
  std::array<float, kMaxUltrasonic> ultrasonic_m{};
  std::array<float, kMaxInfrared> cliff_floor_m{};  ///< distance to the floor under each cliff sensor
  std::array<float, kMaxInfrared> wall_m{};
  std::uint8_t bumps = 0;  ///< bit i: bump switch i blocked
};

/// The world around the board: it moves the wheels at the speeds the motors reach and says what
/// the sensors see. Called from the firmware's tick, on its thread.
class BoardPlant {
 public:
  virtual ~BoardPlant() = default;
  /// The wheels' surface speeds (m/s) over the next tick; `now` is the board's time.
  virtual void drive(Time now, double left_m_s, double right_m_s) noexcept = 0;
  /// The sensors' view at `now`.
  virtual void sense(Time now, PlantSensors& out) noexcept = 0;
};

/// The incremental PID of equation 3-1: u(k) = Kp e(k) + Ki sum e(i) + Kd [e(k) - e(k-1)], its
/// output the PWM duty (-1..1) saturated; the sum stops growing while the duty is saturated.
struct SpeedPid {
  double kp = 0.8;   ///< duty per m/s
  double ki = 0.25;  ///< duty per m/s per period
  double kd = 0.05;  ///< duty per m/s change per period
  double speed_current_error_p = 0.0;  ///< e(k) (the thesis's variable names)
  double speed_current_error_i = 0.0;  ///< sum of e(i)
  double speed_current_error_d = 0.0;  ///< e(k) - e(k-1)
  double previous_error = 0.0;
  /// One motor period: the duty for the error between the required and the measured speed.
  double update(double required_m_s, double measured_m_s) noexcept;
  void reset() noexcept;
};

struct FirmwareConfig {
  /// The dialect the board speaks (null: the thesis's, configs/board/thesis.yaml).
  std::shared_ptr<const ProtocolProfile> protocol;
  Duration tick{std::chrono::milliseconds(1)};            ///< the timer interrupt
  Duration motor_period{std::chrono::milliseconds(10)};   ///< encoder speed and PID refresh
  Duration link_timeout{std::chrono::milliseconds(200)};  ///< no valid request this long: motors stop
  /// The UART's idle line: a frame whose bytes stop coming this long (a byte dropped on the line,
  /// a corrupt Length) is given up, so the next request is not swallowed as its body.
  Duration frame_idle_timeout{std::chrono::milliseconds(5)};
  Duration battery_period{std::chrono::seconds(3)};       ///< section 3.4.1
  double pulses_per_m = 5000.0;    ///< encoder pulses per metre of wheel travel
  double max_wheel_speed_m_s = 1.0;  ///< at 100 % duty and a full pack (16.8 V)
  double motor_time_constant_s = 0.05;
  SpeedPid pid;
  double battery_capacity_ah = 10.4;  ///< section 2.3.1
  double battery_initial = 1.0;       ///< state of charge, 0..1
  double idle_current_a = 0.4;        ///< the boards and sensors
  double motor_current_a = 2.5;       ///< each motor at 100 % duty
  double uv_lamp_current_a = 1.2;
  double atomizer_current_a = 0.6;
  double fan_current_a = 0.3;
  double charger_current_a = 5.2;
  double tank_l = 1.5;                 ///< disinfectant tank
  double tank_initial_l = 1.5;
  double atomizer_l_per_h = 0.6;
  std::size_t ultrasonic_count = 3;    ///< section 3.4.2: configurable
  std::size_t cliff_count = 3;
  std::size_t wall_count = 2;
  /// Section 3.4.3: the cliff judgment compares the difference of two successive ADC readings of
  /// a cliff sensor with a threshold pre-fixed in the data section. A fall of the reading by more
  /// than the threshold (the floor went away) sets the sensor's cliff bit; a rise by more than it
  /// (floor again) clears it. The threshold is what the reading falls from the floor the sensor
  /// is mounted over (cliff_floor_m) to a floor cliff_threshold_m away.
  double cliff_floor_m = 0.02;      ///< flat floor under a cliff sensor (its mount height)
  double cliff_threshold_m = 0.05;  ///< a step down to a floor this far gives the threshold
};

/// The Sharp GP2Y0A51SK0F infrared sensor's output (section 2.4.2: 2-15 cm) as the STM32's 12-bit
/// ADC reads it (3.3 V reference): the voltage falls as the inverse of the distance, about 2.0 V
/// at 2 cm and 0.4 V at 15 cm, and stays at its 15 cm level beyond the range (no return: +inf).
[[nodiscard]] std::uint16_t cliff_sensor_adc(double distance_m) noexcept;
/// The cliff threshold (ADC counts) of a configuration: cliff_sensor_adc(cliff_floor_m) -
/// cliff_sensor_adc(cliff_threshold_m).
[[nodiscard]] int cliff_adc_threshold(const FirmwareConfig& config) noexcept;

/// Battery: 16.8 V full, 12.0 V empty (must charge), linear in the state of charge.
inline constexpr double kBatteryFullV = 16.8;
inline constexpr double kBatteryEmptyV = 12.0;

/// What the firmware did, for tests and reports.
struct FirmwareCounters {
  std::uint64_t requests = 0;        ///< valid requests answered
  std::uint64_t error_responses = 0;
  std::uint64_t watchdog_trips = 0;  ///< link lost: motors stopped
  std::uint64_t voice_prompts = 0;
  std::uint64_t resyncs = 0;
};

/// The firmware. Threading: one thread calls run_until (the tool's loop, or the simulation driver).
class BoardFirmware {
 public:
  /// `link` is the UART (not owned); `plant` the world (not owned). Power-on at `start`.
  BoardFirmware(const FirmwareConfig& config, ByteStream& link, BoardPlant& plant, Time start = Time{});

  /// Runs the 1 ms ticks due up to `now`: each one reads the UART, answers complete requests,
  /// and runs the device loop (link watchdog, motors, battery, tank, sensors). Never throws or
  /// allocates.
  void run_until(Time now) noexcept;
  /// The UART's receive interrupt: runs the ticks due up to `now`, then answers the requests
  /// whose bytes have arrived at once, not at the next tick (a real board answers on reception;
  /// a 1 ms tick alone adds up to 1 ms to every round trip). Never throws or allocates.
  void on_receive(Time now) noexcept;

  // --- the panel and the environment (tests, the tool) ---
  void set_buttons(std::uint8_t held) noexcept;
  void set_charging(bool charging) noexcept { charging_ = charging; }
  void set_tank_l(double litres) noexcept { tank_l_ = litres; }
  void set_state_of_charge(double soc) noexcept { soc_ = soc; }

  // --- state ---
  [[nodiscard]] Time now() const noexcept { return now_; }
  [[nodiscard]] bool synchronised() const noexcept { return synchronised_; }
  [[nodiscard]] bool link_lost() const noexcept { return link_lost_; }
  [[nodiscard]] bool emergency_stop() const noexcept { return (buttons_ & kButtonEmergencyStop) != 0; }
  [[nodiscard]] bool uv_lamp() const noexcept { return uv_lamp_; }
  [[nodiscard]] const FirmwareConfig& config() const noexcept { return config_; }
  [[nodiscard]] bool atomizer() const noexcept { return atomizer_; }
  [[nodiscard]] bool fan() const noexcept { return fan_; }
  [[nodiscard]] std::uint8_t last_voice_track() const noexcept { return voice_track_; }
  [[nodiscard]] std::string_view lcd_line(std::size_t line) const noexcept;
  [[nodiscard]] double wheel_speed_m_s(std::size_t wheel) const noexcept { return motors_[wheel].speed_m_s; }
  [[nodiscard]] double duty(std::size_t wheel) const noexcept { return motors_[wheel].duty; }
  [[nodiscard]] double required_m_s(std::size_t wheel) const noexcept { return motors_[wheel].required_m_s; }
  [[nodiscard]] std::int32_t pulses(std::size_t wheel) const noexcept { return motors_[wheel].pulses; }
  [[nodiscard]] double state_of_charge() const noexcept { return soc_; }
  [[nodiscard]] double battery_current_a() const noexcept { return current_a_; }
  /// The charge the load has drawn since power-on (Ah), whatever the charger put back.
  [[nodiscard]] double charge_drawn_ah() const noexcept { return drawn_as_ / 3600.0; }
  [[nodiscard]] BatteryState battery() const noexcept { return battery_; }
  [[nodiscard]] double tank_l() const noexcept { return tank_l_; }
  [[nodiscard]] double disinfectant_used_l() const noexcept { return used_l_; }
  [[nodiscard]] const FirmwareCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const DecoderStats& decoder_stats() const noexcept { return decoder_.stats(); }
  [[nodiscard]] const DecodeError& last_decode_error() const noexcept { return decoder_.last_error(); }
  [[nodiscard]] const ProtocolProfile& protocol() const noexcept { return profile_; }
  /// When the last valid request was decoded (what the watchdog measures from).
  [[nodiscard]] Time last_request_at() const noexcept { return last_request_; }
  /// When the watchdog last stopped the motors.
  [[nodiscard]] Time link_lost_at() const noexcept { return link_lost_at_; }

 private:
  struct Motor {
    double required_m_s = 0.0;
    double speed_m_s = 0.0;  // the wheel's actual speed (the motor model)
    double duty = 0.0;
    double measured_m_s = 0.0;  // from the encoder over the last motor period
    double travel_pulses = 0.0;  // fractional pulses
    std::int32_t pulses = 0;
    std::int32_t pulses_at_period = 0;
    SpeedPid pid;
  };
  void tick() noexcept;
  void receive() noexcept;
  void abandon_idle_frame() noexcept;
  void handle(const FrameView& frame) noexcept;
  void answer(std::uint8_t resp, std::span<const std::uint8_t> payload) noexcept;
  void answer_error(ErrorCode code, std::uint8_t cmd) noexcept;
  void serve(Command cmd, std::uint8_t id, std::span<const std::uint8_t> payload) noexcept;
  void device_loop() noexcept;
  void update_motors() noexcept;
  void stop_motors() noexcept;
  void sample_battery() noexcept;
  void judge_cliffs() noexcept;
  [[nodiscard]] std::uint32_t sensor_bitmap() const noexcept;
  [[nodiscard]] std::uint8_t status_flags() const noexcept;
  [[nodiscard]] EncoderState encoders() const noexcept;

  FirmwareConfig config_;
  std::shared_ptr<const ProtocolProfile> protocol_;
  const ProtocolProfile& profile_;
  ByteStream& link_;
  BoardPlant& plant_;
  FrameDecoder decoder_;
  std::uint64_t decoder_errors_seen_ = 0;
  std::array<std::uint8_t, 256> rx_{};
  std::array<std::uint8_t, kMaxFrameBytes> tx_{};
  Time now_{};
  std::uint32_t tick_ms_ = 0;
  Time last_request_{};
  Time last_byte_{};  // the latest byte received: the idle line's start
  Time next_motor_{};
  Time next_battery_{};
  Time link_lost_at_{};
  bool synchronised_ = false;
  bool link_lost_ = false;
  std::array<Motor, 2> motors_{};
  PlantSensors sensors_{};
  int cliff_threshold_adc_ = 0;
  std::array<std::uint16_t, kMaxInfrared> cliff_adc_{};  // reading t, against which t+1 is judged
  std::uint32_t cliff_bits_ = 0;                         // latched judgments (kCliffShift + i)
  std::uint8_t buttons_ = 0;
  std::uint8_t pressed_ = 0;
  bool uv_lamp_ = false;
  bool atomizer_ = false;
  bool fan_ = false;
  std::uint8_t voice_track_ = 0;
  std::array<std::array<char, kMaxLcdText + 1>, 4> lcd_{};
  double soc_ = 1.0;
  double current_a_ = 0.0;
  bool charging_ = false;
  double drawn_as_ = 0.0;
  BatteryState battery_{};
  double tank_l_ = 0.0;
  double used_l_ = 0.0;
  FirmwareCounters counters_;
};

/// The firmware in real time between two ticks: waits on `fd` (the line's descriptor: the
/// pseudo-terminal's master) until bytes arrive or `deadline` passes on `clock`, and answers what
/// arrived at once (BoardFirmware::on_receive). True when bytes arrived (the caller loops until its
/// tick is due); false at the deadline. With fd < 0 (a stream without one), or a descriptor that
/// hung up, it sleeps until the deadline and the requests wait for the next tick.
bool serve_until(BoardFirmware& firmware, int fd, const Clock& clock, Time deadline) noexcept;

}  // namespace tripodal::board
