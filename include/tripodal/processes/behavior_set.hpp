// BehaviorSet: the robot's behaviors (CBehavior instances created from the behavior registry) as
// the process supervisor drives them through the BehaviorHost seam. The supervisor activates and
// deactivates them; the control loop steps the active ones (step_active) and fuses their commands.
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/core/clock.hpp"
#include "tripodal/processes/behavior_host.hpp"

namespace tripodal {

/// Owns one CBehavior per name. Single-threaded: the thread that steps the supervisor also steps
/// the behaviors (in simulation and replay, the caller's thread).
class BehaviorSet final : public BehaviorHost {
 public:
  /// `clock` times the status reports (for the supervisor's watchdog).
  explicit BehaviorSet(const Clock& clock) : clock_(clock) {}

  /// Adds a behavior under its manifest name. Throws std::invalid_argument for a duplicate.
  CBehavior& add(std::unique_ptr<CBehavior> behavior);
  /// Creates `type` with `registry` and adds it (std::out_of_range for an unknown type).
  CBehavior& add(const BehaviorRegistry& registry, std::string_view type);
  [[nodiscard]] CBehavior* find(std::string_view name) noexcept;
  [[nodiscard]] std::vector<std::string> names() const;

  /// The context given to behaviors at activation (resources, navigation data, base); its `now`
  /// is replaced by the activation time. Not owned; may be null (behaviors then see none).
  void set_context(const BehaviorContext* context) noexcept { context_ = context; }

  /// One sampling period: steps every running behavior in name order and hands each result to
  /// `sink(name, command)` (nullopt: the behavior has nothing to say this period).
  void step_active(const BehaviorContext& context,
                   const std::function<void(std::string_view, const std::optional<Twist2D>&)>& sink);

  // BehaviorHost
  [[nodiscard]] bool has(std::string_view behavior) const override;
  /// Text values of parameters the manifest declares as numbers or booleans are converted to
  /// that type first ("0.5" -> 0.5), since nets write literals as text.
  void activate(std::string_view behavior, const ParameterValues& params, Time now) override;
  void deactivate(std::string_view behavior, Time now) override;
  [[nodiscard]] BehaviorReport report(std::string_view behavior) const override;

 private:
  struct Entry {
    std::unique_ptr<CBehavior> behavior;
    mutable std::uint64_t seen_steps = 0;  // steps() when last reported
    mutable Time last_step{};             // clock time at which a new step was first seen
  };
  const Clock& clock_;
  const BehaviorContext* context_ = nullptr;
  std::map<std::string, Entry, std::less<>> entries_;
};

}  // namespace tripodal
