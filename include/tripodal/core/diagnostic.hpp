// Located diagnostics for configuration files (nets, robot profiles, maps): every loader collects
// all of a file's problems as Diagnostics and reports them gcc-style, FILE:LINE:COL: error: MSG,
// so an author fixes them in one pass and an editor can jump to each one.
#pragma once

#include <cstdint>
#include <filesystem>
#include <iosfwd>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace tripodal {

/// The name of a file as diagnostics show it. Names are interned: each distinct name is stored
/// once for the life of the process and a SourceFile points at it, so a SourceLocation (which
/// every place, transition and arc of a loaded net keeps) copies without allocating whatever the
/// path's length. Meant for the files a program loads, not for an endless stream of new names.
class SourceFile {
 public:
  SourceFile() noexcept = default;
  // Implicit, so that a location is written {"net.xml", 3, 1} or {path.string(), 0, 0}.
  SourceFile(std::string_view name);
  SourceFile(const std::string& name) : SourceFile(std::string_view(name)) {}
  SourceFile(const char* name) : SourceFile(std::string_view(name)) {}

  [[nodiscard]] const std::string& str() const noexcept;
  [[nodiscard]] bool empty() const noexcept { return name_ == nullptr; }
  operator const std::string&() const noexcept { return str(); }
  operator std::string_view() const noexcept { return str(); }

  friend bool operator==(const SourceFile& a, std::string_view b) noexcept { return std::string_view(a) == b; }

 private:
  const std::string* name_ = nullptr;  // interned; nullptr for no name
};

std::ostream& operator<<(std::ostream& os, const SourceFile& file);

/// Where something was written. line and column count from 1; 0 means unknown.
struct SourceLocation {
  SourceFile file;
  int line = 0;
  int column = 0;

  /// "file:line:col", omitting the parts that are unknown.
  [[nodiscard]] std::string str() const;
};

enum class Severity { note, warning, error };

struct Diagnostic {
  Severity severity = Severity::error;
  SourceLocation where;
  std::string message;

  /// gcc-style "FILE:LINE:COL: error: MESSAGE".
  [[nodiscard]] std::string str() const;
};

/// A list of diagnostics being collected for one or more files.
class Diagnostics {
 public:
  void error(SourceLocation where, std::string message);
  void warning(SourceLocation where, std::string message);
  void note(SourceLocation where, std::string message);
  void add(Diagnostic d);
  void append(const Diagnostics& other);

  [[nodiscard]] bool has_errors() const noexcept { return errors_ > 0; }
  [[nodiscard]] std::size_t error_count() const noexcept { return errors_; }
  [[nodiscard]] const std::vector<Diagnostic>& all() const noexcept { return items_; }
  [[nodiscard]] bool empty() const noexcept { return items_.empty(); }
  /// Every diagnostic, one per line, in the order they were added.
  [[nodiscard]] std::string str() const;

 private:
  std::vector<Diagnostic> items_;
  std::size_t errors_ = 0;
};

/// Thrown by a loader when a file has errors; what() lists every diagnostic, one per line.
class ConfigError : public std::runtime_error {
 public:
  explicit ConfigError(Diagnostics diagnostics);
  ConfigError(SourceLocation where, const std::string& message);
  [[nodiscard]] const Diagnostics& diagnostics() const noexcept { return diagnostics_; }

 private:
  Diagnostics diagnostics_;
};

/// The largest file a configuration loader reads (nets, event scripts, YAML files, map images):
/// 256 MiB, four times the largest map image (kMaxPgmPixels 16-bit samples). A bigger file is
/// refused before it is read, so a mistaken path to a disk image cannot exhaust memory.
inline constexpr std::uintmax_t kMaxConfigFileBytes = std::uintmax_t{256} << 20;

/// The whole of a configuration file, the one way every loader reads one. Throws ConfigError at
/// FILE: "cannot read the file" or "the file has N bytes, more than the M a configuration file
/// may have".
[[nodiscard]] std::string read_config_file(const std::filesystem::path& file);

}  // namespace tripodal
