// Internal helpers shared by the planner's YAML loaders: located diagnostics from yaml-cpp nodes.
#pragma once

#include <yaml-cpp/yaml.h>

#include <string>
#include <string_view>

#include "tripodal/core/diagnostic.hpp"

namespace tripodal::detail {

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
    case YAML::NodeType::Scalar: return "a scalar";
    case YAML::NodeType::Null: return "nothing";
    default: return "undefined";
  }
}

}  // namespace tripodal::detail
