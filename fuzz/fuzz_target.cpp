#include "fuzz_target.hpp"

#include <cstdio>
#include <cstdlib>

namespace tripodal::fuzz {

void require(bool ok, std::string_view what, std::string_view detail) {
  if (ok) return;
  std::fprintf(stderr, "\n*** fuzz property failed: %.*s\n%.*s\n", static_cast<int>(what.size()), what.data(),
               static_cast<int>(detail.size()), detail.data());
  std::abort();
}

void require_located(const ConfigError& error, std::string_view file) {
  const Diagnostics& d = error.diagnostics();
  require(d.has_errors(), "a ConfigError lists at least one error", error.what());
  for (const Diagnostic& item : d.all()) {
    if (item.severity != Severity::error) continue;
    const std::string_view named = item.where.file;
    require(file.empty() ? !named.empty() : named == file, "an error names the file it came from", item.str());
    const bool at_line = item.where.line > 0;
    const bool at_byte = item.message.rfind("at byte ", 0) == 0;
    require(at_line || at_byte, "an error is located (a line, or 'at byte N')", item.str());
  }
}

}  // namespace tripodal::fuzz
