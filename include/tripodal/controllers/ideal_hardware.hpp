// A HardwareInterface whose wheels follow their commands exactly: the test double of the
// controllers' tests and benchmarks, and the simplest hardware for a kinematic simulation.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <span>

#include "tripodal/controllers/controller.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal {

/// Up to kMaxWheels ideal wheels. Every write first advances the wheel positions by the previous
/// command over `period` (the time the previous command was applied), then stores the new one:
/// read positions are those at the time of the write. Fault injection: refuse writes, report
/// stale reads. No allocation.
class IdealWheelHardware final : public HardwareInterface {
 public:
  static constexpr std::size_t kMaxWheels = 8;
  IdealWheelHardware(std::size_t wheels, Duration period) noexcept
      : wheels_(std::min(wheels, kMaxWheels)), period_s_(to_seconds(period)) {}

  [[nodiscard]] std::size_t wheel_count() const noexcept override { return wheels_; }
  bool write_wheel_velocities(std::span<const double> wheel_rad_s) noexcept override {
    if (refuse_writes_ || wheel_rad_s.size() != wheels_) return false;
    for (std::size_t i = 0; i < wheels_; ++i) {
      position_[i] += command_[i] * period_s_;
      command_[i] = wheel_rad_s[i];
    }
    ++writes_;
    return true;
  }
  bool read_wheel_states(std::span<double> velocity_rad_s, std::span<double> position_rad) noexcept override {
    if (stale_reads_ || velocity_rad_s.size() != wheels_ || position_rad.size() != wheels_) return false;
    std::copy_n(command_.begin(), wheels_, velocity_rad_s.begin());
    std::copy_n(position_.begin(), wheels_, position_rad.begin());
    return true;
  }

  /// The period over which each command is applied (the loop's period).
  void set_period(Duration period) noexcept { period_s_ = to_seconds(period); }
  void set_refuse_writes(bool refuse) noexcept { refuse_writes_ = refuse; }
  void set_stale_reads(bool stale) noexcept { stale_reads_ = stale; }
  [[nodiscard]] std::span<const double> commands() const noexcept { return {command_.data(), wheels_}; }
  [[nodiscard]] std::span<const double> positions() const noexcept { return {position_.data(), wheels_}; }
  [[nodiscard]] std::size_t writes() const noexcept { return writes_; }

 private:
  std::size_t wheels_;
  double period_s_;
  std::array<double, kMaxWheels> command_{};
  std::array<double, kMaxWheels> position_{};
  bool refuse_writes_ = false;
  bool stale_reads_ = false;
  std::size_t writes_ = 0;
};

}  // namespace tripodal
