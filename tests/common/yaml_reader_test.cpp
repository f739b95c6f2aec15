// The YAML reading helper every loader uses: located errors, one wording for every loader.
#include "common/yaml_reader.hpp"

#include <sys/stat.h>
#include <unistd.h>

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

TEST_CASE("yaml::parse refuses a key given twice in a map, naming both places", "[yaml][errors]") {
  // yaml-cpp keeps both pairs and map["k"] answers the first: the author's last word was ignored.
  REQUIRE_THROWS_WITH(yaml::parse("period_s: 0.05\nname: x\nperiod_s: 0.01\n", "p.yaml"),
                      Catch::Contains("p.yaml:3:1: error: duplicate key 'period_s' (first at p.yaml:1:1)"));
  // Every duplicate at once, at any depth, in block and flow maps and inside lists.
  try {
    (void)yaml::parse("robot:\n  a: 1\n  b: 2\n  a: 3\nlist:\n  - {x: 1, x: 2}\n  - y: 1\n    y: 2\n", "d.yaml");
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK(e.diagnostics().error_count() == 3);
    CHECK_THAT(std::string(e.what()), Catch::Contains("d.yaml:4:3: error: duplicate key 'a' (first at d.yaml:2:3)") &&
                                          Catch::Contains("d.yaml:6:12: error: duplicate key 'x' (first at d.yaml:6:6)") &&
                                          Catch::Contains("d.yaml:8:5: error: duplicate key 'y' (first at d.yaml:7:5)"));
  }
  // The same key in different maps, a value equal to a key, and a list of equal items are fine.
  CHECK_NOTHROW(yaml::parse("a: {k: 1}\nb: {k: 1}\nc: [k, k]\nk: a\n", "ok.yaml"));
  // Quoting does not make another key.
  CHECK_THROWS_WITH(yaml::parse("'k': 1\nk: 2\n", "q.yaml"), Catch::Contains("q.yaml:2:1: error: duplicate key 'k'"));
  // A key that is a map or a list is not compared (no loader takes one), and the nesting below it
  // does not confuse the key/value order of the map around it.
  CHECK_NOTHROW(yaml::parse("? [a]\n: 1\n? {b: 1}\n: 2\nc: 3\n", "c.yaml"));
  CHECK_THROWS_WITH(yaml::parse("? [a]\n: {c: 1}\nc: 2\nc: 3\n", "c2.yaml"), Catch::Contains("c2.yaml:4:1: error: duplicate key 'c'"));
}

TEST_CASE("yaml::parse scans aliases as written, never expanded", "[yaml][limits]") {
  // Nine levels of ten aliases each would be 10^9 nodes expanded; as written, a few hundred events.
  std::string text = "a0: &a0 [x, x, x, x, x, x, x, x, x, x]\n";
  for (int i = 1; i < 9; ++i) {
    text += "a" + std::to_string(i) + ": &a" + std::to_string(i) + " [";
    for (int k = 0; k < 10; ++k) text += (k ? ", *a" : "*a") + std::to_string(i - 1);
    text += "]\n";
  }
  CHECK_NOTHROW(yaml::parse(text, "laughs.yaml"));
  CHECK_THROWS_WITH(yaml::parse(text + "a3: 1\n", "laughs.yaml"), Catch::Contains("laughs.yaml:10:1: error: duplicate key 'a3' (first at laughs.yaml:4:1)"));
}

TEST_CASE("yaml::Reader::seconds refuses a period too short or too long, with the range", "[yaml][errors]") {
  Fixture f("ok: 0.05\ntiny: 1e-12\nzero: 0\nhuge: 1e12\nword: soon\n");
  CHECK(f.r.seconds(f.root["ok"], "period_s") == 0.05);
  CHECK_FALSE(f.r.seconds(f.root["tiny"], "period_s"));
  CHECK_FALSE(f.r.seconds(f.root["zero"], "period_s"));
  CHECK_FALSE(f.r.seconds(f.root["huge"], "period_s"));
  CHECK_FALSE(f.r.seconds(f.root["word"], "period_s"));
  CHECK_THAT(f.errors(), Catch::Contains("t.yaml:2:7: error: period_s: expected seconds from 1e-06 to 9e+09, got '1e-12'") &&
                             Catch::Contains("t.yaml:3:7: error: period_s: expected seconds from 1e-06 to 9e+09, got '0'") &&
                             Catch::Contains("t.yaml:4:7: error: period_s: expected seconds from 1e-06 to 9e+09, got '1e12'") &&
                             Catch::Contains("t.yaml:5:7: error: period_s: expected seconds from 1e-06 to 9e+09, got 'soon'"));
}

TEST_CASE("yaml::read_file reads regular files only, and no more than the limit", "[yaml][errors][limits]") {
  // A device would be read until memory runs out (/dev/zero) or block for ever (a FIFO no one
  // writes); a directory has no text.
  CHECK_THROWS_WITH(yaml::read_file("/dev/zero"), Catch::Contains("/dev/zero: error: cannot read a character device: a configuration "
                                                                  "file must be a regular file"));
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tripodal_yaml_read_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  CHECK_THROWS_WITH(yaml::read_file(dir), Catch::Contains(dir.string() + ": error: cannot read a directory"));
  const std::filesystem::path fifo = dir / "fifo";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK_THROWS_WITH(yaml::read_file(fifo), Catch::Contains(fifo.string() + ": error: cannot read a FIFO"));
  std::filesystem::remove_all(dir);
}
