// Guard expressions of transitions: a small language over process parameters and facts
// (comparisons, &&, ||, !, numbers, strings, booleans, parentheses). A guard is parsed once when
// a net is loaded; at run time it is evaluated against values in slots, never re-parsed.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/value.hpp"

namespace tripodal {

/// A guard that does not parse. column() counts from 1 within the guard text.
class GuardSyntaxError : public std::runtime_error {
 public:
  GuardSyntaxError(int column, const std::string& message);
  [[nodiscard]] int column() const noexcept { return column_; }

 private:
  int column_;
};

/// A parsed guard. Identifiers are numbered in order of first appearance; evaluation reads the
/// value of identifier i from slot i.
class Guard {
 public:
  /// Parses `text`; throws GuardSyntaxError with the column of the fault.
  [[nodiscard]] static Guard parse(std::string_view text);

  Guard(const Guard& other);
  Guard& operator=(const Guard& other);
  Guard(Guard&&) noexcept;
  Guard& operator=(Guard&&) noexcept;
  ~Guard();

  [[nodiscard]] const std::string& text() const noexcept;
  /// The parameter and fact names the guard reads, in slot order.
  [[nodiscard]] const std::vector<std::string>& identifiers() const noexcept;
  /// The type the guard needs each identifier to have, where the expression implies one
  /// (compared with a number literal -> number, used as a condition -> boolean); nullopt otherwise.
  /// Loaders use it to report a guard that compares a parameter with the wrong type.
  [[nodiscard]] std::optional<ValueType> expected_type(std::size_t slot) const noexcept;
  /// The literals the identifier in `slot` is compared with directly (`wheel_type == 'omni'`),
  /// each once, in order of appearance. The analysis uses them as the values that matter.
  [[nodiscard]] std::vector<Value> compared_literals(std::size_t slot) const;
  /// Evaluates with slot values (slots.size() == identifiers().size()). Comparing values of
  /// different types is false, never an exception: a guard is a condition, not a program.
  [[nodiscard]] bool evaluate(std::span<const Value* const> slots) const noexcept;

  /// Three-valued (Kleene) evaluation with some values unknown (slot nullptr): the verdict of a
  /// check, where parameters are constants and facts may take any value. `false && x` is false
  /// and `true || x` true whatever x; a comparison reading an unknown value is unknown. A result
  /// other than unknown is what evaluate() gives for every value of the unknown slots.
  enum class Truth : std::uint8_t { no, yes, unknown };
  [[nodiscard]] Truth partial_evaluate(std::span<const Value* const> slots) const noexcept;

  struct Impl;

 private:
  explicit Guard(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal
