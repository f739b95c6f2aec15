// Retrieval over the RKMS knowledge base (paper, section 4): the HRI module of the deliberate
// layer asks it which entry an utterance is about. Entries are ranked by BM25 over English stems
// (Xapian, in memory); a word the base does not know is first corrected to the nearest one it does
// (typed input has typos) unless it is English, an English word the base does not know is matched
// through the words a lexicon relates to it, and a confidence says how much of the utterance the
// best entry covers.
#pragma once

#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/hri/knowledge_base.hpp"
#include "tripodal/hri/lexicon.hpp"

namespace tripodal {

struct RetrievalOptions {
  std::size_t max_results = 5;
  /// Extra words the typo correction may correct to (the planner's command words), besides the
  /// base's own.
  std::vector<std::string> extra_vocabulary;
  /// English lexical knowledge (none: words are matched as they are, and every word the base does
  /// not know is a typo candidate). With one, typo correction leaves English words alone, and a
  /// word the base does not know matches the entries of the words WordNet relates to it.
  std::shared_ptr<const Lexicon> lexicon;
};

/// One ranked entry.
struct RetrievalHit {
  std::size_t entry = 0;  ///< index into KnowledgeBase::entries()
  double weight = 0.0;    ///< BM25 weight
  /// The share (0..1) of the utterance's content terms that this entry contains, each term
  /// weighted by its inverse document frequency: 1 when every telling word is the entry's.
  double confidence = 0.0;
};

struct Retrieval {
  std::vector<RetrievalHit> hits;  ///< best first
  std::string corrected;           ///< the utterance's words after typo correction (lower case)
};

/// Not thread-safe (Xapian's objects are not): one search at a time.
class KnowledgeIndex {
 public:
  /// Indexes `base`'s entries (a copy of each entry's terms is kept; the base itself is not
  /// referenced after construction).
  explicit KnowledgeIndex(const KnowledgeBase& base, RetrievalOptions options = {});
  ~KnowledgeIndex();
  KnowledgeIndex(KnowledgeIndex&&) noexcept;
  KnowledgeIndex& operator=(KnowledgeIndex&&) noexcept;
  KnowledgeIndex(const KnowledgeIndex&) = delete;
  KnowledgeIndex& operator=(const KnowledgeIndex&) = delete;

  /// The entries about `utterance`, best first. Never throws for any text.
  [[nodiscard]] Retrieval search(std::string_view utterance) const;

  /// `text` with every word the index does not know replaced by the nearest known word (edit
  /// distance 1, or 2 for words of 7 letters or more), in lower case; numbers are kept.
  [[nodiscard]] std::string correct(std::string_view text) const;

 private:
  [[nodiscard]] Retrieval search_unguarded(std::string_view utterance) const;

  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace tripodal
