#include "tripodal/hri/answer_providers.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>

namespace tripodal {

void AnswerProviders::add(std::string name, std::unique_ptr<AnswerProvider> provider) {
  if (!provider) throw std::invalid_argument("AnswerProviders::add: no provider given for {" + name + "}");
  providers_[std::move(name)] = std::move(provider);
}

const AnswerProvider* AnswerProviders::find(std::string_view name) const noexcept {
  const auto it = providers_.find(name);
  return it == providers_.end() ? nullptr : it->second.get();
}

std::vector<std::string> AnswerProviders::names() const {
  std::vector<std::string> out;
  out.reserve(providers_.size());
  for (const auto& [name, _] : providers_) out.push_back(name);
  return out;
}

namespace {

constexpr std::int64_t kSecondsPerDay = std::int64_t{24} * 3600;

// Seconds since the midnight before the clock's epoch.
std::int64_t seconds_of(const Clock& clock, std::chrono::seconds start_of_day) {
  const auto since_epoch = std::chrono::duration_cast<std::chrono::seconds>(clock.now().time_since_epoch());
  return start_of_day.count() + since_epoch.count();
}

}  // namespace

std::string ClockTimeProvider::value() const {
  const std::int64_t s = ((seconds_of(clock_, start_of_day_) % kSecondsPerDay) + kSecondsPerDay) % kSecondsPerDay;
  char text[8];
  std::snprintf(text, sizeof text, "%02d:%02d", static_cast<int>(s / 3600), static_cast<int>((s / 60) % 60));
  return text;
}

std::string BatteryProvider::value() const {
  const double f = charge_ ? charge_() : std::nan("");
  if (!(f >= 0.0 && f <= 1.0)) return "unknown";
  return std::to_string(static_cast<int>(std::lround(f * 100.0))) + " percent";
}

WeatherTableProvider::WeatherTableProvider(const Clock& clock, std::chrono::seconds start_of_day,
                                           std::vector<std::string> days)
    : clock_(clock), start_of_day_(start_of_day), days_(std::move(days)) {
  if (days_.empty()) throw std::invalid_argument("WeatherTableProvider: the table needs at least one day");
}

std::string WeatherTableProvider::value() const {
  const std::int64_t day = seconds_of(clock_, start_of_day_) / kSecondsPerDay;
  const auto n = static_cast<std::int64_t>(days_.size());
  return days_[static_cast<std::size_t>(((day % n) + n) % n)];
}

}  // namespace tripodal
