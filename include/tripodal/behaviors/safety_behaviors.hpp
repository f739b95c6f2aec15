// The reflexes of the reactive layer for what the laser cannot see (seed 001, sections 2.4.2-2.4.3
// and 3.4.2-3.4.3): a drop under the infrared cliff sensors, a bump switch pressed, glass or a low
// table in the ultrasonic sensors' cones. Each runs as a safety input of the behavior coordinator
// (a profile's `safety: true`): never the winner, it clamps whatever wins, so it holds above every
// task behavior. A back-off is a degenerate envelope (translation pinned at -back_speed_m_s,
// rotation at 0, or at the arc's rate away from a side contact), which the coordinator's clamp
// turns into that command whatever the winner asked.
// Where they hold the robot back they report the hazard's place (NavigationFeedback::hazards), so
// the sequencing layer plans around it; BhCliffGuard also raises the net event `cliff`.
#pragma once

#include <array>
#include <cstdint>
#include <string_view>

#include "tripodal/behaviors/behavior.hpp"

namespace tripodal {

class BehaviorRegistry;

/// Backing off then holding: the shared state machine of the cliff and bump reflexes.
class BackOffReflex {
 public:
  struct Options {
    double back_off_m = 0.12;       ///< how far to back away
    double back_speed_m_s = 0.1;    ///< at this speed, straight for a trigger ahead
    double hold_s = 12.0;           ///< then no forward translation this long (rotation free)...
    double release_turn_rad = 1.0;  ///< ...unless the robot turned this far from its heading at the trigger
    double max_back_off_m = 0.4;    ///< backing while the trigger stays on stops here (a stuck sensor)
    double side_turn_rad = 0.6;     ///< a trigger on a side: the backing arc turns this far over back_off_m...
    double side_release_rad = 0.3;  ///< ...and the hold ends heading no more than this toward that side
  };
  enum class Phase : std::uint8_t { idle, backing, holding };
  /// Where the trigger is on the body. A differential base cannot move sideways, so straight back
  /// from a contact on its side slides along the obstacle (glass met while driving beside it):
  /// from a side it backs along an arc curving away from that side instead (the rear swings
  /// away, the front turns toward it, side_turn_rad in all), which moves the body off the obstacle.
  enum class Side : std::uint8_t { ahead, left, right };

  void configure(const Options& options) noexcept { options_ = options; }
  void reset() noexcept { phase_ = Phase::idle; }
  /// One period: `triggered` while the sensor fires, `side` where. Returns true on a new trigger
  /// (from idle or holding). The robot backs while the trigger is on and back_off_m beyond (it
  /// may have stopped with its sensors past the edge), at most max_back_off_m in all: a trigger
  /// still on then (a sensor stuck at a drop) leaves it standing until it goes off.
  /// `heading_rad`: the robot's heading now (map frame). The hold ends early once the robot has
  /// turned release_turn_rad away from where it was heading when triggered (toward the detour the
  /// sequencing layer planned); a hold that lasts (no way around) outlasts the path follower's
  /// blocked timeout, which ends its activity with "path blocked" rather than driving at the
  /// hazard again and again. After a side trigger the way on may lie straight ahead, along the
  /// obstacle the arc has moved the body off: the hold ends once the robot has turned back to
  /// within side_release_rad of its heading at the trigger toward that side, or beyond it.
  bool update(bool triggered, Time now, double heading_rad = 0.0, Side side = Side::ahead) noexcept;
  /// The envelope of the phase (nullopt when idle).
  [[nodiscard]] std::optional<VelocityEnvelope> envelope(Time now) const noexcept;
  [[nodiscard]] Phase phase() const noexcept { return phase_; }

 private:
  // The turn since the trigger, positive toward the side triggered (counter-clockwise ahead).
  [[nodiscard]] double turn_toward_side_rad() const noexcept;

  Options options_;
  Phase phase_ = Phase::idle;
  Side side_ = Side::ahead;
  Time started_{}, back_until_{}, hold_until_{};
  double heading0_rad_ = 0.0, heading_rad_ = 0.0;
};

/// Cliff: when a cliff bit is set (the board's judgment, InfraredReading::cliff) the robot stops,
/// backs straight off back_off_m, then may not drive forward for hold_s (or until it has turned
/// away: BackOffReflex), and the net event `event`
/// ("cliff") is raised once per detection. The sensors' places on the chassis (parameter
/// `sensors`) give the hazard points: under each firing sensor and 0.35 and 0.7 m ahead of it
/// (the floor is gone beyond the edge too). Fails at activation without a cliff resource.
class BhCliffGuard final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();
  static constexpr std::size_t kMaxSensors = 8;

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const InfraredResource* cliff_ = nullptr;
  std::array<Pose2D, kMaxSensors> sensors_{};  // body frame
  std::size_t sensor_count_ = 0;
  std::string event_;
  BackOffReflex reflex_;
  std::array<Pose2D, NavigationFeedback::kMaxHazards> hazards_{};  // map frame, of this detection
  std::size_t hazard_count_ = 0;
};

/// Bump: a front bump switch pressed (any not in back_mask) stops the robot and backs it off like
/// BhCliffGuard; a back one alone forbids backing while pressed. The pressed sector's direction
/// (of `sectors` equal sectors, sector 0 ahead, counter-clockwise) gives the hazard point and the
/// side: pressed sectors whose mean direction is side_angle_rad or more off ahead are a contact on
/// that side, backed away from along an arc (BackOffReflex::Side).
class BhBumperGuard final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const BumperResource* bumpers_ = nullptr;
  std::uint32_t back_mask_ = 0;
  std::uint32_t sectors_ = 4;
  double radius_m_ = 0.25;
  double side_angle_rad_ = 1.0;
  BackOffReflex reflex_;
  std::array<Pose2D, NavigationFeedback::kMaxHazards> hazards_{};
  std::size_t hazard_count_ = 0;
};

/// Ultrasonic: forward speed falls linearly from max_speed_m_s at slow_distance_m to 0 at
/// stop_distance_m of clearance ahead of the footprint, the clearance taken from the echoes whose
/// cone reaches into the corridor the footprint sweeps (transducers at `angles_rad` on the rim).
/// An echo from where the map holds an obstacle is left to the planner (the paths keep their
/// distance from walls; the laser sees them): the sonar guards against what the map does not hold.
/// Before the first reading no forward translation. Echoes at stop distance are hazard points.
class BhSonarGuard final : public CBehavior {
 public:
  static const ModuleManifest& static_manifest();
  static constexpr std::size_t kMaxTransducers = 8;

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_activate(const ParameterSet& params, const BehaviorContext& context) override;
  std::optional<Twist2D> on_step(const BehaviorContext& context) noexcept override;

 private:
  const SonarResource* sonar_ = nullptr;
  std::array<double, kMaxTransducers> angles_{};
  std::size_t angle_count_ = 0;
  double radius_m_ = 0.25, stop_m_ = 0.1, slow_m_ = 0.6, max_speed_ = 0.5, margin_m_ = 0.03, cone_half_ = 0.13;
};

/// Registers BhCliffGuard, BhBumperGuard and BhSonarGuard.
void register_safety_behaviors(BehaviorRegistry& registry);

}  // namespace tripodal
