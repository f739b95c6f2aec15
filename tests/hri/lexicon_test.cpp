// The HRI's English lexicon (WordNet and the word list of Debian's wordnet-base and wamerican) and
// what it changes in retrieval: English words are not "corrected", unknown words reach entries
// through the words WordNet relates to them.
#include "tripodal/hri/lexicon.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "tripodal/hri/knowledge_index.hpp"

using namespace tripodal;

namespace {

bool has_related(const Lexicon& lexicon, std::string_view word, std::string_view related) {
  const auto rs = lexicon.related(word);
  return std::any_of(rs.begin(), rs.end(), [&](const RelatedWord& r) { return r.word == related; });
}

KnowledgeBase small_base() {
  KnowledgeBase kb;
  kb.put({"creator", "who made me", {"built", "made", "creator"}, {"Who built you?"}, "KIST.", "", {}});
  kb.put({"restroom", "the restrooms", {"restroom", "toilet"}, {"Where is the toilet?"}, "Left.", "", {}});
  kb.put({"finder", "finding things", {"find", "lost"}, {"Can you find my bag?"}, "No.", "", {}});
  return kb;
}

}  // namespace

TEST_CASE("the system lexicon knows English words, their base forms and related words") {
  const auto lexicon = Lexicon::system();
  REQUIRE_FALSE(lexicon->empty());  // scripts/install-deps.sh installs wordnet-base and wamerican
  CHECK(lexicon->is_english("kind"));
  CHECK(lexicon->is_english("running"));
  CHECK(lexicon->is_english("whose"));  // a function word: in the word list, not in WordNet
  // Rare in text, one letter from a common word: a typo, not what the visitor meant.
  CHECK_FALSE(lexicon->is_english("wether"));
  CHECK_FALSE(lexicon->is_english("gide"));
  CHECK_FALSE(lexicon->is_english("xqzt"));

  const auto made = lexicon->base_forms("made");
  CHECK(std::find(made.begin(), made.end(), "make") != made.end());
  const auto toilets = lexicon->base_forms("toilets");
  CHECK(std::find(toilets.begin(), toilets.end(), "toilet") != toilets.end());
  CHECK(lexicon->base_forms("xqzt").empty());

  CHECK(has_related(*lexicon, "loo", "toilet"));            // synonym
  CHECK(has_related(*lexicon, "constructed", "build"));     // synonym of the base form
  CHECK(has_related(*lexicon, "restaurant", "cafeteria"));  // a narrower term
  for (const auto& r : lexicon->related("loo")) {
    CHECK(r.word != "loo");
    CHECK(r.closeness > 0.0);
    CHECK(r.closeness <= 1.0);
  }
}

TEST_CASE("the lexicon knows how common a word is, and relates a word through its senses in use only (issue 37)") {
  const auto lexicon = Lexicon::system();
  REQUIRE_FALSE(lexicon->empty());
  // The Semantic Concordance's counts: everyday words are common, names and rare words are not.
  CHECK(lexicon->frequency("know") > 500);
  CHECK(lexicon->frequency("year") > lexicon->frequency("music"));
  CHECK(lexicon->frequency("running") >= lexicon->frequency("run"));  // the commonest base form's count
  CHECK(lexicon->frequency("samsung") == 0);
  CHECK(lexicon->frequency("xqzt") == 0);
  // "song" is a piece of music; its rare sense "a bird's call" no longer relates it to "call" (which
  // made "sing me a song" a question about what to call Jinny).
  CHECK_FALSE(has_related(*lexicon, "song", "call"));
  CHECK(has_related(*lexicon, "song", "ballad"));
}

TEST_CASE("a common word the base lacks does not sink the entry of the telling words (issue 37)") {
  const KnowledgeBase jinny = KnowledgeBase::load(TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml");
  const KnowledgeIndex index(jinny, {.lexicon = Lexicon::system()});
  const auto id = [&](const Retrieval& r) { return jinny.entries()[r.hits.front().entry].id; };
  // "running" and "out" are everyday words: battery covers most of what is asked.
  const Retrieval r = index.search("are you running out of battery");
  REQUIRE_FALSE(r.hits.empty());
  CHECK(id(r) == "battery");
  // ... and covers more than with a rare word in its place (measured 0.50 against 0.34).
  const Retrieval rare = index.search("are you xylophoning out of battery");
  REQUIRE_FALSE(rare.hits.empty());
  CHECK(r.hits.front().confidence > rare.hits.front().confidence + 0.1);
  // A rare word the base lacks ("samsung") still weighs as much as the base's rarest.
  const Retrieval name = index.search("samsung stock");
  REQUIRE_FALSE(name.hits.empty());
  CHECK(id(name) == "stock");
  CHECK(name.hits.front().confidence < 0.5);
}

TEST_CASE("a lexicon whose files are missing or malformed is refused naming the file") {
  LexiconPaths missing;
  missing.wordnet_dir = "/nonexistent/wordnet";
  CHECK_THROWS_WITH(Lexicon(missing), Catch::Contains("/nonexistent/wordnet/index.noun"));

  const auto dir = std::filesystem::temp_directory_path() / "tripodal_lexicon_test";
  std::filesystem::create_directories(dir);
  for (const char* pos : {"noun", "verb", "adj", "adv"}) {
    std::ofstream(dir / (std::string("index.") + pos)) << "cat n 2 1 @ 2 0 02121620\n";  // two synsets, one offset
    std::ofstream(dir / (std::string(pos) + ".exc")) << "";
  }
  LexiconPaths bad;
  bad.wordnet_dir = dir.string();
  CHECK_THROWS_WITH(Lexicon(bad), Catch::Contains("index.noun:1: malformed WordNet index line"));
  std::filesystem::remove_all(dir);

  const Lexicon none;
  CHECK(none.empty());
  CHECK_FALSE(none.is_english("kind"));
  CHECK(none.related("loo").empty());
}

TEST_CASE("with the lexicon, English words are not corrected and unknown words match through related ones") {
  RetrievalOptions without;
  RetrievalOptions with;
  with.lexicon = Lexicon::system();
  REQUIRE_FALSE(with.lexicon->empty());
  const KnowledgeIndex plain(small_base(), without);
  const KnowledgeIndex lexical(small_base(), with);

  // "kind" is one letter from "find": without the lexicon it is bent into it.
  CHECK(plain.correct("what kind of robot") == "what find of robot");
  CHECK(lexical.correct("what kind of robot") == "what kind of robot");
  // A word that is not English is still corrected.
  CHECK(lexical.correct("where is the tolet") == "where is the toilet");

  // "loo" is nowhere in the base: without the lexicon only "where" matches, with it the restroom
  // is covered further.
  const Retrieval loo = lexical.search("where is the loo");
  REQUIRE_FALSE(loo.hits.empty());
  CHECK(loo.hits.front().entry == 1);
  const Retrieval plain_loo = plain.search("where is the loo");
  REQUIRE_FALSE(plain_loo.hits.empty());
  CHECK(plain_loo.hits.front().confidence < loo.hits.front().confidence);
  // ... matched through a relation, it covers less than the base's own word would.
  const Retrieval toilet = lexical.search("where is the toilet");
  REQUIRE_FALSE(toilet.hits.empty());
  CHECK(toilet.hits.front().entry == 1);
  CHECK(loo.hits.front().confidence < toilet.hits.front().confidence);

  // "constructed" reaches "built" through its base form "construct" and the synonym "build".
  const Retrieval built = lexical.search("who constructed you");
  REQUIRE_FALSE(built.hits.empty());
  CHECK(built.hits.front().entry == 0);
}

TEST_CASE("an adjective said of the robot asks how it feels (issue 37)") {
  const auto lexicon = Lexicon::system();
  REQUIRE_FALSE(lexicon->empty());
  CHECK(lexicon->is_adjective("tired"));
  CHECK(lexicon->is_adjective("happier"));  // through its base form
  CHECK_FALSE(lexicon->is_adjective("robot"));
  KnowledgeBase kb;
  kb.put({"feeling", "how I feel", {"feel", "fine"}, {"How do you feel?"}, "Fine.", "", {}});
  kb.put({"move", "how I move", {"move", "wheels"}, {"How do you move?"}, "On wheels.", "", {}});
  const KnowledgeIndex index(kb, {.lexicon = lexicon});
  // The base has neither word; said of the robot, they ask how it is.
  for (const char* said : {"are you tired", "are you feeling happy", "you look so sad"}) {
    INFO(said);
    const Retrieval r = index.search(said);
    REQUIRE_FALSE(r.hits.empty());
    CHECK(kb.entries()[r.hits.front().entry].id == "feeling");
    // Well ahead of the entry that shares only "you" with it (before: the two tied).
    CHECK(r.hits.front().confidence > 0.4);
    if (r.hits.size() > 1) CHECK(r.hits[1].confidence < r.hits.front().confidence - 0.2);
  }
  // Not without a verb of being or seeming: "can you fly" says nothing of how the robot is.
  const Retrieval fly = index.search("can you fly");
  CHECK(std::none_of(fly.hits.begin(), fly.hits.end(),
                     [&](const RetrievalHit& h) { return kb.entries()[h.entry].id == "feeling" && h.confidence >= 0.5; }));
}
