#include "tripodal/core/value.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;

TEST_CASE("values parse by declared type and refuse what does not fit") {
  CHECK(parse_value(ValueType::boolean, "true") == Value{true});
  CHECK_FALSE(parse_value(ValueType::boolean, "yes"));
  CHECK(parse_value(ValueType::number, "0.35") == Value{0.35});
  CHECK(parse_value(ValueType::number, "+2") == Value{2.0});
  CHECK_FALSE(parse_value(ValueType::number, "2m"));
  CHECK_FALSE(parse_value(ValueType::number, ""));
  CHECK_FALSE(parse_value(ValueType::number, "inf"));
  CHECK(parse_value(ValueType::string, "omni") == Value{std::string("omni")});
}

TEST_CASE("value types and printing") {
  CHECK(type_of(Value{1.0}) == ValueType::number);
  CHECK(parse_value_type("boolean") == ValueType::boolean);
  CHECK_FALSE(parse_value_type("int"));
  CHECK(to_string(Value{std::string("x")}) == "\"x\"");
  CHECK(to_string(Value{0.5}) == "0.5");
  CHECK(to_string(Value{false}) == "false");
}
