#include "text.hpp"

#include <algorithm>
#include <array>
#include <cstdint>
#include <utility>

#include "tripodal/core/xml_text.hpp"

namespace tripodal::hri {

std::vector<std::string> words(std::string_view text) {
  std::vector<std::string> out;
  std::string word;
  for (std::size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    const auto u = static_cast<unsigned char>(c);
    // "PSR-1" is one name, "psr1": a hyphen before a digit joins (the digit would otherwise match
    // every other "1" of the base).
    if (c == '-' && !word.empty() && i + 1 < text.size() && text[i + 1] >= '0' && text[i + 1] <= '9') continue;
    if ((u >= 'a' && u <= 'z') || (u >= '0' && u <= '9') || u >= 0x80) {
      word += c;
    } else if (u >= 'A' && u <= 'Z') {
      word += static_cast<char>(u - 'A' + 'a');
    } else if (!word.empty()) {
      out.push_back(std::move(word));
      word.clear();
    }
  }
  if (!word.empty()) out.push_back(std::move(word));
  return out;
}

std::string_view expand_chat_word(std::string_view word) noexcept {
  // Sorted for binary search.
  static constexpr std::array<std::pair<std::string_view, std::string_view>, 12> kChat = {{
      {"b4", "before"},
      {"cu", "see"},
      {"pls", "please"},
      {"plz", "please"},
      {"r", "are"},
      {"thanx", "thanks"},
      {"thnx", "thanks"},
      {"thx", "thanks"},
      {"u", "you"},
      {"ur", "your"},
      {"wat", "what"},
      {"ya", "you"},
  }};
  const auto it =
      std::lower_bound(kChat.begin(), kChat.end(), word, [](const auto& entry, std::string_view w) { return entry.first < w; });
  return it != kChat.end() && it->first == word ? it->second : word;
}

bool is_stop_word(std::string_view word) noexcept {
  // Sorted for binary search. Kept short on purpose: "who", "where", "how" and "you" stay out
  // because entries are told apart by them ("who are you" vs "where are you").
  static constexpr std::array<std::string_view, 68> kStop = {
      "a",      "about", "am",    "an",    "and",  "any",   "anything", "are", "at",   "be",        "can",    "could",
      "d",      "do",    "does",  "for",   "give", "i",     "in",       "is",  "it",   "just",      "kindly", "know",
      "let",    "ll",    "m",     "may",   "me",   "might", "must",     "my",  "now",  "of",        "on",     "or",
      "please", "pls",   "re",    "s",     "say",  "shall", "should",   "so",  "some", "something", "t",      "tell",
      "than",   "that",  "the",   "there", "this", "to",    "too",      "us",  "ve",   "very",      "want",   "was",
      "we",     "what",  "whats", "will",  "with", "would", "yes",      "your"};
  return std::binary_search(kStop.begin(), kStop.end(), word);
}

std::size_t edit_distance(std::string_view a, std::string_view b, std::size_t limit) {
  const std::size_t n = a.size();
  const std::size_t m = b.size();
  if ((n > m ? n - m : m - n) > limit) return limit + 1;
  // Three rows: the transposition looks two rows back.
  std::vector<std::size_t> prev2(m + 1), prev(m + 1), cur(m + 1);
  for (std::size_t j = 0; j <= m; ++j) prev[j] = j;
  for (std::size_t i = 1; i <= n; ++i) {
    cur[0] = i;
    std::size_t row_min = cur[0];
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      std::size_t d = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) d = std::min(d, prev2[j - 2] + 1);
      cur[j] = d;
      row_min = std::min(row_min, d);
    }
    if (row_min > limit) return limit + 1;
    std::swap(prev2, prev);
    std::swap(prev, cur);
  }
  return std::min(prev[m], limit + 1);
}

bool is_text(std::string_view bytes) noexcept {
  // What XML 1.0 allows (every text of the HRI may end up in the knowledge file), without the C1
  // controls it only discourages.
  return !find_xml_text_fault(bytes, true).has_value();
}

bool has_digit(std::string_view word) noexcept {
  return std::any_of(word.begin(), word.end(), [](char c) { return c >= '0' && c <= '9'; });
}

const std::vector<std::vector<std::string_view>>& polite_openings() {
  static const std::vector<std::vector<std::string_view>> openings = {
      {"let", "s"},   {"let", "us"},    {"i", "would", "like", "you", "to"}, {"i", "want", "you", "to"},
      {"can", "you"}, {"could", "you"}, {"would", "you"},                    {"will", "you"},
      {"please"},     {"jinny"},        {"hey"},                             {"ok"},
  };
  return openings;
}

const std::vector<std::string_view>& polite_closings() {
  static const std::vector<std::string_view> closings = {"please", "jinny", "now"};
  return closings;
}

std::vector<std::string> without_politeness(std::vector<std::string> ws) {
  bool stripped = true;
  while (stripped && !ws.empty()) {
    stripped = false;
    for (const auto& opening : polite_openings()) {
      if (ws.size() > opening.size() && std::equal(opening.begin(), opening.end(), ws.begin())) {
        ws.erase(ws.begin(), ws.begin() + static_cast<std::ptrdiff_t>(opening.size()));
        stripped = true;
      }
    }
  }
  const auto& closings = polite_closings();
  while (ws.size() > 1 && std::find(closings.begin(), closings.end(), ws.back()) != closings.end()) ws.pop_back();
  return ws;
}

const std::vector<std::string_view>& yes_answers() {
  static const std::vector<std::string_view> yes = {"yes", "yeah", "yep", "sure", "ok", "okay", "correct", "right", "go ahead", "do it", "please do"};
  return yes;
}

const std::vector<std::string_view>& no_answers() {
  static const std::vector<std::string_view> no = {"no", "nope", "cancel", "wrong", "stop", "don't", "do not"};
  return no;
}

Answer yes_or_no(const std::vector<std::string>& ws) {
  const auto starts_with = [&](std::string_view phrase) {
    const std::vector<std::string> p = words(phrase);
    return !p.empty() && ws.size() >= p.size() && std::equal(p.begin(), p.end(), ws.begin());
  };
  // "ok" is also a polite opening; a bare "please" is the politeness itself, a yes.
  if (ws.size() == 1 && ws.front() == "please") return Answer::yes;
  if (std::any_of(no_answers().begin(), no_answers().end(), starts_with)) return Answer::no;
  if (std::any_of(yes_answers().begin(), yes_answers().end(), starts_with)) return Answer::yes;
  return Answer::neither;
}

}  // namespace tripodal::hri
