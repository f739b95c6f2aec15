#include "tripodal/hri/lexicon.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <array>
#include <cstdlib>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>
#include <stdexcept>
#include <unordered_map>
#include <unordered_set>

namespace tripodal {

namespace {

// WordNet's four parts of speech, in the order of their files.
constexpr std::array<std::string_view, 4> kPosNames = {"noun", "verb", "adj", "adv"};

// How close a related word is to the one asked about. A synonym says the same; a broader or a
// narrower term ("restaurant" for "cafeteria") and a derivation ("maker" for "make") say less, and
// are weighed so that an utterance matched through them alone stays below an exact match. A
// broader term least: "fly" and "swim" are kinds of "move", yet not what a robot that rolls does.
constexpr double kSynonym = 1.0;
constexpr double kHypernym = 0.5;
constexpr double kHyponym = 0.7;
constexpr double kDerivation = 0.8;
constexpr double kSimilar = 0.8;
// A sense counts when the Semantic Concordance met it at least this share as often as the word's
// first sense: "song" is a piece of music, not a bird's call (which made "sing me a song" a
// question about Jinny's name, "what should I call you").
constexpr double kMinSenseShare = 0.25;

// WordNet's detachment rules (morphy): the suffix of an inflected form and what replaces it.
struct Detachment {
  std::string_view suffix;
  std::string_view ending;
};
constexpr std::array<Detachment, 8> kNounRules = {
    {{"s", ""}, {"ses", "s"}, {"xes", "x"}, {"zes", "z"}, {"ches", "ch"}, {"shes", "sh"}, {"men", "man"}, {"ies", "y"}}};
constexpr std::array<Detachment, 8> kVerbRules = {
    {{"s", ""}, {"ies", "y"}, {"es", "e"}, {"es", ""}, {"ed", "e"}, {"ed", ""}, {"ing", "e"}, {"ing", ""}}};
constexpr std::array<Detachment, 4> kAdjRules = {{{"er", ""}, {"est", ""}, {"er", "e"}, {"est", "e"}}};

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open the lexicon's file (is the package installed?)");
  std::ostringstream out;
  out << in.rdbuf();
  return out.str();
}

bool is_single_word(std::string_view lemma) {
  return !lemma.empty() && std::all_of(lemma.begin(), lemma.end(), [](char c) { return c >= 'a' && c <= 'z'; });
}

}  // namespace

struct Lexicon::Impl {
  std::string wordnet_dir;
  // Per part of speech: each lemma's synset offsets into its data file, most frequent sense first,
  // and how many of them the Semantic Concordance saw in use (0 for a word rare in text: "wether").
  struct Lemma {
    std::vector<std::uint32_t> offsets;
    std::size_t tagged = 0;
  };
  std::array<std::unordered_map<std::string, Lemma>, 4> index;
  // Per part of speech: irregular forms and their base forms ("made" -> "make").
  std::array<std::unordered_map<std::string, std::vector<std::string>>, 4> exceptions;
  std::unordered_set<std::string> word_list;
  // Each lemma's tagged occurrences in the Semantic Concordance, over its senses and parts of speech.
  std::unordered_map<std::string, std::size_t> counts;
  // Each sense's count, by "lemma%ss_type#sense" (ss_type 1 noun, 2 verb, 3 adjective, 4 adverb).
  std::unordered_map<std::string, std::size_t> sense_counts;

  [[nodiscard]] std::size_t sense_count(const std::string& lemma, std::size_t pos, std::size_t sense) const {
    const auto it = sense_counts.find(lemma + "%" + std::to_string(pos + 1) + "#" + std::to_string(sense));
    return it == sense_counts.end() ? 0 : it->second;
  }

  void read_counts(const std::string& path) {
    std::ifstream in(path);
    if (!in) {
      spdlog::warn("hri: {}: cannot open WordNet's sense counts; every word counts as rare", path);
      return;
    }
    // "know%2:31:01:: 1 672": a sense key (lemma%...), its sense number, its count.
    std::string key;
    std::size_t sense = 0;
    std::size_t count = 0;
    while (in >> key >> sense >> count) {
      const std::size_t percent = key.find('%');
      if (percent == std::string::npos) continue;
      counts[key.substr(0, percent)] += count;
      if (percent + 1 < key.size()) {
        // Satellite adjectives (5) are numbered among the adjectives (3).
        const char type = key[percent + 1] == '5' ? '3' : key[percent + 1];
        sense_counts[key.substr(0, percent) + "%" + type + "#" + std::to_string(sense)] += count;
      }
    }
  }

  void read_index(std::size_t pos) {
    const std::string path = wordnet_dir + "/index." + std::string(kPosNames[pos]);
    const std::string text = read_file(path);
    std::istringstream in(text);
    std::string line;
    std::size_t line_no = 0;
    while (std::getline(in, line)) {
      ++line_no;
      if (line.empty() || line[0] == ' ') continue;  // the licence at the top is indented
      std::istringstream fields(line);
      std::string lemma;
      std::string pos_letter;
      std::size_t synsets = 0;
      std::size_t pointers = 0;
      fields >> lemma >> pos_letter >> synsets >> pointers;
      std::string skip;
      for (std::size_t i = 0; i < pointers; ++i) fields >> skip;
      std::size_t sense_count = 0;
      std::size_t tagged = 0;
      fields >> sense_count >> tagged;
      std::vector<std::uint32_t> offsets;
      for (std::size_t i = 0; i < synsets; ++i) {
        unsigned long offset = 0;
        if (!(fields >> offset)) break;
        offsets.push_back(static_cast<std::uint32_t>(offset));
      }
      if (!fields && offsets.size() != synsets) {
        throw std::runtime_error(path + ":" + std::to_string(line_no) + ": malformed WordNet index line");
      }
      index[pos].emplace(std::move(lemma), Lemma{std::move(offsets), tagged});
    }
  }

  void read_exceptions(std::size_t pos) {
    const std::string path = wordnet_dir + "/" + std::string(kPosNames[pos]) + ".exc";
    std::istringstream in(read_file(path));
    std::string line;
    while (std::getline(in, line)) {
      std::istringstream fields(line);
      std::string inflected;
      std::string base;
      fields >> inflected;
      while (fields >> base) exceptions[pos][inflected].push_back(base);
    }
  }

  [[nodiscard]] bool has(std::size_t pos, const std::string& lemma) const { return index[pos].count(lemma) != 0; }

  // Base forms of `word` for one part of speech (morphy).
  void forms(std::size_t pos, const std::string& word, std::vector<std::pair<std::size_t, std::string>>& out) const {
    auto add = [&](const std::string& f) {
      if (has(pos, f) && std::find(out.begin(), out.end(), std::make_pair(pos, f)) == out.end()) out.emplace_back(pos, f);
    };
    add(word);
    if (const auto it = exceptions[pos].find(word); it != exceptions[pos].end()) {
      for (const auto& f : it->second) add(f);
    }
    auto detach = [&](const auto& rules) {
      for (const auto& r : rules) {
        if (word.size() > r.suffix.size() && word.compare(word.size() - r.suffix.size(), r.suffix.size(), r.suffix) == 0) {
          add(word.substr(0, word.size() - r.suffix.size()) + std::string(r.ending));
        }
      }
    };
    if (pos == 0) detach(kNounRules);
    if (pos == 1) detach(kVerbRules);
    if (pos == 2) detach(kAdjRules);
  }

  [[nodiscard]] std::vector<std::pair<std::size_t, std::string>> all_forms(const std::string& word) const {
    std::vector<std::pair<std::size_t, std::string>> out;
    for (std::size_t pos = 0; pos < kPosNames.size(); ++pos) forms(pos, word, out);
    return out;
  }

  // One synset's data line: its words and its pointers.
  struct Synset {
    std::vector<std::string> words;
    std::vector<std::tuple<std::string, std::uint32_t, std::size_t>> pointers;  // symbol, offset, pos
  };

  // The data files (27 MB together), read on first use: a word's hyponyms are hundreds of lines.
  mutable std::array<std::once_flag, 4> data_read;
  mutable std::array<std::string, 4> data;

  [[nodiscard]] const std::string& data_file(std::size_t pos) const {
    std::call_once(data_read[pos], [&] {
      try {
        data[pos] = read_file(wordnet_dir + "/data." + std::string(kPosNames[pos]));
      } catch (const std::exception& e) {
        spdlog::warn("hri: {}", e.what());  // the relations of this part of speech are not known
      }
    });
    return data[pos];
  }

  [[nodiscard]] Synset synset(std::size_t pos, std::uint32_t offset) const {
    Synset s;
    const std::string& file = data_file(pos);
    if (offset >= file.size()) return s;
    const std::size_t end = file.find('\n', offset);
    std::istringstream fields(file.substr(offset, end == std::string::npos ? std::string::npos : end - offset));
    std::string skip;
    std::string word_count_hex;
    fields >> skip >> skip >> skip >> word_count_hex;  // offset, lexicographer file, synset type
    const unsigned long words = std::strtoul(word_count_hex.c_str(), nullptr, 16);
    for (unsigned long i = 0; i < words; ++i) {
      std::string w;
      fields >> w >> skip;  // word, lex_id
      // Adjectives may carry a syntactic marker: "galore(ip)".
      if (const auto paren = w.find('('); paren != std::string::npos) w.resize(paren);
      std::transform(w.begin(), w.end(), w.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
      s.words.push_back(std::move(w));
    }
    std::size_t pointer_count = 0;
    fields >> pointer_count;
    for (std::size_t i = 0; i < pointer_count; ++i) {
      std::string symbol;
      unsigned long target = 0;
      std::string pos_letter;
      fields >> symbol >> target >> pos_letter >> skip;
      const std::size_t target_pos = pos_letter == "n"                          ? 0
                                     : pos_letter == "v"                        ? 1
                                     : (pos_letter == "a" || pos_letter == "s") ? 2
                                                                                : 3;
      s.pointers.emplace_back(symbol, static_cast<std::uint32_t>(target), target_pos);
    }
    return s;
  }
};

Lexicon::Lexicon(const LexiconPaths& paths) : impl_(std::make_unique<Impl>()) {
  impl_->wordnet_dir = paths.wordnet_dir;
  for (std::size_t pos = 0; pos < kPosNames.size(); ++pos) {
    impl_->read_index(pos);
    impl_->read_exceptions(pos);
  }
  impl_->read_counts(paths.sense_counts);
  std::istringstream in(read_file(paths.word_list));
  std::string w;
  while (std::getline(in, w)) {
    if (w.find('\'') != std::string::npos || w.empty()) continue;
    std::transform(w.begin(), w.end(), w.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    impl_->word_list.insert(w);
  }
}

Lexicon::Lexicon() = default;
Lexicon::~Lexicon() = default;
Lexicon::Lexicon(Lexicon&&) noexcept = default;
Lexicon& Lexicon::operator=(Lexicon&&) noexcept = default;

std::shared_ptr<const Lexicon> Lexicon::system() {
  static const std::shared_ptr<const Lexicon> lexicon = [] {
    LexiconPaths paths;
    if (const char* dir = std::getenv("TRIPODAL_WORDNET_DIR")) {
      paths.wordnet_dir = dir;
      paths.sense_counts = std::string(dir) + "/cntlist.rev";
    }
    if (const char* list = std::getenv("TRIPODAL_WORD_LIST")) paths.word_list = list;
    try {
      return std::make_shared<const Lexicon>(paths);
    } catch (const std::exception& e) {
      spdlog::warn(
          "hri: no English lexicon ({}); install wordnet-base and wamerican for synonyms and typo "
          "correction that leaves English words alone",
          e.what());
      return std::make_shared<const Lexicon>();
    }
  }();
  return lexicon;
}

bool Lexicon::empty() const noexcept {
  return !impl_ || impl_->word_list.empty();
}

bool Lexicon::is_english(std::string_view word) const {
  if (!impl_) return false;
  const std::string w(word);
  const auto forms = impl_->all_forms(w);
  // Words WordNet has but that are rare in text ("wether", "gide") are more likely a typo of a
  // common one; function words ("whose") are in the word list only.
  if (forms.empty()) return impl_->word_list.count(w) != 0;
  return std::any_of(forms.begin(), forms.end(), [&](const auto& f) { return impl_->index[f.first].at(f.second).tagged > 0; });
}

bool Lexicon::is_adjective(std::string_view word) const {
  if (!impl_) return false;
  const auto forms = impl_->all_forms(std::string(word));
  return std::any_of(forms.begin(), forms.end(), [](const auto& f) { return kPosNames.at(f.first) == "adj"; });
}

std::size_t Lexicon::frequency(std::string_view word) const {
  if (!impl_) return 0;
  std::size_t best = 0;
  for (const auto& [pos, f] : impl_->all_forms(std::string(word))) {
    if (const auto it = impl_->counts.find(f); it != impl_->counts.end()) best = std::max(best, it->second);
  }
  return best;
}

std::vector<std::string> Lexicon::base_forms(std::string_view word) const {
  std::vector<std::string> out;
  if (!impl_) return out;
  for (const auto& [pos, f] : impl_->all_forms(std::string(word))) {
    if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
  }
  return out;
}

std::vector<RelatedWord> Lexicon::related(std::string_view word) const {
  std::vector<RelatedWord> out;
  if (!impl_) return out;
  const Impl& x = *impl_;
  const std::vector<std::pair<std::size_t, std::string>> forms = x.all_forms(std::string(word));
  std::map<std::string, double> best;
  auto note = [&](const std::vector<std::string>& ws, double closeness) {
    for (const auto& w : ws) {
      if (!is_single_word(w)) continue;
      double& b = best[w];
      b = std::max(b, closeness);
    }
  };
  for (const auto& [pos, form] : forms) {
    // The senses seen in use only (at least the most frequent one): a word's rare senses relate it
    // to words a visitor does not mean ("capital" as "first-rate").
    const Impl::Lemma& lemma = x.index[pos].at(form);
    const std::size_t senses = std::min(lemma.offsets.size(), std::max<std::size_t>(1, lemma.tagged));
    const std::size_t first_count = x.sense_count(form, pos, 1);
    for (std::size_t k = 0; k < senses; ++k) {
      // A sense met far less often than the word's first is not what a visitor means by it
      // ("song" as a bird's call).
      if (k > 0 && static_cast<double>(x.sense_count(form, pos, k + 1)) < kMinSenseShare * static_cast<double>(first_count)) {
        continue;
      }
      const std::uint32_t offset = lemma.offsets[k];
      const Impl::Synset s = x.synset(pos, offset);
      note(s.words, kSynonym);
      for (const auto& [symbol, target, target_pos] : s.pointers) {
        double closeness = 0.0;
        if (symbol == "@" || symbol == "@i")
          closeness = kHypernym;
        else if (symbol == "~" || symbol == "~i")
          closeness = kHyponym;
        else if (symbol == "+")
          closeness = kDerivation;
        else if (symbol == "&")
          closeness = kSimilar;
        if (closeness == 0.0) continue;
        note(x.synset(target_pos, target).words, closeness);
      }
    }
  }
  for (const auto& [pos, form] : forms) best.erase(form);
  best.erase(std::string(word));
  out.reserve(best.size());
  for (auto& [w, c] : best) out.push_back({w, c});
  std::sort(out.begin(), out.end(), [](const RelatedWord& a, const RelatedWord& b) {
    return a.closeness != b.closeness ? a.closeness > b.closeness : a.word < b.word;
  });
  return out;
}

}  // namespace tripodal
