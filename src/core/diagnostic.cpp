#include "tripodal/core/diagnostic.hpp"

#include <filesystem>
#include <fstream>
#include <mutex>
#include <ostream>
#include <sstream>
#include <string>
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
  const SourceLocation where{file.string(), 0, 0};
  // Only a regular file has a size to check before reading: a device (/dev/zero), a FIFO or a
  // socket would be read until memory runs out, or block forever, and a directory has no text.
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(file, ec);
  if (ec || !std::filesystem::exists(st)) throw ConfigError(where, "cannot read the file");
  if (!std::filesystem::is_regular_file(st)) {
    const char* what = std::filesystem::is_directory(st)       ? "a directory"
                       : std::filesystem::is_fifo(st)          ? "a FIFO"
                       : std::filesystem::is_character_file(st) ? "a character device"
                       : std::filesystem::is_block_file(st)     ? "a block device"
                       : std::filesystem::is_socket(st)         ? "a socket"
                                                                : "not a file";
    throw ConfigError(where, std::string("cannot read ") + what + ": a configuration file must be a regular file");
  }
  const auto too_big = [&](std::uintmax_t size) {
    return ConfigError(where, "the file has " + std::to_string(size) + " bytes, more than the " +
                                  std::to_string(kMaxConfigFileBytes) + " a configuration file may have");
  };
  const std::uintmax_t size = std::filesystem::file_size(file, ec);
  if (!ec && size > kMaxConfigFileBytes) throw too_big(size);
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(where, "cannot read the file");
  // Read no more than the limit even so: the file may grow (or be swapped) after the check.
  std::string text;
  text.resize(static_cast<std::size_t>(ec ? 0 : size));
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (in.bad()) throw ConfigError(where, "cannot read the file");
  char chunk[65536];
  while (in && !in.eof()) {
    in.read(chunk, sizeof chunk);
    text.append(chunk, static_cast<std::size_t>(in.gcount()));
    if (text.size() > kMaxConfigFileBytes) throw too_big(text.size());
  }
  if (in.bad()) throw ConfigError(where, "cannot read the file");
  return text;
}

}  // namespace tripodal
