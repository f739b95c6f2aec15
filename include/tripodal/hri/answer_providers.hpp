// Providers of the values an RKMS answer names as {placeholders} (the time, the robot's battery,
// the weather): the application plugs in its sources; the HRI module (deliberate layer) asks them
// when it speaks an answer. The ones here are local and fixed, as in the demo (no network).
#pragma once

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/clock.hpp"

namespace tripodal {

/// One source of a value spoken in answers.
class AnswerProvider {
 public:
  virtual ~AnswerProvider() = default;
  /// The value as words ("ten past three", "82 percent"). Must not throw; a source that cannot
  /// answer says so in words ("unknown").
  [[nodiscard]] virtual std::string value() const = 0;
};

/// Providers by placeholder name.
class AnswerProviders {
 public:
  /// Adds or replaces the provider of {name}.
  void add(std::string name, std::unique_ptr<AnswerProvider> provider);
  [[nodiscard]] const AnswerProvider* find(std::string_view name) const noexcept;
  [[nodiscard]] std::vector<std::string> names() const;

 private:
  std::map<std::string, std::unique_ptr<AnswerProvider>, std::less<>> providers_;
};

/// {time}: the time of day as "14:05", from the injected clock: `start_of_day` is the time of day
/// at the clock's epoch (a robot sets it at start-up; the simulator and tests pick it).
class ClockTimeProvider final : public AnswerProvider {
 public:
  ClockTimeProvider(const Clock& clock, std::chrono::seconds start_of_day) noexcept
      : clock_(clock), start_of_day_(start_of_day) {}
  [[nodiscard]] std::string value() const override;

 private:
  const Clock& clock_;
  std::chrono::seconds start_of_day_;
};

/// {battery}: the charge as "82 percent", from a callback returning the fraction 0..1 (the
/// robot's battery resource); a value outside 0..1 or NaN is "unknown".
class BatteryProvider final : public AnswerProvider {
 public:
  explicit BatteryProvider(std::function<double()> charge_fraction) : charge_(std::move(charge_fraction)) {}
  [[nodiscard]] std::string value() const override;

 private:
  std::function<double()> charge_;
};

/// {weather}: a fixed local table, one description per day, cycling (the demo has no internet);
/// the day is counted from the clock's epoch plus `start_of_day`, like ClockTimeProvider.
class WeatherTableProvider final : public AnswerProvider {
 public:
  WeatherTableProvider(const Clock& clock, std::chrono::seconds start_of_day, std::vector<std::string> days);
  [[nodiscard]] std::string value() const override;

 private:
  const Clock& clock_;
  std::chrono::seconds start_of_day_;
  std::vector<std::string> days_;
};

/// A fixed text ({robot_name}, {hall}).
class FixedProvider final : public AnswerProvider {
 public:
  explicit FixedProvider(std::string text) : text_(std::move(text)) {}
  [[nodiscard]] std::string value() const override { return text_; }

 private:
  std::string text_;
};

}  // namespace tripodal
