// Where a line stands in a shipped file, for tests that check an error's FILE:LINE: the files grow
// as the robots do, and a hard-coded line number breaks with every entry added above it.
#pragma once

#include <filesystem>
#include <fstream>
#include <string>

namespace tripodal::test {

/// "NAME:N:" for the first line of `path` equal to `line` (NAME the file's name), as located
/// errors print it; a text naming what is missing otherwise, which no error contains.
inline std::string located_line(const std::filesystem::path& path, const std::string& line) {
  std::ifstream in(path);
  std::string text;
  for (int n = 1; std::getline(in, text); ++n) {
    if (text == line) return path.filename().string() + ":" + std::to_string(n) + ":";
  }
  return "no line '" + line + "' in " + path.string();
}

}  // namespace tripodal::test
