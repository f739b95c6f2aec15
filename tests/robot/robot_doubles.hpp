// Test doubles of the types the PSR-2 profile (configs/robots/psr2.yaml) names, registered under
// the same type names: behaviors as real CBehavior subclasses that work for a while (pausing while
// the robot is lost), navigation modules as CModules — a localizer that posts localizer.lost/ok, a
// section splitter that answers sections(room) — and a hardware "sim" of ideal wheels.
#pragma once

#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "tripodal/behaviors/behavior.hpp"
#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"
#include "tripodal/navi/navi_modules.hpp"
#include "tripodal/robot/plugins.hpp"

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

/// Works for `work` (time counted only while the robot is localized, unless it is the one that
/// localizes), then succeeds; BhGlobalLocalization restores localization.
class TestBehavior final : public CBehavior {
 public:
  TestBehavior(const ModuleManifest& manifest, TestWorld& world, Duration work, bool localizes)
      : manifest_(manifest), world_(world), work_(work), localizes_(localizes) {}

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return manifest_; }
  void on_activate(const ParameterSet&, const BehaviorContext&) override { done_ = Duration{0}; }
  std::optional<Twist2D> on_step(const BehaviorContext& c) noexcept override {
    if (!localizes_ && !world_.localized) return Twist2D{};
    done_ += c.period;
    if (done_ >= work_) {
      if (localizes_) world_.localized = true;
      succeed();
    }
    return Twist2D{0.2, 0.0, 0.0};
  }

 private:
  const ModuleManifest& manifest_;
  TestWorld& world_;
  Duration work_;
  bool localizes_;
  Duration done_{0};
};

/// Registers BhAutoMove (3 s), BhCleaning and BhCleaningTwoWheel (10 s), BhGlobalLocalization (2 s).
inline void register_test_behaviors(BehaviorRegistry& reg, TestWorld& world) {
  static const ModuleManifest automove = behavior_manifest("BhAutoMove", {"map_from_base"}, {text_param("goal")});
  static const ModuleManifest cleaning = behavior_manifest("BhCleaning", {"map_from_base"}, {text_param("section")});
  static const ModuleManifest two_wheel = behavior_manifest("BhCleaningTwoWheel", {"map_from_base"}, {text_param("section")});
  static const ModuleManifest global = behavior_manifest("BhGlobalLocalization", {}, {});
  using std::chrono::seconds;
  reg.add(automove, [&world] { return std::make_unique<TestBehavior>(automove, world, seconds(3), false); });
  reg.add(cleaning, [&world] { return std::make_unique<TestBehavior>(cleaning, world, seconds(10), false); });
  reg.add(two_wheel, [&world] { return std::make_unique<TestBehavior>(two_wheel, world, seconds(10), false); });
  reg.add(global, [&world] { return std::make_unique<TestBehavior>(global, world, seconds(2), true); });
}

inline ModuleManifest module_manifest(std::string name, std::vector<std::string> in, std::vector<std::string> out,
                                      std::vector<ParameterSpec> params = {}) {
  return navi::navi_manifest(std::move(name), "test double", std::move(in), std::move(out), std::move(params));
}

/// Posts localizer.lost / localizer.ok when the world's localization changes; heartbeats.
class TestLocalizer final : public navi::CNaviModules {
 public:
  static TestWorld* world;
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m =
        module_manifest("ScanMatchingLocalizer", {"laser_scan", "odometry", "grid_map"}, {"map_from_base"},
                        {ParameterSpec{"initial_x_m", ValueType::number, Value{0.0}, "m", "", {}, {}},
                         ParameterSpec{"initial_y_m", ValueType::number, Value{0.0}, "m", "", {}, {}},
                         ParameterSpec{"initial_theta_rad", ValueType::number, Value{0.0}, "rad", "", {}, {}},
                         ParameterSpec{"surface_at_cell_face", ValueType::boolean, Value{false}, "", "", {}, {}}});
    return m;
  }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_update(ModuleContext& c) override {
    if (world->localizer_throws) throw std::runtime_error("scan matcher crashed");
    if (world->localizer_silent) return;
    c.heartbeat = true;
    c.navigation->localized = world->localized;
    if (world->localized != reported_) {
      reported_ = world->localized;
      c.post(reported_ ? "localizer.ok" : "localizer.lost");
    }
  }

 private:
  bool reported_ = true;
};
inline TestWorld* TestLocalizer::world = nullptr;

class TestSectionSplitter final : public navi::CNaviModules {
 public:
  static TestWorld* world;
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = module_manifest("SectionSplitter", {"grid_map"}, {"sections"});
    return m;
  }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  std::optional<KnowledgeAnswer> on_answer(std::string_view function, std::string_view room, const NavigationData&) const override {
    if (function != "sections") return std::nullopt;
    auto it = world->sections.find(std::string(room));
    if (it == world->sections.end()) return KnowledgeAnswer{false, {}, "unknown room '" + std::string(room) + "'"};
    return KnowledgeAnswer{true, it->second, {}};
  }
};
inline TestWorld* TestSectionSplitter::world = nullptr;

/// A module that does nothing, under a type name of the profile.
template <int N>
class PassiveModule final : public navi::CNaviModules {
 public:
  static ModuleManifest* manifest_of;
  static const ModuleManifest& static_manifest() { return *manifest_of; }

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return *manifest_of; }
};
template <int N>
ModuleManifest* PassiveModule<N>::manifest_of = nullptr;

/// Hardware "sim": ideal wheels, no sensors.
class TestHardware final : public CHardware {
 public:
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = hardware_manifest("sim", "ideal wheels and a laser", {"laser_scan"}, {});
    return m;
  }
  explicit TestHardware(const HardwareConfig& c)
      : wheels_(c.base == nullptr || c.base->type == "differential" ? 2 : c.base->holonomic.wheels.size(),
                c.base != nullptr ? c.base->period : std::chrono::milliseconds(10)) {}

 protected:
  const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  HardwareInterface& do_wheels() noexcept override { return wheels_; }

 private:
  IdealWheelHardware wheels_;
};

/// The PSR-2 profile's types, as doubles: behaviors, the navigation modules, the hardware, and the
/// real controllers.
inline RobotPlugins test_plugins(TestWorld& world) {
  RobotPlugins p;
  register_test_behaviors(p.behaviors, world);
  register_builtin_controllers(p.controllers);
  TestLocalizer::world = &world;
  TestSectionSplitter::world = &world;
  p.modules.add<TestLocalizer>();
  p.modules.add<TestSectionSplitter>();
  static ModuleManifest maps = module_manifest("GridMaps", {}, {"grid_map"},
                                               {ParameterSpec{"robot_radius_m", ValueType::number, Value{0.3}, "m", "", {}, {}}});
  static ModuleManifest planner = module_manifest("PathPlanner", {"grid_map", "map_from_base"}, {"path"});
  static ModuleManifest coverage = module_manifest(
      "CoveragePlanner", {"grid_map", "sections"}, {"coverage_path"},
      {ParameterSpec{"cleaning_width_m", ValueType::number, Value{0.4}, "m", "", {}, {}}});
  static ModuleManifest mapping = module_manifest("MapBuilder", {"laser_scan", "odometry"}, {"built_map"});
  PassiveModule<0>::manifest_of = &maps;
  PassiveModule<1>::manifest_of = &planner;
  PassiveModule<2>::manifest_of = &coverage;
  PassiveModule<3>::manifest_of = &mapping;
  p.modules.add<PassiveModule<0>>();
  p.modules.add<PassiveModule<1>>();
  p.modules.add<PassiveModule<2>>();
  p.modules.add<PassiveModule<3>>();
  static const ModuleManifest laser = [] {
    ModuleManifest m = resource_manifest<LaserScan>();
    m.name = "LaserScanner";
    return m;
  }();
  p.resources.add(laser, [](const ResourceConfig& c) { return std::make_unique<LaserResource>(c.name); });
  p.hardware.add(TestHardware::static_manifest(), [](const HardwareConfig& c) { return std::make_unique<TestHardware>(c); });
  return p;
}

}  // namespace tripodal::test
