// BhApproach, the behavior of docs/behavior-tutorial.md: drives straight at whatever is ahead,
// slowing down as it gets closer, and succeeds when it stands stop_distance_m short of it.
#pragma once

#include <optional>

#include "tripodal/behaviors/behavior.hpp"

namespace example {

class BhApproach final : public tripodal::CBehavior {
 public:
  static const tripodal::ModuleManifest& static_manifest();

 protected:
  const tripodal::ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const tripodal::ParameterSet& params, const tripodal::BehaviorContext& context) override;
  std::optional<tripodal::Twist2D> on_step(const tripodal::BehaviorContext& context) noexcept override;

 private:
  const tripodal::LaserResource* laser_ = nullptr;
  double speed_m_s_ = 0.0, slow_m_ = 0.0, stop_m_ = 0.0, radius_m_ = 0.0;
};

}  // namespace example
