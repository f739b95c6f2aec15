#include "tripodal/hri/knowledge_index.hpp"

#include <xapian.h>

#include <algorithm>
#include <array>
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
// How much an entry's answer tells of what the entry is about, against its keywords and questions:
// "which robot patrols at night" is about PSR-1, whose answer says it patrols the building at night,
// but an answer also says things the entry is not about ("just in time for this festival").
constexpr Xapian::termcount kAnswerWdf = 1;
constexpr double kAnswerCloseness = 0.6;
// A word no entry has weighs what a word of ordinary text tells: a rare one (a name, "chess") as the
// rarest of the base, a common one ("need", "use", "year") less, by its count in the Semantic
// Concordance (1 - kCommonWordSlope ln(1 + count), never below kCommonWordFloor of it: "year", 450, weighs 63 %), so one
// everyday word does not sink a question whose telling words an entry has.
constexpr double kCommonWordSlope = 0.06;
constexpr double kCommonWordFloor = 0.25;
// The related words whose mention in an answer counts (synonyms, derivations, similar adjectives).
constexpr double kDerivationOrCloser = 0.8;
// Question words and "you" tell entries apart ("who are you" vs "where are you"), but say less of
// what a question is about than its other words: "how are you programmed" is about programs, not
// about an entry because its questions open with "how".
constexpr double kFunctionWordScale = 0.8;

// An adjective said of the robot ("are you tired", "you look happy") asks how it feels; the entry
// with "feel" is about that, a little less surely than one with the word itself.
constexpr double kSaidOfYouCloseness = 0.8;

// The words of `ws` said of the one spoken to: the adjective after "you" ("you look tired") or after
// "are you" ("are you feeling happy"), with a verb of being or seeming and an adverb of degree between.
std::set<std::string> said_of_you(const std::vector<std::string>& ws, const Lexicon& lexicon) {
  static constexpr std::array<std::string_view, 8> kLinking = {"are", "re", "look", "looks", "seem", "seems", "feel", "feeling"};
  static constexpr std::array<std::string_view, 5> kDegree = {"so", "very", "really", "quite", "bit"};
  const auto is_in = [](const auto& list, const std::string& w) { return std::find(list.begin(), list.end(), w) != list.end(); };
  std::set<std::string> out;
  for (std::size_t k = 0; k < ws.size(); ++k) {
    if (ws[k] != "you") continue;
    // "are you ...", or "you are / look / seem ...": "can you fly" says nothing of how it is.
    bool linked = k > 0 && ws[k - 1] == "are";
    std::size_t j = k + 1;
    for (; j < ws.size() && (is_in(kLinking, ws[j]) || is_in(kDegree, ws[j]) || ws[j] == "a"); ++j) {
      if (is_in(kLinking, ws[j])) linked = true;
    }
    if (linked && j < ws.size() && lexicon.is_adjective(ws[j])) out.insert(ws[j]);
  }
  return out;
}

bool is_function_word(std::string_view w) {
  static constexpr std::array<std::string_view, 8> kWords = {"how", "when", "where", "which", "who", "whom", "why", "you"};
  return std::find(kWords.begin(), kWords.end(), w) != kWords.end();
}

// True when one word is the other with one letter doubled ("helo", "hello").
bool differs_by_doubling(std::string_view a, std::string_view b) {
  if (a.size() > b.size()) std::swap(a, b);
  if (b.size() != a.size() + 1) return false;
  for (std::size_t i = 1; i < b.size(); ++i) {
    if (b[i] == b[i - 1] && a.substr(0, i) == b.substr(0, i) && a.substr(i) == b.substr(i + 1)) return true;
  }
  return false;
}

// The terms one word of an utterance may match, each with how close it is to the word.
struct WordTerms {
  std::vector<std::pair<std::string, double>> terms;
};

}  // namespace

struct KnowledgeIndex::Impl {
  Xapian::WritableDatabase db{std::string(), Xapian::DB_BACKEND_INMEMORY};
  Xapian::Stem stem{"english"};
  RetrievalOptions options;
  std::unordered_set<std::string> known;  // every word of the base and the extra vocabulary
  // Candidates of the typo correction by length, each with how many entries use it (ties go to
  // the more common word).
  std::map<std::size_t, std::vector<std::pair<std::string, Xapian::doccount>>> by_length;
  // Per entry (by index): its words as written. Ties go to the entry with the visitor's own words:
  // "hour" is the time's, "hours" the opening hours'.
  std::vector<std::set<std::string>> surface;
  std::string robot_name;  // said to the robot, not about anything ("thank you very much, jinny")

  [[nodiscard]] std::string term(const std::string& word) const { return "Z" + stem(word); }
  // The same word in an entry's answer.
  [[nodiscard]] static std::string answer_term(const std::string& t) { return "A" + t.substr(1); }

  void index_answer(Xapian::Document& doc, std::string_view text) {
    for (const auto& w : hri::words(text)) {
      if (hri::is_stop_word(w) || w.size() < 3) continue;
      doc.add_term(answer_term(term(w)), kAnswerWdf);
      if (options.lexicon) {
        for (const auto& f : options.lexicon->base_forms(w)) doc.add_term(answer_term(term(f)), kAnswerWdf);
      }
    }
  }

  void index_text(Xapian::Document& doc, std::string_view text, Xapian::termcount wdf, std::set<std::string>& words_seen) {
    const std::vector<std::string> ws = hri::words(text);
    surface.back().insert(ws.begin(), ws.end());
    for (const auto& w : ws) {
      words_seen.insert(w);
      // Stop words are indexed too: the query weighs them little, but they tell apart entries
      // whose telling words are the same ("what can you do" vs "how are you").
      doc.add_term(term(w), wdf);
      // Its base forms too ("made" -> "make"): a visitor's "produced" relates to "make", which
      // the English stemmer does not derive from "made".
      if (options.lexicon && !hri::is_stop_word(w)) {
        for (const auto& f : options.lexicon->base_forms(w)) doc.add_term(term(f), wdf);
      }
    }
  }

  // Each word's own term, and when no entry has it, the terms of the words the lexicon relates to
  // it that some entry has (only those: the others could not match).
  [[nodiscard]] std::vector<WordTerms> word_terms(const std::vector<std::string>& ws, const std::set<std::string>& of_you) const {
    std::vector<WordTerms> out;
    out.reserve(ws.size());
    for (const auto& w : ws) {
      WordTerms g;
      g.terms.emplace_back(term(w), 1.0);
      if (of_you.count(w) != 0 && !db.term_exists(term(w)) && db.term_exists(term("feel"))) {
        g.terms.emplace_back(term("feel"), kSaidOfYouCloseness);
      }
      // Words of one or two letters are abbreviations more often than words ("no" is WordNet's
      // "number"): they are matched as they are.
      if (options.lexicon && w.size() >= 3 && !db.term_exists(term(w)) && !hri::has_digit(w)) {
        for (const auto& f : options.lexicon->base_forms(w)) {
          if (db.term_exists(term(f))) g.terms.emplace_back(term(f), 1.0);
        }
        for (const auto& rel : options.lexicon->related(w)) {
          if (db.term_exists(term(rel.word))) g.terms.emplace_back(term(rel.word), rel.closeness);
          if (rel.closeness >= kDerivationOrCloser && db.term_exists(answer_term(term(rel.word)))) {
            g.terms.emplace_back(answer_term(term(rel.word)), rel.closeness * kAnswerCloseness);
          }
        }
      }
      // The word and its base forms in the entries' answers.
      if (!hri::has_digit(w) && w.size() >= 3) {
        std::vector<std::string> forms{w};
        if (options.lexicon) {
          for (const auto& f : options.lexicon->base_forms(w)) forms.push_back(f);
        }
        for (const auto& f : forms) {
          const std::string a = answer_term(term(f));
          if (db.term_exists(a)) g.terms.emplace_back(a, kAnswerCloseness);
        }
      }
      out.push_back(std::move(g));
    }
    return out;
  }

  [[nodiscard]] std::string corrected_word(const std::string& typed) const {
    const std::string w(hri::expand_chat_word(typed));
    if (known.count(w) != 0 || hri::is_stop_word(w) || hri::has_digit(w) || db.term_exists(term(w))) return std::string(w);
    // An English word is what the visitor meant, even when the base does not have it: "kind" is
    // no typo of "find".
    if (options.lexicon && options.lexicon->is_english(w)) return std::string(w);
    const std::size_t limit = w.size() >= 7 ? 2 : (w.size() >= 4 ? 1 : 0);
    if (limit == 0) return std::string(w);
    std::string best;
    std::size_t best_d = limit + 1;
    Xapian::doccount best_freq = 0;
    for (std::size_t len = w.size() - std::min(w.size(), limit); len <= w.size() + limit; ++len) {
      const auto it = by_length.find(len);
      if (it == by_length.end()) continue;
      for (const auto& [candidate, freq] : it->second) {
        const std::size_t d = hri::edit_distance(w, candidate, std::min(limit, best_d));
        // Ties go to a doubled or undoubled letter, the commonest slip ("helo" is "hello", not
        // "help"), then to the more common word.
        const bool better_tie =
            d == best_d && d <= limit &&
            (differs_by_doubling(w, candidate) != differs_by_doubling(w, best) ? differs_by_doubling(w, candidate)
                                                                               : freq > best_freq);
        if (d < best_d || better_tie) {
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
  if (const auto name = hri::words(base.robot()); name.size() == 1) x.robot_name = name.front();
  std::map<std::string, Xapian::doccount> word_entries;
  for (const KnowledgeEntry& e : base.entries()) {
    Xapian::Document doc;
    std::set<std::string> seen;
    x.surface.emplace_back();
    for (const auto& k : e.keywords) x.index_text(doc, k, kKeywordWdf, seen);
    x.index_text(doc, e.topic, kTopicWdf, seen);
    for (const auto& q : e.questions) x.index_text(doc, q, kQuestionWdf, seen);
    // Documents are numbered from 1 in the order added: docid - 1 is the entry's index.
    // The answer of an entry that starts a task says what the robot will do ("I will take you to
    // node 0"), not what the visitor asked: matched, it made "take me to node" start the visit.
    if (e.action.empty()) x.index_answer(doc, e.answer);
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
  std::vector<std::string> content;
  std::vector<std::string> stop;
  std::set<std::string> seen;  // a word said twice counts once
  for (const auto& w : ws) {
    if (seen.insert(w).second) (hri::is_stop_word(w) || w == x.robot_name ? stop : content).push_back(w);
  }
  std::set<std::string> stop_terms;
  if (content.empty()) {
    content.swap(stop);
  } else {
    std::set<std::string> content_terms;
    for (const auto& w : content) content_terms.insert(x.term(w));
    for (const auto& w : stop) {
      if (content_terms.count(x.term(w)) == 0) stop_terms.insert(x.term(w));
    }
  }
  if (content.empty() || x.db.get_doccount() == 0) return r;

  // The confidence weighs each word by its inverse document frequency, so a match on a rare,
  // telling word counts more than one on a word many entries share; a word no entry has gets
  // the largest weight (the utterance is about something the base does not know); an entry with a
  // word the lexicon relates to it covers part of that weight.
  const double n = static_cast<double>(x.db.get_doccount());
  auto idf_of = [&](const std::string& t) { return std::log((n + 1.0) / (static_cast<double>(x.db.get_termfreq(t)) + 0.5)); };
  const std::vector<WordTerms> groups =
      x.word_terms(content, x.options.lexicon ? said_of_you(ws, *x.options.lexicon) : std::set<std::string>{});
  std::map<std::string, double> query_terms;  // term -> its best closeness over the words
  std::vector<double> weight(groups.size());
  double total = 0.0;
  for (std::size_t i = 0; i < groups.size(); ++i) {
    for (const auto& [t, closeness] : groups[i].terms) {
      double& q = query_terms[t];
      q = std::max(q, closeness);
    }
    const std::string& own = groups[i].terms.front().first;
    weight[i] = idf_of(own);
    if (x.options.lexicon && x.db.get_termfreq(own) == 0) {
      const double count = static_cast<double>(x.options.lexicon->frequency(content[i]));
      weight[i] *= std::max(kCommonWordFloor, 1.0 - kCommonWordSlope * std::log1p(count));
    }
    if (is_function_word(content[i])) weight[i] *= kFunctionWordScale;
    total += weight[i];
  }

  Xapian::Enquire enquire(x.db);
  std::vector<Xapian::Query> subqueries;
  subqueries.reserve(query_terms.size());
  for (const auto& [t, closeness] : query_terms) {
    subqueries.push_back(closeness >= 1.0 ? Xapian::Query(t)
                                          : Xapian::Query(Xapian::Query::OP_SCALE_WEIGHT, Xapian::Query(t), closeness));
  }
  Xapian::Query query(Xapian::Query::OP_OR, subqueries.begin(), subqueries.end());
  if (!stop_terms.empty()) {
    query = Xapian::Query(Xapian::Query::OP_OR, query,
                          Xapian::Query(Xapian::Query::OP_SCALE_WEIGHT,
                                        Xapian::Query(Xapian::Query::OP_OR, stop_terms.begin(), stop_terms.end()),
                                        kStopWordScale));
  }
  enquire.set_query(query);
  const Xapian::MSet mset = enquire.get_mset(0, static_cast<Xapian::doccount>(x.options.max_results));
  std::vector<std::size_t> own_words(x.surface.size(), 0);
  for (auto it = mset.begin(); it != mset.end(); ++it) {
    RetrievalHit hit;
    hit.entry = static_cast<std::size_t>(*it - 1);
    for (const auto& w : content) own_words[hit.entry] += x.surface.at(hit.entry).count(w);
    hit.weight = it.get_weight();
    std::set<std::string> matching(enquire.get_matching_terms_begin(it), enquire.get_matching_terms_end(it));
    double matched = 0.0;
    for (std::size_t i = 0; i < groups.size(); ++i) {
      // The word's own term counts whole; a related one as much as it tells (its own rarity) and
      // as close as the relation is, so a match through the lexicon never outweighs an exact one.
      double best = 0.0;
      for (const auto& [t, closeness] : groups[i].terms) {
        if (matching.count(t) == 0) continue;
        // An answer's word is the utterance's own word (or a close relative), as telling as itself.
        const bool own_or_answer = t == groups[i].terms.front().first || t.front() == 'A';
        best = std::max(best, own_or_answer ? weight[i] * closeness : std::min(weight[i], idf_of(t)) * closeness);
      }
      matched += best;
    }
    hit.confidence = total > 0.0 ? matched / total : 0.0;
    r.hits.push_back(hit);
  }
  // The entry that covers most of the utterance first: BM25 alone would put an entry matched
  // through several loosely related words ahead of one with the utterance's own telling word.
  // Between entries that cover it equally, the one with the visitor's own words as written.
  std::stable_sort(r.hits.begin(), r.hits.end(), [&](const RetrievalHit& a, const RetrievalHit& b) {
    if (a.confidence != b.confidence) return a.confidence > b.confidence;
    return own_words[a.entry] > own_words[b.entry];
  });
  return r;
}

}  // namespace tripodal
