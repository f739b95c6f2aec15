#include "tripodal/core/guard.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;

namespace {
bool eval(const Guard& g, std::initializer_list<const Value*> slots) {
  const std::vector<const Value*> v(slots);
  return g.evaluate(v);
}
}  // namespace

TEST_CASE("guards select a behavior by a process parameter") {
  const Guard g = Guard::parse("wheel_type == 'omni'");
  REQUIRE(g.identifiers() == std::vector<std::string>{"wheel_type"});
  CHECK(g.expected_type(0) == ValueType::string);
  const Value omni{std::string("omni")};
  const Value diff{std::string("differential")};
  CHECK(eval(g, {&omni}));
  CHECK_FALSE(eval(g, {&diff}));
}

TEST_CASE("precedence: ! binds tighter than &&, && tighter than ||") {
  const Guard g = Guard::parse("!a || b && c > 2.5");
  REQUIRE(g.identifiers() == std::vector<std::string>{"a", "b", "c"});
  CHECK(g.expected_type(0) == ValueType::boolean);
  CHECK(g.expected_type(2) == ValueType::number);
  const Value t{true}, f{false}, three{3.0}, two{2.0};
  CHECK(eval(g, {&f, &f, &two}));       // !a
  CHECK_FALSE(eval(g, {&t, &t, &two}));  // b && c>2.5 false
  CHECK(eval(g, {&t, &t, &three}));
  CHECK(Guard::parse("(a || b) && !c").evaluate(std::vector<const Value*>{&t, &f, &f}));
}

TEST_CASE("comparisons across types and missing values are false, not errors") {
  const Guard g = Guard::parse("battery_v < 12");
  const Value s{std::string("low")}, v{11.5};
  CHECK(eval(g, {&v}));
  CHECK_FALSE(eval(g, {&s}));
  CHECK_FALSE(eval(g, {nullptr}));
  CHECK_FALSE(Guard::parse("x != 1").evaluate(std::vector<const Value*>{&s}));
}

TEST_CASE("literals, dotted names and numbers in exponent form") {
  CHECK(Guard::parse("true").evaluate({}));
  CHECK_FALSE(Guard::parse("!true").evaluate({}));
  CHECK(Guard::parse("1e3 == 1000").evaluate({}));
  CHECK(Guard::parse("-0.5 < 0").evaluate({}));
  CHECK(Guard::parse("\"b\" > 'a'").evaluate({}));
  CHECK(Guard::parse("localizer.ok").identifiers() == std::vector<std::string>{"localizer.ok"});
}

TEST_CASE("syntax errors name the column of the fault") {
  auto column_of = [](const char* text) {
    try {
      (void)Guard::parse(text);
    } catch (const GuardSyntaxError& e) {
      return e.column();
    }
    return -1;
  };
  CHECK(column_of("a == ") == 6);
  CHECK(column_of("a = 1") == 3);
  CHECK(column_of("(a && b") == 8);
  CHECK(column_of("a && 'open") == 6);
  CHECK(column_of("a b") == 3);
  CHECK(column_of("1.2.3 > x") == 1);
  CHECK(column_of("") == 1);
  CHECK(column_of("a & b") == 3);
  CHECK_THROWS_WITH(Guard::parse("a == "), Catch::Contains("column 6") && Catch::Contains("expected a value"));
}

TEST_CASE("guards copy and move with their parsed form") {
  Guard a = Guard::parse("x > 1");
  Guard b = a;
  Guard c = std::move(a);
  const Value two{2.0};
  CHECK(b.evaluate(std::vector<const Value*>{&two}));
  CHECK(c.text() == "x > 1");
}

TEST_CASE("compared_literals lists the literals compared with one identifier", "[guard]") {
  const Guard g = Guard::parse("speed_mps < 0.5 && (mode == 'fast' || 'slow' == mode || mode == 'fast') && !armed");
  REQUIRE(g.identifiers() == std::vector<std::string>{"speed_mps", "mode", "armed"});
  CHECK(g.compared_literals(0) == std::vector<Value>{Value{0.5}});
  CHECK(g.compared_literals(1) == std::vector<Value>{Value{std::string("fast")}, Value{std::string("slow")}});
  CHECK(g.compared_literals(2).empty());
}

TEST_CASE("three-valued evaluation: parameters known, facts unknown", "[guard]") {
  using T = Guard::Truth;
  auto partial = [](const Guard& g, std::initializer_list<const Value*> slots) {
    const std::vector<const Value*> v(slots);
    return g.partial_evaluate(v);
  };
  const Value no{false};
  const Value yes{true};
  const Value full{95.0};
  // The hang of issue 40: a false parameter in a conjunction decides it whatever the fact says.
  const Guard charge = Guard::parse("auto_charge && battery_percent >= full_percent");
  REQUIRE(charge.identifiers() == std::vector<std::string>{"auto_charge", "battery_percent", "full_percent"});
  CHECK(partial(charge, {&no, nullptr, &full}) == T::no);
  CHECK(partial(charge, {&yes, nullptr, &full}) == T::unknown);
  CHECK(partial(Guard::parse("!auto_charge || battery_low"), {&no, nullptr}) == T::yes);
  CHECK(partial(Guard::parse("!auto_charge || battery_low"), {&yes, nullptr}) == T::unknown);
  CHECK(partial(Guard::parse("!(auto_charge && battery_low)"), {&no, nullptr}) == T::yes);
  CHECK(partial(Guard::parse("!battery_low"), {nullptr}) == T::unknown);
  // Comparisons reading an unknown value are unknown, also '!=' (evaluate() makes it false for a
  // missing value, true for a different one).
  CHECK(partial(Guard::parse("mode != 'x'"), {nullptr}) == T::unknown);
  // Without unknowns it is evaluate().
  const Value slow{std::string("slow")};
  CHECK(partial(Guard::parse("mode == 'fast' || mode == 'slow'"), {&slow}) == T::yes);
  CHECK(partial(Guard::parse("mode == 'fast'"), {&slow}) == T::no);
  // A decided result holds for every value of the unknowns.
  const Guard g = Guard::parse("(p || f) && !(q && f)");
  for (const Value* p : {&no, &yes}) {
    for (const Value* q : {&no, &yes}) {
      const T t = partial(g, {p, nullptr, q});
      if (t == T::unknown) continue;
      for (const Value* f : {&no, &yes}) CHECK(eval(g, {p, f, q}) == (t == T::yes));
    }
  }
}
