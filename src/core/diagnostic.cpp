#include "tripodal/core/diagnostic.hpp"

#include <fstream>
#include <mutex>
#include <ostream>
#include <sstream>
#include <unordered_set>
#include <utility>

namespace tripodal {

namespace {

// Node-based, so that an interned name never moves; names are never removed.
struct FileNames {
  std::mutex mutex;
  std::unordered_set<std::string> names;
};

FileNames& file_names() {
  static FileNames names;
  return names;
}

const std::string kNoName;

}  // namespace

SourceFile::SourceFile(std::string_view name) {
  if (name.empty()) return;
  FileNames& interned = file_names();
  const std::scoped_lock lock(interned.mutex);
  name_ = &*interned.names.emplace(name).first;
}

const std::string& SourceFile::str() const noexcept { return name_ == nullptr ? kNoName : *name_; }

std::ostream& operator<<(std::ostream& os, const SourceFile& file) { return os << file.str(); }

std::string SourceLocation::str() const {
  std::string out = file.empty() ? std::string("<input>") : file.str();
  if (line > 0) {
    out += ':' + std::to_string(line);
    if (column > 0) out += ':' + std::to_string(column);
  }
  return out;
}

std::string Diagnostic::str() const {
  const char* kind = severity == Severity::error ? "error" : severity == Severity::warning ? "warning" : "note";
  return where.str() + ": " + kind + ": " + message;
}

void Diagnostics::error(SourceLocation where, std::string message) {
  add({Severity::error, where, std::move(message)});
}
void Diagnostics::warning(SourceLocation where, std::string message) {
  add({Severity::warning, where, std::move(message)});
}
void Diagnostics::note(SourceLocation where, std::string message) {
  add({Severity::note, where, std::move(message)});
}
void Diagnostics::add(Diagnostic d) {
  if (d.severity == Severity::error) ++errors_;
  items_.push_back(std::move(d));
}
void Diagnostics::append(const Diagnostics& other) {
  for (const auto& d : other.all()) add(d);
}
std::string Diagnostics::str() const {
  std::string out;
  for (const auto& d : items_) {
    out += d.str();
    out += '\n';
  }
  return out;
}

ConfigError::ConfigError(Diagnostics diagnostics)
    : std::runtime_error(diagnostics.str()), diagnostics_(std::move(diagnostics)) {}

namespace {
Diagnostics single(SourceLocation where, const std::string& message) {
  Diagnostics d;
  d.error(where, message);
  return d;
}
}  // namespace

ConfigError::ConfigError(SourceLocation where, const std::string& message)
    : ConfigError(single(where, message)) {}

std::string read_config_file(const std::filesystem::path& file) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(SourceLocation{file.string(), 0, 0}, "cannot read the file");
  std::error_code ec;
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  // A size that cannot be told (a pipe, /dev/stdin) is read as it comes.
  if (!ec && size > kMaxConfigFileBytes) {
    throw ConfigError(SourceLocation{file.string(), 0, 0},
                      "the file has " + std::to_string(size) + " bytes, more than the " +
                          std::to_string(kMaxConfigFileBytes) + " a configuration file may have");
  }
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(SourceLocation{file.string(), 0, 0}, "cannot read the file");
  return text.str();
}

}  // namespace tripodal
