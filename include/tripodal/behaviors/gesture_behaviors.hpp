// Gestures as behaviors (paper, section 4, Table 3: Jinny's interaction elements): BhFaceVisitor
// turns the base to face the visitor the laser sees, BhNeckGesture moves a neck or arm joint to a
// position. A joint's state is a resource (JointResource, resources/resource.hpp) its driver (the
// simulator's joint, sim/sim_hardware.hpp, or a servo board) publishes; its position is a command
// channel the hardware exports under the joint's name (core/command_channel.hpp), written by the
// behavior.
#pragma once

#include <optional>
#include <string>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"

namespace tripodal {

/// Turns the base on the spot to face the visitor: the nearest laser return within max_range_m
/// that the map does not hold (NavigationData::map; every return counts without one). Succeeds
/// facing it within tolerance_rad, or at once when nobody stands within max_range_m (nobody to
/// face); fails "no laser" without a fresh scan for stale_timeout_s. Re-aims every scan, so a
/// visitor who steps aside is followed.
class BhFaceVisitor final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const LaserResource* laser_ = nullptr;
  double max_range_m_ = 0.0, tolerance_rad_ = 0.0, max_yaw_rate_ = 0.0, gain_ = 0.0;
  Duration stale_timeout_{0};
  std::size_t scan_seen_ = 0;
  std::optional<double> bearing_rad_;  // of the visitor, body frame, at the last scan
  double yaw_at_scan_ = 0.0;           // odometry heading when the bearing was measured
  const OdometryResource* odom_ = nullptr;
  bool stale_ = false;
  Time stale_since_{};
};

/// Moves joint `joint` (a JointResource) to angle_deg and succeeds when it is within
/// tolerance_deg and has stopped; fails "joint limit" when the angle is beyond the joint's limits
/// (the joint goes to the limit), "no joint" when the resource is missing, "timeout" after
/// timeout_s. Gives no base command.
class BhNeckGesture final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const TypedResource<JointReading>* joint_ = nullptr;
  double target_rad_ = 0.0, tolerance_rad_ = 0.0;
  Duration timeout_{0};
  Time started_{};
  bool commanded_ = false;
};

/// Registers BhFaceVisitor and BhNeckGesture.
void register_gesture_behaviors(BehaviorRegistry& registry);

}  // namespace tripodal
