#include "tripodal/core/registry.hpp"

#include <algorithm>
#include <cctype>

namespace tripodal {

namespace {

char folded(char c) noexcept { return static_cast<char>(std::tolower(static_cast<unsigned char>(c))); }

// Levenshtein distance with case folded: "bhcleaning" and "BhCleaning" are the same name to a
// reader, so a wrong case alone must always get the suggestion.
std::size_t edit_distance(std::string_view a, std::string_view b) {
  std::vector<std::size_t> row(b.size() + 1);
  for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    std::size_t diagonal = row[0];
    row[0] = i;
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t above = row[j];
      const std::size_t substitute = diagonal + (folded(a[i - 1]) == folded(b[j - 1]) ? 0 : 1);
      row[j] = std::min({above + 1, row[j - 1] + 1, substitute});
      diagonal = above;
    }
  }
  return row[b.size()];
}

}  // namespace

std::optional<std::string> closest_name(std::string_view name, const std::vector<std::string>& known) {
  const std::string* best = nullptr;
  std::size_t best_distance = 0;
  for (const auto& candidate : known) {
    // Measured on the longer of the two names, so that a truncated name ("BhClean") still finds
    // the full one ("BhCleaning", 3 edits).
    const std::size_t allowed = std::max<std::size_t>(2, std::max(name.size(), candidate.size()) / 3);
    const std::size_t d = edit_distance(name, candidate);
    if (d <= allowed && (best == nullptr || d < best_distance)) {
      best = &candidate;
      best_distance = d;
    }
  }
  if (best == nullptr) return std::nullopt;
  return *best;
}

std::string unknown_name_message(std::string_view kind, std::string_view name, const std::vector<std::string>& known) {
  std::string out = "unknown " + std::string(kind) + " '" + std::string(name) + "'; known: ";
  if (known.empty()) out += "none";
  for (std::size_t i = 0; i < known.size(); ++i) out += (i == 0 ? "" : ", ") + known[i];
  if (auto suggestion = closest_name(name, known)) out += "; did you mean '" + *suggestion + "'?";
  return out;
}

}  // namespace tripodal
