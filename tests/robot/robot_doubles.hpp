// Test doubles of the modules the PSR-2 profile (configs/robots/psr2.yaml) names, registered under
// the same type names: behaviors as real CBehavior subclasses that work for a number of periods
// (pausing while the robot is lost), and navigation modules and resources as RobotModules — a
// localizer that posts localizer.lost/ok, a section splitter that answers sections(room).
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/robot/module.hpp"

namespace tripodal::test {

/// What the doubles share: the truth about localization and the faults a test injects.
struct TestWorld {
  bool localized = true;
  bool localizer_throws = false;
  bool localizer_silent = false;
  std::map<std::string, std::vector<std::string>> sections{{"3211", {"A", "B"}}, {"2111", {"C"}}};
};

inline ModuleManifest behavior_manifest(std::string name, std::vector<std::string> inputs, std::vector<ParameterSpec> params) {
  ModuleManifest m;
  m.name = std::move(name);
  m.layer = Layer::reactive;
  m.kind = ModuleKind::behavior;
  m.inputs = std::move(inputs);
  m.outputs = {"behavior_command"};
  m.parameters = std::move(params);
  return m;
}

inline ParameterSpec text_param(std::string name, std::optional<std::string> def = std::nullopt) {
  ParameterSpec p;
  p.name = std::move(name);
  p.type = ValueType::string;
  if (def) p.default_value = Value{*def};
  return p;
}

/// Works `steps` periods, then succeeds; stands still (zero command, no progress) while the robot
/// is lost unless it is the one that localizes; BhGlobalLocalization restores localization.
class TestBehavior final : public CBehavior {
 public:
  TestBehavior(const ModuleManifest& manifest, TestWorld& world, int steps, bool localizes)
      : manifest_(manifest), world_(world), steps_(steps), localizes_(localizes) {}
  std::string last_param;

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return manifest_; }
  void on_activate(const ParameterSet& params, const BehaviorContext&) override {
    progress_ = 0;
    last_param = params.values().empty() ? std::string() : to_string(params.values().begin()->second);
  }
  std::optional<Twist2D> on_step(const BehaviorContext&) noexcept override {
    if (!localizes_ && !world_.localized) return Twist2D{};
    if (++progress_ >= steps_) {
      if (localizes_) world_.localized = true;
      succeed();
    }
    return Twist2D{0.2, 0.0, 0.0};
  }

 private:
  const ModuleManifest& manifest_;
  TestWorld& world_;
  int steps_;
  bool localizes_;
  int progress_ = 0;
};

/// Registers BhAutoMove (30 periods), BhCleaning and BhCleaningTwoWheel (100), BhGlobalLocalization (20).
inline void register_test_behaviors(BehaviorRegistry& reg, TestWorld& world) {
  static const ModuleManifest automove = behavior_manifest("BhAutoMove", {"map_from_base", "laser_scan", "grid_map"}, {text_param("goal")});
  static const ModuleManifest cleaning =
      behavior_manifest("BhCleaning", {"map_from_base", "laser_scan", "grid_map"}, {text_param("section")});
  static const ModuleManifest two_wheel =
      behavior_manifest("BhCleaningTwoWheel", {"map_from_base", "laser_scan", "grid_map"}, {text_param("section")});
  static const ModuleManifest global = behavior_manifest("BhGlobalLocalization", {"laser_scan"}, {});
  reg.add(automove, [&world] { return std::make_unique<TestBehavior>(automove, world, 30, false); });
  reg.add(cleaning, [&world] { return std::make_unique<TestBehavior>(cleaning, world, 100, false); });
  reg.add(two_wheel, [&world] { return std::make_unique<TestBehavior>(two_wheel, world, 100, false); });
  reg.add(global, [&world] { return std::make_unique<TestBehavior>(global, world, 20, true); });
}

/// Posts localizer.lost / localizer.ok when the world's localization changes; heartbeats.
class TestLocalizer final : public RobotModule {
 public:
  explicit TestLocalizer(TestWorld& w) : world_(w) {}

 protected:
  void on_update(Time) override {
    if (world_.localizer_throws) throw std::runtime_error("scan matcher crashed");
    if (world_.localizer_silent) return;
    port().heartbeat();
    if (world_.localized != reported_) {
      reported_ = world_.localized;
      port().post_event(reported_ ? "localizer.ok" : "localizer.lost");
    }
  }

 private:
  TestWorld& world_;
  bool reported_ = true;
};

class TestSectionSplitter final : public RobotModule {
 public:
  explicit TestSectionSplitter(TestWorld& w) : world_(w) {}

 protected:
  std::optional<TaskKnowledge::ListResult> on_answer(std::string_view function, std::string_view room) const override {
    if (function != "sections") return std::nullopt;
    auto it = world_.sections.find(std::string(room));
    if (it == world_.sections.end()) return TaskKnowledge::ListResult{false, {}, "unknown room '" + std::string(room) + "'"};
    return TaskKnowledge::ListResult{true, it->second, {}};
  }

 private:
  TestWorld& world_;
};

class PassiveModule final : public RobotModule {};

inline ModuleManifest module_manifest(std::string name, Layer layer, ModuleKind kind, std::vector<std::string> in,
                                      std::vector<std::string> out) {
  ModuleManifest m;
  m.name = std::move(name);
  m.layer = layer;
  m.kind = kind;
  m.inputs = std::move(in);
  m.outputs = std::move(out);
  return m;
}

/// The PSR-2 profile's module types.
inline void register_test_modules(ModuleRegistry& reg, TestWorld& world) {
  auto passive = [](const ModuleConfig&) { return std::make_unique<PassiveModule>(); };
  reg.add(module_manifest("LaserScanner", Layer::reactive, ModuleKind::resource, {}, {"laser_scan"}), passive);
  reg.add(module_manifest("Gyro", Layer::reactive, ModuleKind::resource, {}, {"yaw_rate"}), passive);
  reg.add(module_manifest("GridMaps", Layer::sequencing, ModuleKind::navigation, {}, {"grid_map"}), passive);
  reg.add(module_manifest("Localizer", Layer::sequencing, ModuleKind::navigation, {"laser_scan", "odometry", "grid_map"},
                          {"map_from_base"}),
          [&world](const ModuleConfig&) { return std::make_unique<TestLocalizer>(world); });
  reg.add(module_manifest("SectionSplitter", Layer::sequencing, ModuleKind::navigation, {"grid_map", "map_from_base"},
                          {"sections"}),
          [&world](const ModuleConfig&) { return std::make_unique<TestSectionSplitter>(world); });
}

}  // namespace tripodal::test
