// Typed values of process parameters and facts: what guards compare and what places pass to the
// behaviors they bind. Three types, as in the guard language: boolean, number, string.
#pragma once

#include <optional>
#include <string>
#include <string_view>
#include <variant>

namespace tripodal {

enum class ValueType { boolean, number, string };

/// A parameter or fact value. Numbers are doubles (SI units; the name says which).
using Value = std::variant<bool, double, std::string>;

[[nodiscard]] ValueType type_of(const Value& v) noexcept;
[[nodiscard]] std::string_view to_string(ValueType t) noexcept;
/// "bool", "boolean", "number", "string" -> ValueType; nullopt otherwise.
[[nodiscard]] std::optional<ValueType> parse_value_type(std::string_view text) noexcept;
/// Parses `text` as a value of type `t` ("true"/"false", a decimal number, any string);
/// nullopt when it does not parse.
[[nodiscard]] std::optional<Value> parse_value(ValueType t, std::string_view text);
/// Human-readable form: true, 0.5, "kitchen" (strings quoted).
[[nodiscard]] std::string to_string(const Value& v);

}  // namespace tripodal
