// Module manifests: layer and kind names, parameter resolution. (The one-provider-per-input check
// and the layered diagram of a robot are src/robot/layering's, tested in tests/robot.)
#include "tripodal/core/manifest.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;

TEST_CASE("Layers and kinds have names") {
  CHECK(to_string(Layer::sequencing) == "sequencing");
  CHECK(parse_layer("reactive") == Layer::reactive);
  CHECK_FALSE(parse_layer("middle").has_value());
  CHECK(to_string(ModuleKind::controller) == "controller");
}

TEST_CASE("Parameters resolve with defaults, conversions and bounds") {
  ModuleManifest m;
  m.name = "BhTest";
  m.parameters = {{"speed_m_s", ValueType::number, Value{0.5}, "m/s", "speed", 0.0, 2.0},
                  {"room", ValueType::string, std::nullopt, "", "room name", {}, {}},
                  {"careful", ValueType::boolean, Value{false}, "", "go slowly", {}, {}}};
  const ParameterSet p = ParameterSet::resolve(m, {{"room", Value{std::string("3211")}}, {"careful", Value{std::string("true")}}});
  CHECK(p.number("speed_m_s") == 0.5);
  CHECK(p.string("room") == "3211");
  CHECK(p.boolean("careful"));
  CHECK(p.contains("room"));
  CHECK_FALSE(p.contains("x"));
  CHECK(m.find_parameter("room") != nullptr);
  CHECK(m.find_parameter("nope") == nullptr);
  REQUIRE_THROWS_WITH(ParameterSet::resolve(m, {{"speed_m_s", Value{3.0}}}, {"net.xml", 4, 2}),
                      Catch::Contains("net.xml:4:2: error: BhTest: missing required parameter 'room' (string)") &&
                          Catch::Contains("net.xml:4:2: error: BhTest: parameter 'speed_m_s' = 3 m/s is outside [0, 2]"));
}

TEST_CASE("The public builders make manifests and parameter declarations") {
  const ModuleManifest m = ManifestBuilder("BhApproach", ModuleKind::behavior)
                               .description("drives toward the closest obstacle")
                               .input("laser_scan")
                               .inputs({"odometry"})
                               .output("behavior_command")
                               .number("stop_distance_m", 0.3, "m", "stops this close", 0.05, 2.0)
                               .text("laser", "", "laser resource name")
                               .flag("careful", false, "go slowly")
                               .parameter(parameter::positive("gain", std::nullopt, "1/s", "proportional gain"))
                               .parameters({parameter::optional(parameter::number("limit_m_s", 1.0, "m/s", "unset: none"))})
                               .build();
  CHECK(m.name == "BhApproach");
  CHECK(m.kind == ModuleKind::behavior);
  CHECK(m.layer == Layer::reactive);
  CHECK(m.inputs == std::vector<std::string>{"laser_scan", "odometry"});
  CHECK(m.outputs == std::vector<std::string>{"behavior_command"});
  REQUIRE(m.parameters.size() == 5);
  const ParameterSpec& stop = *m.find_parameter("stop_distance_m");
  CHECK(stop.type == ValueType::number);
  CHECK(stop.default_value == Value{0.3});
  CHECK(stop.unit == "m");
  CHECK(stop.min == 0.05);
  CHECK(stop.max == 2.0);
  CHECK(m.find_parameter("laser")->default_value == Value{std::string()});
  CHECK(m.find_parameter("careful")->type == ValueType::boolean);
  CHECK(m.find_parameter("gain")->min_exclusive);
  CHECK_FALSE(m.find_parameter("gain")->default_value.has_value());
  CHECK(m.find_parameter("limit_m_s")->optional);
  CHECK_FALSE(m.find_parameter("limit_m_s")->default_value.has_value());  // optional drops the default

  // A required parameter must be given, an optional one may stay unset, an exclusive bound is > .
  const ParameterSet p = ParameterSet::resolve(m, {{"gain", Value{2.0}}});
  CHECK(p.number("stop_distance_m") == 0.3);
  CHECK_FALSE(p.contains("limit_m_s"));
  REQUIRE_THROWS_WITH(ParameterSet::resolve(m, {{"gain", Value{0.0}}, {"stop_distance_m", Value{3.0}}}, {"net.xml", 2, 3}),
                      Catch::Contains("net.xml:2:3: error: BhApproach: parameter 'gain' = 0 1/s is outside (0, inf]") &&
                          Catch::Contains("BhApproach: parameter 'stop_distance_m' = 3 m is outside [0.05, 2]"));
  REQUIRE_THROWS_WITH(ParameterSet::resolve(m, {}), Catch::Contains("BhApproach: missing required parameter 'gain' (number)"));
}

TEST_CASE("A parameter value is checked against its declaration with one message") {
  const ParameterSpec radius = parameter::positive("wheel_radius_m", std::nullopt, "m", "wheel radius");
  CHECK_FALSE(check_parameter_value(radius, Value{0.05}).has_value());
  CHECK(check_parameter_value(radius, Value{-0.05}) == "parameter 'wheel_radius_m' = -0.05 m is outside (0, inf]");
  CHECK(check_parameter_value(radius, Value{std::string("big")}) ==
        "parameter 'wheel_radius_m' expects a number, got \"big\"");
  const ParameterSpec angle = parameter::number("angle_rad", 0.0, "rad", "turn", std::nullopt, 3.5);
  CHECK(check_parameter_value(angle, Value{4.0}) == "parameter 'angle_rad' = 4 rad is outside [-inf, 3.5]");
  CHECK_FALSE(check_parameter_value(angle, Value{-1e9}).has_value());
  CHECK(check_parameter_value(parameter::flag("careful", true, "go slowly"), Value{1.0}) ==
        "parameter 'careful' expects a bool, got 1");
}
