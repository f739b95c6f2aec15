// The phrasings of a request a visitor uses around the task grammar's literal commands (docs/hri.md,
// "The command grammar"): stripped or rewritten here, so the planner's templates stay literal.
#include <algorithm>
#include <array>

#include "text.hpp"

namespace tripodal::hri {

namespace {

using Phrase = std::vector<std::string_view>;

bool starts_with(const std::vector<std::string>& ws, std::size_t at, const Phrase& p) {
  if (ws.size() - at < p.size()) return false;
  return std::equal(p.begin(), p.end(), ws.begin() + static_cast<std::ptrdiff_t>(at));
}

bool ends_with(const std::vector<std::string>& ws, const Phrase& p) {
  return ws.size() >= p.size() && std::equal(p.begin(), p.end(), ws.end() - static_cast<std::ptrdiff_t>(p.size()));
}

// Said before a request; stripped repeatedly, longest first where they share a start. The request
// itself is never stripped away entirely.
const std::vector<Phrase>& openings() {
  static const std::vector<Phrase> list = {
      {"i", "would", "like", "you", "to"},
      {"i", "d", "like", "you", "to"},
      {"i", "want", "you", "to"},
      {"we", "would", "like", "you", "to"},
      {"we", "want", "you", "to"},
      {"could", "you"},
      {"would", "you"},
      {"can", "you"},
      {"will", "you"},
      {"would", "you", "mind"},
      {"let", "s"},
      {"lets"},
      {"um"},
      {"uh"},
      {"er"},
      {"erm"},
      {"hmm"},
      {"well"},
      {"so"},
      {"okay"},
      {"ok"},
      {"please"},
      {"kindly"},
      {"jinny"},
      {"hey"},
      {"hi"},
      {"hello"},
      {"oh"},
      {"and"},
      {"robot"},
  };
  return list;
}

// Said after a request; stripped repeatedly.
const std::vector<Phrase>& tails() {
  static const std::vector<Phrase> list = {
      {"for", "me"},
      {"for", "us"},
      {"to", "me"},
      {"to", "us"},
      {"if", "you", "can"},
      {"if", "you", "could"},
      {"if", "you", "would"},
      {"if", "possible"},
      {"if", "you", "please"},
      {"right", "now"},
      {"now"},
      {"please"},
      {"jinny"},
      {"thanks"},
      {"thank", "you"},
      {"ok"},
      {"okay"},  // not "robot": "explain this robot"
  };
  return list;
}

// A visitor's way in to a place, and the grammar's: "i want to go to node 1" -> "go to node 1".
struct Rewrite {
  Phrase from;
  Phrase to;
};
const std::vector<Rewrite>& rewrites() {
  static const std::vector<Rewrite> list = {
      {{"i", "want", "to", "go", "to"}, {"go", "to"}},
      {{"we", "want", "to", "go", "to"}, {"go", "to"}},
      {{"i", "would", "like", "to", "go", "to"}, {"go", "to"}},
      {{"we", "would", "like", "to", "go", "to"}, {"go", "to"}},
      {{"i", "d", "like", "to", "go", "to"}, {"go", "to"}},
      {{"i", "need", "to", "go", "to"}, {"go", "to"}},
      {{"i", "want", "to", "see"}, {"take", "me", "to"}},
      {{"we", "want", "to", "see"}, {"take", "me", "to"}},
      {{"i", "would", "like", "to", "see"}, {"take", "me", "to"}},
      {{"we", "would", "like", "to", "see"}, {"take", "me", "to"}},
      {{"i", "d", "like", "to", "see"}, {"take", "me", "to"}},
      {{"let", "us", "go", "to"}, {"go", "to"}},
      {{"lead", "the", "way", "to"}, {"guide", "me", "to"}},
      {{"show", "the", "way", "to"}, {"guide", "me", "to"}},
      {{"walk", "me", "to"}, {"guide", "me", "to"}},
      {{"walk", "us", "to"}, {"guide", "me", "to"}},
      {{"escort", "me", "to"}, {"guide", "me", "to"}},
      {{"escort", "us", "to"}, {"guide", "me", "to"}},
  };
  return list;
}

bool is_guiding_verb(std::string_view w) {
  return w == "guide" || w == "take" || w == "lead" || w == "bring" || w == "show";
}

}  // namespace

std::string number_word_as_digits(const std::string& word) {
  static constexpr std::array<std::string_view, 21> kNumbers = {
      "zero", "one", "two", "three", "four", "five", "six", "seven", "eight", "nine", "ten",
      "eleven", "twelve", "thirteen", "fourteen", "fifteen", "sixteen", "seventeen", "eighteen", "nineteen", "twenty"};
  for (std::size_t i = 0; i < kNumbers.size(); ++i) {
    if (word == kNumbers[i]) return std::to_string(i);
  }
  if (word == "oh" || word == "o") return "0";
  return word;
}

std::vector<std::string> command_phrasing(std::vector<std::string> ws) {
  bool changed = true;
  while (changed && !ws.empty()) {
    changed = false;
    for (const auto& p : openings()) {
      if (ws.size() > p.size() && starts_with(ws, 0, p)) {
        ws.erase(ws.begin(), ws.begin() + static_cast<std::ptrdiff_t>(p.size()));
        changed = true;
      }
    }
    for (const auto& p : tails()) {
      if (ws.size() > p.size() && ends_with(ws, p)) {
        ws.erase(ws.end() - static_cast<std::ptrdiff_t>(p.size()), ws.end());
        changed = true;
      }
    }
  }
  for (const auto& r : rewrites()) {
    if (starts_with(ws, 0, r.from)) {
      ws.erase(ws.begin(), ws.begin() + static_cast<std::ptrdiff_t>(r.from.size()));
      ws.insert(ws.begin(), r.to.begin(), r.to.end());
      break;
    }
  }
  // "take us to", "bring us to": the grammar is written for one visitor.
  for (std::size_t i = 1; i < ws.size(); ++i) {
    if (ws[i] == "us" && is_guiding_verb(ws[i - 1])) ws[i] = "me";
  }
  // "take me to the robot at node 1": the place is the node.
  for (std::size_t i = 0; i + 4 < ws.size(); ++i) {
    if (ws[i] == "to" && ws[i + 1] == "the" && (ws[i + 2] == "robot" || ws[i + 2] == "exhibit") && ws[i + 3] == "at") {
      ws.erase(ws.begin() + static_cast<std::ptrdiff_t>(i) + 1, ws.begin() + static_cast<std::ptrdiff_t>(i) + 4);
    }
  }
  for (std::size_t i = 0; i < ws.size(); ++i) {
    // "show me node 1" is a request to be taken there ("show me a dance" is a command of its own).
    if (ws[i] == "show" && i + 1 < ws.size() && ws[i + 1] == "me" && i + 2 < ws.size() &&
        (ws[i + 2] == "node" || (ws[i + 2] == "the" && i + 3 < ws.size() && ws[i + 3] == "node"))) {
      ws[i] = "take";
      ws.insert(ws.begin() + static_cast<std::ptrdiff_t>(i) + 2, "to");
    }
    if (ws[i] == "node" && i + 1 < ws.size()) {
      if (ws[i + 1] == "number" && i + 2 < ws.size()) ws.erase(ws.begin() + static_cast<std::ptrdiff_t>(i) + 1);
      if (i + 1 < ws.size()) ws[i + 1] = number_word_as_digits(ws[i + 1]);
    }
  }
  return ws;
}

}  // namespace tripodal::hri
