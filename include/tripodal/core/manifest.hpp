// The static manifest every plugin (behavior, resource, controller, process, navigation module)
// declares: its name, its layer, the information it needs and provides, and its parameters. It
// feeds the layered functionality diagram and the start-up check that every input has a provider.
#pragma once

#include <cstddef>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tripodal/core/command_channel.hpp"
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
  std::optional<double> min;      ///< numbers only: bounds checked at activation, inclusive ...
  std::optional<double> max;
  bool min_exclusive = false;     ///< ... except min when this is set (a radius must be > 0)
  bool optional = false;          ///< without a default: may stay unset rather than being required
};

/// The problem with `value` for `spec` ("'wheel_radius_m' must be > 0, got -0.05"), or nullopt
/// when it is of the declared type and within the bounds. Every reader of parameters (net
/// bindings, YAML configuration) reports through this, so the messages are the same everywhere.
[[nodiscard]] std::optional<std::string> check_parameter_value(const ParameterSpec& spec, const Value& value);

/// Builders of parameter declarations, for manifests written in code: `parameter::number(
/// "wheel_radius_m", std::nullopt, "m", "wheel radius", 0.0)`. A nullopt default makes the
/// parameter required.
namespace parameter {
[[nodiscard]] ParameterSpec number(std::string name, std::optional<double> default_value, std::string unit,
                                   std::string description, std::optional<double> min = std::nullopt,
                                   std::optional<double> max = std::nullopt);
/// A number that must be > 0 (lengths, periods, gains).
[[nodiscard]] ParameterSpec positive(std::string name, std::optional<double> default_value, std::string unit,
                                     std::string description);
[[nodiscard]] ParameterSpec text(std::string name, std::optional<std::string> default_value, std::string description);
[[nodiscard]] ParameterSpec flag(std::string name, std::optional<bool> default_value, std::string description);
/// `spec` without a default and not required: left unset unless configured ("no limit").
[[nodiscard]] ParameterSpec optional(ParameterSpec spec);
}  // namespace parameter

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
  /// Behaviors: the command channels the behavior writes (at most kMaxBehaviorChannels; its
  /// writes are indexed in this order). Hardware: the channels every instance of the type
  /// exports (an instance may export more, e.g. the joints of its world).
  std::vector<ChannelWrite> writes;
  std::vector<ChannelSpec> command_channels;

  [[nodiscard]] const ParameterSpec* find_parameter(std::string_view parameter) const noexcept;
};

/// Builds a manifest in one expression, the way every plugin type declares its static manifest:
///   ManifestBuilder("BhGoToPose", ModuleKind::behavior).input("odometry").output("behavior_command")
///       .number("max_speed_m_s", 0.5, "m/s", "cruise speed", 0.0, 2.0).build()
class ManifestBuilder {
 public:
  ManifestBuilder(std::string name, ModuleKind kind, Layer layer = Layer::reactive);
  ManifestBuilder& layer(Layer layer);
  ManifestBuilder& kind(ModuleKind kind);
  ManifestBuilder& description(std::string text);
  ManifestBuilder& input(std::string information);
  ManifestBuilder& inputs(std::vector<std::string> information);
  ManifestBuilder& output(std::string information);
  ManifestBuilder& outputs(std::vector<std::string> information);
  /// Appends a parameter; see parameter::number and friends for the arguments.
  ManifestBuilder& parameter(ParameterSpec spec);
  ManifestBuilder& parameters(std::vector<ParameterSpec> specs);
  ManifestBuilder& number(std::string name, std::optional<double> default_value, std::string unit,
                          std::string description, std::optional<double> min = std::nullopt,
                          std::optional<double> max = std::nullopt);
  ManifestBuilder& text(std::string name, std::optional<std::string> default_value, std::string description);
  ManifestBuilder& flag(std::string name, std::optional<bool> default_value, std::string description);
  /// A command channel the behavior writes, by name ...
  ManifestBuilder& writes(std::string channel, ChannelType type, std::string description);
  /// ... or named by the value of its string parameter `parameter`.
  ManifestBuilder& writes_named_by(std::string parameter, ChannelType type, std::string description);
  /// A command channel the hardware type exports.
  ManifestBuilder& command_channel(ChannelSpec spec);
  [[nodiscard]] ModuleManifest build() const& { return manifest_; }
  [[nodiscard]] ModuleManifest build() && { return std::move(manifest_); }

 private:
  ModuleManifest manifest_;
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
  /// name, a wrong type, a missing required parameter, a number outside [min, max]. An optional
  /// parameter without a value stays absent (contains() is false). `where` is
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
