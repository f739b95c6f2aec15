// The one way every YAML loader (robot profiles, reactive configurations, worlds, regions, map
// descriptions, task templates, recovery rules) reads its file: parse errors and file errors as
// located ConfigErrors, and typed reads that collect every problem of a file as Diagnostics with
// the same wording everywhere: "WHAT: expected a number, got 'fast'", "unknown key 'x' in WHAT;
// expected one of: a, b". Internal (src/), never installed: no YAML::Node leaves a loader.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal::yaml {

/// The shortest period or timeout a configuration may give (s): 1 µs.
inline constexpr double kMinPeriodSeconds = 1e-6;

/// The keys a mapping may hold, in the order the error message lists them.
using KeyList = std::initializer_list<std::string_view>;

/// The whole file, or a ConfigError at FILE: "cannot read the file".
[[nodiscard]] std::string read_file(const std::filesystem::path& file);

/// Parses YAML text; a syntax error becomes a ConfigError at FILE:LINE:COL.
[[nodiscard]] YAML::Node parse(std::string_view text, const std::string& file);

/// Runs a loader's walk over its parsed nodes. The typed reads below never throw, but yaml-cpp
/// still does on a shape no read expected (a subscript of a text, a list as a key): that becomes
/// a ConfigError at the node's FILE:LINE:COL instead of a YAML exception without the file's name.
template <class Walk>
decltype(auto) guarded(const std::string& file, Walk&& walk) {
  try {
    return walk();
  } catch (const YAML::Exception& e) {
    throw ConfigError(SourceLocation{file, e.mark.line + 1, e.mark.column + 1}, "unexpected YAML structure: " + e.msg);
  }
}

/// What a node is, for messages: "a map", "a list", "'text'" (the scalar itself), "nothing".
[[nodiscard]] std::string kind(const YAML::Node& node);

/// Reads typed values out of one file's nodes; every problem is added to the diagnostics at the
/// node's FILE:LINE:COL and the read returns nullopt/false, so a loader reports all at once.
/// `what` names the value for the author ("robot.laser.beams", "controller 'base'").
class Reader {
 public:
  Reader(std::string file, Diagnostics& diagnostics) : file_(std::move(file)), d_(diagnostics) {}

  [[nodiscard]] const std::string& file() const noexcept { return file_; }
  [[nodiscard]] Diagnostics& diagnostics() noexcept { return d_; }

  /// FILE:LINE:COL of a node (yaml-cpp counts from 0, diagnostics from 1); 1:1 for the empty
  /// document, the one node without a position.
  [[nodiscard]] SourceLocation at(const YAML::Node& node) const;
  void error(const YAML::Node& node, std::string message);

  /// "WHAT: expected a map, got a list" unless node is a map.
  bool expect_map(const YAML::Node& node, std::string_view what);
  /// "WHAT: expected a list, got a map" unless node is a sequence.
  bool expect_list(const YAML::Node& node, std::string_view what);
  /// A map whose keys are all in `allowed`: each other key is reported at the key itself,
  /// "unknown key 'k' in WHAT; expected one of: a, b, c". False when node is not a map.
  bool expect_keys(const YAML::Node& map, KeyList allowed, std::string_view what);
  /// map[key], or "WHAT: missing 'KEY' (EXPECTED)" at the map and an undefined node.
  YAML::Node require(const YAML::Node& map, std::string_view key, std::string_view what, std::string_view expected);

  /// A map key's text. Keys a map does not constrain (parameters, process names) may be written
  /// as lists or maps (`? [a]: b`): "WHAT: a key must be text, got a list" at the key.
  std::optional<std::string> key(const YAML::Node& key, std::string_view what);
  /// The text of a key already checked by expect_keys, which reported a non-text key as
  /// unknown: "" for such a key, so the caller's dispatch skips it.
  [[nodiscard]] static std::string checked_key(const YAML::Node& key) { return key.IsScalar() ? key.Scalar() : std::string(); }
  /// A scalar's text ("WHAT: expected text, got a list"); non_empty also refuses "".
  std::optional<std::string> text(const YAML::Node& node, std::string_view what, bool non_empty = false);
  /// A finite number ("WHAT: expected a number, got 'fast'").
  std::optional<double> number(const YAML::Node& node, std::string_view what);
  /// A number > 0 (strictly) or >= 0: "WHAT: expected a number > 0, got -1".
  std::optional<double> positive(const YAML::Node& node, std::string_view what);
  std::optional<double> non_negative(const YAML::Node& node, std::string_view what);
  /// A duration in seconds within [min_s, max_s]: "WHAT: expected seconds from 1e-06 to 9e+09, got
  /// 1e-12". A period shorter than a microsecond rounds to no time at all (nanosecond clock) and
  /// one beyond kMaxSeconds would be capped: both are refused here, where the author wrote them.
  std::optional<double> seconds(const YAML::Node& node, std::string_view what, double min_s = kMinPeriodSeconds,
                                double max_s = kMaxSeconds);
  /// A whole number in [lo, hi]: "WHAT: expected a whole number from LO to HI, got 2.5".
  std::optional<std::int64_t> integer(const YAML::Node& node, std::string_view what, std::int64_t lo,
                                      std::int64_t hi);
  /// true/false (also yes/no, on/off, 1/0): "WHAT: expected true or false, got 'maybe'".
  std::optional<bool> boolean(const YAML::Node& node, std::string_view what);
  /// One of `choices`: "WHAT: expected one of a, b, c; got 'd'".
  std::optional<std::string> choice(const YAML::Node& node, std::string_view what, KeyList choices);
  /// A list of texts: "WHAT: expected a list of names, got a map".
  std::optional<std::vector<std::string>> names(const YAML::Node& node, std::string_view what);
  /// A list of min_count..max_count numbers: "WHAT: expected SHAPE, got a list of 5 items".
  std::optional<std::vector<double>> numbers(const YAML::Node& node, std::string_view what, std::size_t min_count,
                                             std::size_t max_count, std::string_view shape);

 private:
  std::string file_;
  Diagnostics& d_;
};

}  // namespace tripodal::yaml
