// Timed event scripts for simulating a configuration net without a robot (`tripodal-net
// simulate`): one event or fact change per line, at a time in seconds. Format in docs/engine.md.
#pragma once

#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal {

struct ScriptEntry {
  enum class Kind { event, set_fact };
  Time time{};
  Kind kind = Kind::event;
  std::string name;        ///< the event, or the fact to set
  std::string value_text;  ///< set_fact: the value as written (quotes removed)
  bool value_quoted = false;
  SourceLocation where;        ///< of the time at the start of the line
  SourceLocation name_where;   ///< of the event or fact name
  SourceLocation value_where;  ///< of the value (set_fact)
};

struct EventScript {
  std::string source;  ///< file name used in diagnostics
  std::vector<ScriptEntry> entries;  ///< ascending time; file order at equal times
};

/// Parses a script. Throws ConfigError listing every bad line as "SOURCE:LINE:COL: error: ...".
[[nodiscard]] EventScript parse_event_script(std::string_view text, std::string_view source = "<script>");
/// Reads and parses a file; throws ConfigError (also when it cannot be read).
[[nodiscard]] EventScript load_event_script(const std::filesystem::path& file);

}  // namespace tripodal
