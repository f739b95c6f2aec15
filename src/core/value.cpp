#include "tripodal/core/value.hpp"

#include <charconv>
#include <cmath>
#include <cstdio>

namespace tripodal {

ValueType type_of(const Value& v) noexcept {
  switch (v.index()) {
    case 0: return ValueType::boolean;
    case 1: return ValueType::number;
    default: return ValueType::string;
  }
}

std::string_view to_string(ValueType t) noexcept {
  switch (t) {
    case ValueType::boolean: return "bool";
    case ValueType::number: return "number";
    case ValueType::string: return "string";
  }
  return "?";
}

std::optional<ValueType> parse_value_type(std::string_view text) noexcept {
  if (text == "bool" || text == "boolean") return ValueType::boolean;
  if (text == "number") return ValueType::number;
  if (text == "string") return ValueType::string;
  return std::nullopt;
}

std::optional<Value> parse_value(ValueType t, std::string_view text) {
  switch (t) {
    case ValueType::boolean:
      if (text == "true") return Value{true};
      if (text == "false") return Value{false};
      return std::nullopt;
    case ValueType::number: {
      double x = 0.0;
      const char* first = text.data();
      const char* last = text.data() + text.size();
      if (first != last && *first == '+') ++first;
      auto [ptr, ec] = std::from_chars(first, last, x);
      if (ec != std::errc{} || ptr != last || first == last || !std::isfinite(x)) return std::nullopt;
      return Value{x};
    }
    case ValueType::string:
      return Value{std::string(text)};
  }
  return std::nullopt;
}

std::string to_string(const Value& v) {
  switch (v.index()) {
    case 0: return std::get<bool>(v) ? "true" : "false";
    case 1: {
      char buf[32];
      std::snprintf(buf, sizeof buf, "%.15g", std::get<double>(v));
      return buf;
    }
    default: return '"' + std::get<std::string>(v) + '"';
  }
}

}  // namespace tripodal
