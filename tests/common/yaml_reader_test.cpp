// The YAML reading helper every loader uses: located errors, one wording for every loader.
#include "common/yaml_reader.hpp"

#include <catch2/catch.hpp>
#include <filesystem>

using namespace tripodal;

namespace {

// Reads `text` as file "t.yaml" with a fresh Reader and returns what it diagnosed.
struct Fixture {
  explicit Fixture(std::string_view text) : root(yaml::parse(text, "t.yaml")) {}
  Diagnostics d;
  yaml::Reader r{"t.yaml", d};
  YAML::Node root;
  [[nodiscard]] std::string errors() const { return d.str(); }
};

}  // namespace

TEST_CASE("yaml::parse locates a syntax error", "[yaml]") {
  REQUIRE_THROWS_WITH(yaml::parse("a: [1, 2\nb: 3\n", "s.yaml"),
                      Catch::Contains("s.yaml:") && Catch::Contains("error: YAML syntax error:"));
  REQUIRE_THROWS_WITH(yaml::read_file("/nonexistent/x.yaml"), Catch::Contains("/nonexistent/x.yaml: error: cannot read the file"));
}

TEST_CASE("yaml::Reader names the kind it expected and the kind it got", "[yaml]") {
  Fixture f("map: {a: 1}\nlist: [1, 2]\ntext: hello\nempty:\n");
  CHECK(f.r.expect_map(f.root["map"], "m"));
  CHECK_FALSE(f.r.expect_map(f.root["list"], "the map"));
  CHECK_FALSE(f.r.expect_list(f.root["text"], "the list"));
  CHECK_FALSE(f.r.expect_list(f.root["empty"], "the other list"));
  CHECK_THAT(f.errors(), Catch::Contains("t.yaml:2:7: error: the map: expected a map, got a list") &&
                             Catch::Contains("t.yaml:3:7: error: the list: expected a list, got 'hello'") &&
                             Catch::Contains("the other list: expected a list, got nothing"));
}

TEST_CASE("yaml::Reader reports unknown keys at the key, with the allowed keys named", "[yaml]") {
  Fixture f("robot:\n  name: x\n  colour: red\n  size: 3\n");
  CHECK(f.r.expect_keys(f.root["robot"], {"name", "description"}, "robot"));
  CHECK(f.d.error_count() == 2);
  CHECK_THAT(f.errors(), Catch::Contains("t.yaml:3:3: error: unknown key 'colour' in robot; expected one of: name, description") &&
                             Catch::Contains("t.yaml:4:3: error: unknown key 'size' in robot"));
  CHECK_FALSE(f.r.require(f.root["robot"], "description", "robot", "a line of text"));
  CHECK_THAT(f.errors(), Catch::Contains("t.yaml:2:3: error: robot: missing 'description' (a line of text)"));
}

TEST_CASE("yaml::Reader typed reads accept good values and locate bad ones", "[yaml]") {
  Fixture f(
      "n: 2.5\nbad: fast\nnan: .nan\nneg: -1\nint: 7\nfrac: 2.5\nbig: 1000\nyes: true\nmaybe: maybe\n"
      "mode: raw\nodd: fancy\nnames: [a, b]\nnot_names: {a: 1}\npair: [1, 2]\ntriple: [1, x, 3]\ntext: ''\n");
  CHECK(f.r.number(f.root["n"], "n") == 2.5);
  CHECK(f.r.positive(f.root["n"], "n") == 2.5);
  CHECK(f.r.non_negative(f.root["n"], "n") == 2.5);
  CHECK(f.r.integer(f.root["int"], "int", 0, 10) == 7);
  CHECK(f.r.boolean(f.root["yes"], "yes") == true);
  CHECK(f.r.choice(f.root["mode"], "mode", {"trinary", "raw"}) == "raw");
  CHECK(f.r.names(f.root["names"], "names") == std::vector<std::string>{"a", "b"});
  CHECK(f.r.numbers(f.root["pair"], "pair", 2, 3, "[x, y]") == std::vector<double>{1.0, 2.0});
  CHECK(f.r.text(f.root["text"], "text") == "");
  CHECK(f.d.empty());

  CHECK_FALSE(f.r.number(f.root["bad"], "speed"));
  CHECK_FALSE(f.r.number(f.root["nan"], "speed"));
  CHECK_FALSE(f.r.positive(f.root["neg"], "period_s"));
  CHECK_FALSE(f.r.non_negative(f.root["neg"], "timeout_s"));
  CHECK_FALSE(f.r.integer(f.root["frac"], "beams", 1, 100));
  CHECK_FALSE(f.r.integer(f.root["big"], "beams", 1, 100));
  CHECK_FALSE(f.r.boolean(f.root["maybe"], "negate"));
  CHECK_FALSE(f.r.choice(f.root["odd"], "mode", {"trinary", "scale", "raw"}));
  CHECK_FALSE(f.r.names(f.root["not_names"], "inputs"));
  CHECK_FALSE(f.r.numbers(f.root["names"], "origin", 3, 3, "[x, y, yaw]"));
  CHECK_FALSE(f.r.numbers(f.root["triple"], "origin", 3, 3, "[x, y, yaw]"));
  CHECK_FALSE(f.r.text(f.root["text"], "name", true));
  CHECK_FALSE(f.r.text(f.root["names"], "name"));
  const std::string e = f.errors();
  CHECK_THAT(e, Catch::Contains("t.yaml:2:6: error: speed: expected a number, got 'fast'"));
  CHECK_THAT(e, Catch::Contains("t.yaml:3:6: error: speed: expected a number, got '.nan'"));
  CHECK_THAT(e, Catch::Contains("t.yaml:4:6: error: period_s: expected a number > 0, got '-1'"));
  CHECK_THAT(e, Catch::Contains("timeout_s: expected a number >= 0, got '-1'"));
  CHECK_THAT(e, Catch::Contains("t.yaml:6:7: error: beams: expected a whole number from 1 to 100, got '2.5'"));
  CHECK_THAT(e, Catch::Contains("beams: expected a whole number from 1 to 100, got '1000'"));
  CHECK_THAT(e, Catch::Contains("t.yaml:9:8: error: negate: expected true or false, got 'maybe'"));
  CHECK_THAT(e, Catch::Contains("t.yaml:11:6: error: mode: expected one of trinary, scale, raw; got 'fancy'"));
  CHECK_THAT(e, Catch::Contains("inputs: expected a list of names, got a map"));
  CHECK_THAT(e, Catch::Contains("origin: expected [x, y, yaw], got a list of 2 items"));
  CHECK_THAT(e, Catch::Contains("t.yaml:15:13: error: origin: expected a number, got 'x'"));
  CHECK_THAT(e, Catch::Contains("name: expected a non-empty text, got an empty text"));
  CHECK_THAT(e, Catch::Contains("name: expected text, got a list"));
}

TEST_CASE("yaml::Reader::key refuses a list or a map as a key, at the key", "[yaml]") {
  Fixture f("params:\n  speed: 1\n  [a, b]: 2\n  {c: 3}: 4\n");
  std::vector<std::string> keys;
  for (const auto& kv : f.root["params"]) {
    if (auto k = f.r.key(kv.first, "params")) keys.push_back(*k);
  }
  CHECK(keys == std::vector<std::string>{"speed"});
  CHECK_THAT(f.errors(), Catch::Contains("t.yaml:3:3: error: params: a key must be text, got a list") &&
                             Catch::Contains("t.yaml:4:3: error: params: a key must be text, got a map"));
  CHECK(yaml::Reader::checked_key(f.root["params"].begin()->first) == "speed");
}

TEST_CASE("yaml::guarded turns what yaml-cpp throws into an error located in the file", "[yaml]") {
  const YAML::Node root = yaml::parse("a: text\nb: [1, 2]\n", "g.yaml");
  CHECK(yaml::guarded("g.yaml", [&] { return root["a"].Scalar(); }) == "text");
  // A subscript of a text throws yaml-cpp's BadSubscript; the file's name and the node's line come with it.
  REQUIRE_THROWS_WITH(yaml::guarded("g.yaml", [&] { return root["a"]["x"].Scalar(); }),
                      Catch::StartsWith("g.yaml:1:4: error: unexpected YAML structure:"));
  REQUIRE_THROWS_WITH(yaml::guarded("g.yaml", [&] { return root["b"].as<std::string>(); }),
                      Catch::StartsWith("g.yaml:2:4: error: unexpected YAML structure:"));
}

TEST_CASE("yaml::Reader locates the empty document at 1:1") {
  // Found by fuzz_robot_profile: an empty profile's "expected a map, got nothing" had no line.
  Diagnostics d;
  yaml::Reader r("empty.yaml", d);
  const SourceLocation where = r.at(yaml::parse("", "empty.yaml"));
  CHECK(where.str() == "empty.yaml:1:1");
}
