// Internal helpers of the navigation loaders: located diagnostics from yaml-cpp nodes and file
// reading with a located error.
#pragma once

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "tripodal/core/diagnostic.hpp"

namespace tripodal::navi::detail {

/// file:line:col of a node (yaml-cpp counts from 0, diagnostics from 1).
inline SourceLocation where(const std::string& file, const YAML::Node& node) {
  const YAML::Mark m = node.Mark();
  if (m.line < 0) return {file, 0, 0};
  return {file, m.line + 1, m.column + 1};
}

inline std::string kind_name(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Map: return "a map";
    case YAML::NodeType::Sequence: return "a list";
    case YAML::NodeType::Scalar: return "'" + node.Scalar() + "'";
    case YAML::NodeType::Null: return "nothing";
    default: return "undefined";
  }
}

/// The whole file, or a ConfigError naming it.
inline std::string read_text_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(SourceLocation{file.string(), 0, 0}, "cannot open file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Parses YAML text; a syntax error becomes a located ConfigError.
inline YAML::Node parse_yaml(std::string_view text, const std::string& file) {
  try {
    return YAML::Load(std::string(text));
  } catch (const YAML::ParserException& e) {
    throw ConfigError(SourceLocation{file, e.mark.line + 1, e.mark.column + 1}, e.msg);
  }
}

/// A finite double scalar, or an error at the node.
inline std::optional<double> as_double(const YAML::Node& n, const std::string& file, const std::string& what,
                                       Diagnostics& d) {
  if (n.IsScalar()) {
    try {
      const double v = n.as<double>();
      if (std::isfinite(v)) return v;
    } catch (const YAML::Exception&) {
    }
  }
  d.error(where(file, n), what + " must be a finite number, got " + kind_name(n));
  return std::nullopt;
}

}  // namespace tripodal::navi::detail
