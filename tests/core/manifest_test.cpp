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
