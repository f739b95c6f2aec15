// The static manifest every plugin (behavior, resource, controller, process, navigation module)
// declares: its name, its layer, the information it needs and provides, and its parameters. It
// feeds the layered functionality diagram and the start-up check that every input has a provider.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/value.hpp"

namespace tripodal {

/// The three layers of the layered functionality diagram (paper, Fig. 1).
enum class Layer { deliberate, sequencing, reactive };

/// What family of plugin a manifest describes; decides which registry it lives in.
enum class ModuleKind { behavior, resource, controller, process, navigation, planner, hri, other };

[[nodiscard]] std::string_view to_string(Layer layer) noexcept;
[[nodiscard]] std::string_view to_string(ModuleKind kind) noexcept;
/// "deliberate" | "sequencing" | "reactive" -> Layer.
[[nodiscard]] std::optional<Layer> parse_layer(std::string_view text) noexcept;

/// One declared parameter. A parameter without a default is required.
struct ParameterSpec {
  std::string name;               ///< snake_case with the unit as suffix where ambiguous: goal_x_m
  ValueType type = ValueType::number;
  std::optional<Value> default_value;
  std::string unit;               ///< SI unit ("m", "m/s", "rad", "s") or "" for none
  std::string description;
  std::optional<double> min;      ///< numbers only: inclusive bounds checked at activation
  std::optional<double> max;
};

/// Static description of a plugin type. Inputs and outputs are names of information
/// ("laser_scan", "odometry", "map_from_base", "goal_pose", "cmd_vel"): a configured robot is
/// consistent when every input has exactly one provider among the configured modules.
struct ModuleManifest {
  std::string name;  ///< registered type name, e.g. "BhGoToPose"
  Layer layer = Layer::reactive;
  ModuleKind kind = ModuleKind::other;
  std::string description;
  std::vector<std::string> inputs;
  std::vector<std::string> outputs;
  std::vector<ParameterSpec> parameters;

  [[nodiscard]] const ParameterSpec* find_parameter(std::string_view parameter) const noexcept;
};

/// Parameter values by name, as given to an activation (same type as the engine's).
using ParameterValues = std::map<std::string, Value, std::less<>>;

/// Parameter values resolved against a manifest: every declared parameter has a value of the
/// declared type (given or default). Built at activation, outside the control loop; lookups are
/// by name and intended for on_activate(), which copies them into typed members.
class ParameterSet {
 public:
  ParameterSet() = default;
  /// Resolves `given` against `manifest`. Throws ConfigError listing every problem: an unknown
  /// name, a wrong type, a missing required parameter, a number outside [min, max]. `where` is
  /// used for the location of the messages (e.g. the net file and the place binding it).
  static ParameterSet resolve(const ModuleManifest& manifest, const ParameterValues& given,
                              const SourceLocation& where = {});

  /// The value of a declared parameter; throws std::out_of_range for an undeclared name and
  /// std::bad_variant_access when the type differs.
  [[nodiscard]] double number(std::string_view name) const;
  [[nodiscard]] bool boolean(std::string_view name) const;
  [[nodiscard]] const std::string& string(std::string_view name) const;
  [[nodiscard]] const Value& value(std::string_view name) const;
  [[nodiscard]] bool contains(std::string_view name) const noexcept;
  [[nodiscard]] const ParameterValues& values() const noexcept { return values_; }

 private:
  ParameterValues values_;
};

}  // namespace tripodal
