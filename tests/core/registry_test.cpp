// The plugin registry template: registration, lookup, creation by name, and the one
// unknown-name message every plugin family reports.
#include "tripodal/core/registry.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;

namespace {

// A small plugin family of its own: a base, two types, and a constructor argument.
struct Greeter {
  virtual ~Greeter() = default;
  [[nodiscard]] virtual std::string greet() const = 0;
};

struct HelloGreeter final : Greeter {
  explicit HelloGreeter(std::string who) : who_(std::move(who)) {}
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = [] {
      ModuleManifest x;
      x.name = "Hello";
      x.kind = ModuleKind::other;
      x.description = "says hello";
      return x;
    }();
    return m;
  }
  [[nodiscard]] std::string greet() const override { return "hello " + who_; }
  std::string who_;
};

ModuleManifest named(std::string name) {
  ModuleManifest m;
  m.name = std::move(name);
  return m;
}

using GreeterRegistry = Registry<Greeter, std::string>;

}  // namespace

TEST_CASE("Registry creates a registered type by name with its arguments") {
  GreeterRegistry r("greeter type");
  r.add<HelloGreeter>();
  struct Bye final : Greeter {
    [[nodiscard]] std::string greet() const override { return "bye"; }
  };
  r.add(named("Bye"), [](std::string) { return std::unique_ptr<Greeter>(std::make_unique<Bye>()); });

  CHECK(r.kind() == "greeter type");
  CHECK(r.names() == std::vector<std::string>{"Bye", "Hello"});
  CHECK(r.size() == 2);
  CHECK(r.contains("Hello"));
  CHECK_FALSE(r.contains("hello"));
  REQUIRE(r.find("Hello") != nullptr);
  CHECK(r.find("Hello")->description == "says hello");
  CHECK(r.find("Nobody") == nullptr);
  CHECK(&r.manifest("Bye") == r.find("Bye"));
  CHECK(r.create("Hello", "robot")->greet() == "hello robot");
  CHECK(r.create_at({"robot.yaml", 3, 5}, "Bye", "")->greet() == "bye");
}

TEST_CASE("Registry refuses empty and duplicate names and empty factories") {
  GreeterRegistry r("greeter type");
  r.add<HelloGreeter>();
  REQUIRE_THROWS_WITH(r.add<HelloGreeter>(), Catch::Contains("greeter type 'Hello' is already registered"));
  REQUIRE_THROWS_WITH(r.add(named(""), [](std::string) { return std::unique_ptr<Greeter>(); }),
                      Catch::Contains("a greeter type needs a name"));
  REQUIRE_THROWS_WITH(r.add(named("Empty"), nullptr), Catch::Contains("greeter type 'Empty' has no factory"));
  r.add(named("Null"), [](std::string) { return std::unique_ptr<Greeter>(); });
  REQUIRE_THROWS_WITH(r.create("Null", ""), Catch::Contains("the factory of greeter type 'Null' returned nothing"));
}

TEST_CASE("Registry reports an unknown name at its location, listing the known ones") {
  GreeterRegistry r("greeter type");
  r.add<HelloGreeter>();
  r.add(named("Goodbye"), [](std::string) { return std::unique_ptr<Greeter>(); });
  REQUIRE_THROWS_AS(r.create("Helo", ""), ConfigError);
  REQUIRE_THROWS_WITH(r.create("Helo", ""),
                      Catch::Contains("error: unknown greeter type 'Helo'; known: Goodbye, Hello; did you mean 'Hello'?"));
  REQUIRE_THROWS_WITH(r.create_at({"robot.yaml", 7, 9}, "Zzzzzz", ""),
                      Catch::Contains("robot.yaml:7:9: error: unknown greeter type 'Zzzzzz'; known: Goodbye, Hello") &&
                          !Catch::Contains("did you mean"));
  REQUIRE_THROWS_WITH(r.manifest("goodby", {"a.yaml", 1, 2}),
                      Catch::Contains("a.yaml:1:2: error: unknown greeter type 'goodby'; known: Goodbye, Hello; "
                                      "did you mean 'Goodbye'?"));
}

TEST_CASE("The closest name is within max(2, size/3) edits, case-insensitive, first on a tie") {
  const std::vector<std::string> known{"BhAutoMove", "BhCleaning", "BhCleaningTwoWheel", "BhStop"};
  CHECK(closest_name("BhClean", known) == "BhCleaning");     // 3 edits, 10 / 3 allowed
  CHECK(closest_name("bhcleaning", known) == "BhCleaning");  // case alone is no edit
  CHECK(closest_name("BhStpo", known) == "BhStop");          // 2 edits, the minimum allowed
  CHECK_FALSE(closest_name("BhSt", std::vector<std::string>{"BhStopNow"}).has_value());  // 5 edits, 3 allowed
  CHECK_FALSE(closest_name("PrCleaning", std::vector<std::string>{"BhStop"}).has_value());
  CHECK_FALSE(closest_name("Bh", std::vector<std::string>{"BhAutoMove"}).has_value());
  CHECK_FALSE(closest_name("x", {}).has_value());
  // A tie goes to the name listed first.
  CHECK(closest_name("ab", std::vector<std::string>{"ac", "ad"}) == "ac");
  CHECK(closest_name("ab", std::vector<std::string>{"ad", "ac"}) == "ad");
  // A closer name wins over an earlier one.
  CHECK(closest_name("omnii", std::vector<std::string>{"mecanum", "omn", "omni"}) == "omni");
}

TEST_CASE("The unknown-name message lists every known name in order, or none") {
  CHECK(unknown_name_message("controller type", "tank", {"differential", "mecanum", "omni"}) ==
        "unknown controller type 'tank'; known: differential, mecanum, omni");
  CHECK(unknown_name_message("process type", "net2", {"net"}) ==
        "unknown process type 'net2'; known: net; did you mean 'net'?");
  CHECK(unknown_name_message("resource type", "Laser", {}) == "unknown resource type 'Laser'; known: none");
}
