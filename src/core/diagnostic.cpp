#include "tripodal/core/diagnostic.hpp"

#include <mutex>
#include <ostream>
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
  add({Severity::error, std::move(where), std::move(message)});
}
void Diagnostics::warning(SourceLocation where, std::string message) {
  add({Severity::warning, std::move(where), std::move(message)});
}
void Diagnostics::note(SourceLocation where, std::string message) {
  add({Severity::note, std::move(where), std::move(message)});
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
  d.error(std::move(where), message);
  return d;
}
}  // namespace

ConfigError::ConfigError(SourceLocation where, const std::string& message)
    : ConfigError(single(std::move(where), message)) {}

}  // namespace tripodal
