#include "tripodal/hri/knowledge_index.hpp"

#include <xapian.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <unordered_set>

#include "text.hpp"

namespace tripodal {

namespace {

// Within-document frequencies per field: a keyword is the author saying "this is what the entry
// is about", a question form is one way of asking among several.
constexpr Xapian::termcount kKeywordWdf = 3;
constexpr Xapian::termcount kTopicWdf = 2;
constexpr Xapian::termcount kQuestionWdf = 1;
// How much a stop word of the utterance counts in the ranking, relative to a content word.
constexpr double kStopWordScale = 0.2;

}  // namespace

struct KnowledgeIndex::Impl {
  Xapian::WritableDatabase db{std::string(), Xapian::DB_BACKEND_INMEMORY};
  Xapian::Stem stem{"english"};
  RetrievalOptions options;
  std::unordered_set<std::string> known;  // every word of the base and the extra vocabulary
  // Candidates of the typo correction by length, each with how many entries use it (ties go to
  // the more common word).
  std::map<std::size_t, std::vector<std::pair<std::string, Xapian::doccount>>> by_length;

  [[nodiscard]] std::string term(const std::string& word) const { return "Z" + stem(word); }

  void index_text(Xapian::Document& doc, std::string_view text, Xapian::termcount wdf, std::set<std::string>& words_seen) {
    const std::vector<std::string> ws = hri::words(text);
    for (const auto& w : ws) {
      words_seen.insert(w);
      // Stop words are indexed too: the query weighs them little, but they tell apart entries
      // whose telling words are the same ("what can you do" vs "how are you").
      doc.add_term(term(w), wdf);
    }
  }

  [[nodiscard]] std::string corrected_word(const std::string& w) const {
    if (known.count(w) != 0 || hri::is_stop_word(w) || hri::has_digit(w) || db.term_exists(term(w))) return w;
    const std::size_t limit = w.size() >= 7 ? 2 : (w.size() >= 4 ? 1 : 0);
    if (limit == 0) return w;
    std::string best;
    std::size_t best_d = limit + 1;
    Xapian::doccount best_freq = 0;
    for (std::size_t len = w.size() - std::min(w.size(), limit); len <= w.size() + limit; ++len) {
      const auto it = by_length.find(len);
      if (it == by_length.end()) continue;
      for (const auto& [candidate, freq] : it->second) {
        const std::size_t d = hri::edit_distance(w, candidate, std::min(limit, best_d));
        if (d < best_d || (d == best_d && d <= limit && freq > best_freq)) {
          best = candidate;
          best_d = d;
          best_freq = freq;
        }
      }
    }
    return best_d <= limit ? best : w;
  }
};

KnowledgeIndex::KnowledgeIndex(const KnowledgeBase& base, RetrievalOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& x = *impl_;
  x.options = std::move(options);
  std::map<std::string, Xapian::doccount> word_entries;
  for (const KnowledgeEntry& e : base.entries()) {
    Xapian::Document doc;
    std::set<std::string> seen;
    for (const auto& k : e.keywords) x.index_text(doc, k, kKeywordWdf, seen);
    x.index_text(doc, e.topic, kTopicWdf, seen);
    for (const auto& q : e.questions) x.index_text(doc, q, kQuestionWdf, seen);
    // Documents are numbered from 1 in the order added: docid - 1 is the entry's index.
    x.db.add_document(doc);
    for (const auto& w : seen) ++word_entries[w];
  }
  for (const auto& extra : x.options.extra_vocabulary) {
    for (const auto& w : hri::words(extra)) word_entries.try_emplace(w, 0);
  }
  for (const auto& [w, n] : word_entries) {
    x.known.insert(w);
    if (!hri::has_digit(w)) x.by_length[w.size()].emplace_back(w, n);
  }
}

KnowledgeIndex::~KnowledgeIndex() = default;
KnowledgeIndex::KnowledgeIndex(KnowledgeIndex&&) noexcept = default;
KnowledgeIndex& KnowledgeIndex::operator=(KnowledgeIndex&&) noexcept = default;

std::string KnowledgeIndex::correct(std::string_view text) const {
  std::string out;
  for (const auto& w : hri::words(text)) {
    if (!out.empty()) out += ' ';
    out += impl_->corrected_word(w);
  }
  return out;
}

Retrieval KnowledgeIndex::search(std::string_view utterance) const {
  try {
    return search_unguarded(utterance);
  } catch (const Xapian::Error&) {
    // Xapian documents errors for I/O and corrupt databases, which an in-memory index built here
    // should never meet; if it does, the utterance is simply not understood.
    return {};
  }
}

Retrieval KnowledgeIndex::search_unguarded(std::string_view utterance) const {
  const Impl& x = *impl_;
  Retrieval r;
  std::vector<std::string> ws = hri::words(utterance);
  for (auto& w : ws) w = x.corrected_word(w);
  for (const auto& w : ws) r.corrected += (r.corrected.empty() ? "" : " ") + w;

  // Content words decide the confidence; stop words only break ties between entries (weighed
  // kStopWordScale), unless the utterance has nothing else ("who are you" without "who"...).
  std::set<std::string> terms;
  std::set<std::string> stop_terms;
  for (const auto& w : ws) {
    if (!hri::is_stop_word(w)) terms.insert(x.term(w));
  }
  for (const auto& w : ws) {
    if (hri::is_stop_word(w) && terms.count(x.term(w)) == 0) stop_terms.insert(x.term(w));
  }
  if (terms.empty()) terms.swap(stop_terms);
  if (terms.empty() || x.db.get_doccount() == 0) return r;

  // The confidence weighs each term by its inverse document frequency, so a match on a rare,
  // telling word counts more than one on a word many entries share; a word no entry has gets
  // the largest weight (the utterance is about something the base does not know).
  const double n = static_cast<double>(x.db.get_doccount());
  std::map<std::string, double> idf;
  double total = 0.0;
  for (const auto& t : terms) {
    const double df = static_cast<double>(x.db.get_termfreq(t));
    const double w = std::log((n + 1.0) / (df + 0.5));
    idf[t] = w;
    total += w;
  }

  Xapian::Enquire enquire(x.db);
  Xapian::Query query(Xapian::Query::OP_OR, terms.begin(), terms.end());
  if (!stop_terms.empty()) {
    query = Xapian::Query(Xapian::Query::OP_OR, query,
                          Xapian::Query(Xapian::Query::OP_SCALE_WEIGHT,
                                        Xapian::Query(Xapian::Query::OP_OR, stop_terms.begin(), stop_terms.end()),
                                        kStopWordScale));
  }
  enquire.set_query(query);
  const Xapian::MSet mset = enquire.get_mset(0, static_cast<Xapian::doccount>(x.options.max_results));
  for (auto it = mset.begin(); it != mset.end(); ++it) {
    RetrievalHit hit;
    hit.entry = static_cast<std::size_t>(*it - 1);
    hit.weight = it.get_weight();
    double matched = 0.0;
    for (auto t = enquire.get_matching_terms_begin(it); t != enquire.get_matching_terms_end(it); ++t) {
      const auto found = idf.find(*t);
      if (found != idf.end()) matched += found->second;
    }
    hit.confidence = total > 0.0 ? matched / total : 0.0;
    r.hits.push_back(hit);
  }
  return r;
}

}  // namespace tripodal
