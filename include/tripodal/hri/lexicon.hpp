// English lexical knowledge for the HRI's matcher (deliberate layer, beside the RKMS retrieval):
// which words are English at all (so typo correction leaves them alone), their base forms, and the
// words WordNet relates to them (synonyms, one step up or down the is-a hierarchy, derivations), so
// a visitor's "who constructed you" reaches an entry written with "built".
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace tripodal {

/// A word WordNet relates to another, and how closely (1 for a synonym, less for a broader or a
/// narrower term or a derivation).
struct RelatedWord {
  std::string word;
  double closeness = 1.0;
};

/// Where the lexicon's data is read from. Debian's `wordnet-base` and `wamerican` packages hold
/// them at the defaults.
struct LexiconPaths {
  std::string wordnet_dir = "/usr/share/wordnet";
  std::string word_list = "/usr/share/dict/american-english";
  /// WordNet's sense counts in the Semantic Concordance (`cntlist.rev`): how often a word is met in
  /// text. Optional: a missing file leaves every word's `frequency` 0.
  std::string sense_counts = "/usr/share/wordnet/cntlist.rev";
};

/// Read-only after construction; safe to share between threads.
class Lexicon {
 public:
  /// An empty lexicon: knows no word (the matcher behaves as without one).
  Lexicon();
  /// Reads WordNet's index files (data files are read lazily, line by line) and the word list.
  /// Throws std::runtime_error naming the file when one is missing or malformed.
  explicit Lexicon(const LexiconPaths& paths);
  ~Lexicon();
  Lexicon(Lexicon&&) noexcept;
  Lexicon& operator=(Lexicon&&) noexcept;
  Lexicon(const Lexicon&) = delete;
  Lexicon& operator=(const Lexicon&) = delete;

  /// The lexicon of the system's packages, loaded once per process ($TRIPODAL_WORDNET_DIR and
  /// $TRIPODAL_WORD_LIST override the paths). When the data is not installed, an empty lexicon
  /// and one warning on the log.
  [[nodiscard]] static std::shared_ptr<const Lexicon> system();

  [[nodiscard]] bool empty() const noexcept;

  /// True for a word in common use: one WordNet has (in any inflected form) with a sense seen in
  /// the Semantic Concordance, or a word of the word list WordNet does not have (function words).
  /// Lower case.
  [[nodiscard]] bool is_english(std::string_view word) const;

  /// True when WordNet has the word, or a base form of it, as an adjective ("tired", "happier").
  [[nodiscard]] bool is_adjective(std::string_view word) const;

  /// WordNet's base forms of `word` ("made" -> "make", "toilets" -> "toilet"), the word itself
  /// first when WordNet has it; empty when WordNet knows no form of it.
  [[nodiscard]] std::vector<std::string> base_forms(std::string_view word) const;

  /// How often the word is met in ordinary English text: the Semantic Concordance's count of its
  /// most used base form, summed over that form's senses ("know" 954, "year" 450, "music" 65,
  /// "samsung" 0). A word every conversation uses ("need", "use") tells little of what a question
  /// is about; a rare one (a name, "chess") tells a lot. 0 for a word WordNet lacks.
  [[nodiscard]] std::size_t frequency(std::string_view word) const;

  /// Single words related to `word` through its base forms' senses in use (at least the most
  /// frequent one): synonyms (closeness 1),
  /// hypernyms, hyponyms and derivations (closeness < 1). Each word once, at its best closeness;
  /// neither `word` nor its base forms.
  [[nodiscard]] std::vector<RelatedWord> related(std::string_view word) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal
