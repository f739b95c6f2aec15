#include "tripodal/hri/knowledge_index.hpp"

#include <catch2/catch.hpp>

using namespace tripodal;

namespace {

KnowledgeBase small_base() {
  KnowledgeBase kb;
  kb.put({"weather", "the weather", {"weather", "rain", "umbrella"}, {"Will it rain today?"}, "Sunny.", "", {}});
  kb.put({"time", "the time", {"time", "clock"}, {"What time is it?"}, "Noon.", "", {}});
  kb.put({"psr1", "PSR-1", {"psr-1", "delivery robot"}, {"What does PSR-1 do?"}, "It delivers.", "", {}});
  kb.put({"psr2", "PSR-2", {"psr-2", "cleaning robot"}, {"What does PSR-2 do?"}, "It cleans.", "", {}});
  return kb;
}

}  // namespace

TEST_CASE("retrieval ranks by English stems and says how much of the utterance the best entry covers") {
  const KnowledgeIndex index(small_base());
  // "raining" and "umbrellas" share the stems of "rain" and "umbrella".
  const Retrieval r = index.search("Is it raining? Umbrellas?");
  REQUIRE_FALSE(r.hits.empty());
  CHECK(r.hits.front().entry == 0);
  CHECK(r.hits.front().confidence == Approx(1.0));
  // Half the telling words are unknown to the base: the confidence drops accordingly.
  const Retrieval half = index.search("rain in Jupiter");
  REQUIRE_FALSE(half.hits.empty());
  CHECK(half.hits.front().entry == 0);
  CHECK(half.hits.front().confidence < 0.6);
  CHECK(half.hits.front().confidence > 0.3);
  // Nothing in common: no hit at all.
  CHECK(index.search("capital of France").hits.empty());
  CHECK(index.search("").hits.empty());
}

TEST_CASE("a hyphenated name with a number is one word: PSR-1 does not match PSR-2's 2 or other 1s") {
  const KnowledgeIndex index(small_base());
  const Retrieval one = index.search("tell me about PSR-1");
  REQUIRE_FALSE(one.hits.empty());
  CHECK(one.hits.front().entry == 2);
  const Retrieval two = index.search("what is psr2");
  REQUIRE_FALSE(two.hits.empty());
  CHECK(two.hits.front().entry == 3);
  // The others share only the stop words "what" and "is", which rank but do not make confidence.
  for (std::size_t i = 1; i < two.hits.size(); ++i) CHECK(two.hits[i].confidence == 0.0);
}

TEST_CASE("typo correction uses the base's words and the extra vocabulary, within 1 or 2 edits by length") {
  const KnowledgeIndex index(small_base(), {.extra_vocabulary = {"guide me to node {node}"}});
  CHECK(index.correct("wheather") == "weather");    // 8 letters: 1 edit
  CHECK(index.correct("umberlla") == "umbrella");   // a transposition is one edit
  CHECK(index.correct("cleening robott") == "cleaning robot");
  CHECK(index.correct("gide me") == "guide me");    // from the extra vocabulary
  CHECK(index.correct("tmie") == "time");           // 4 letters: 1 edit (a transposition)
  CHECK(index.correct("tame") == "time");
  CHECK(index.correct("tam") == "tam");             // 3 letters: never corrected
  CHECK(index.correct("node 12") == "node 12");     // numbers are kept
  const Retrieval r = index.search("wether");
  REQUIRE_FALSE(r.hits.empty());
  CHECK(r.corrected == "weather");
  CHECK(r.hits.front().entry == 0);
}

TEST_CASE("an entry's answer counts too, less than its keywords and questions (issue 37)") {
  KnowledgeBase kb;
  kb.put({"psr1", "PSR-1", {"psr-1"}, {"What is PSR-1?"}, "PSR-1 patrols the building at night.", "", {}});
  kb.put({"psr2", "PSR-2", {"psr-2", "robot"}, {"What is PSR-2?"}, "PSR-2 cleans.", "", {}});
  const KnowledgeIndex index(kb);
  // Only PSR-1's answer says it patrols at night.
  const Retrieval r = index.search("which robot patrols at night");
  REQUIRE_FALSE(r.hits.empty());
  CHECK(r.hits.front().entry == 0);
  CHECK(r.hits.front().confidence > 0.3);  // without the answer: 0 (measured 0.35)
  CHECK(r.hits.front().confidence < 1.0);  // a match in an answer covers less than one in a question
  // Words of one or two letters and stop words of an answer match nothing.
  CHECK(index.search("at").hits.empty());
}

TEST_CASE("between entries that cover an utterance equally, the one with its words as written comes first (issue 37)") {
  KnowledgeBase kb;
  kb.put({"hours", "opening hours", {"opening hours", "hours", "open"}, {"What are the opening hours?"}, "10 to 6.", "", {}});
  kb.put({"time", "the time", {"time", "hour"}, {"What time is it?"}, "Noon.", "", {}});
  const KnowledgeIndex index(kb);
  // "hour" and "hours" share a stem: both entries cover the question whole, the time has "hour" as said.
  const Retrieval r = index.search("what is the hour");
  REQUIRE(r.hits.size() >= 2);
  CHECK(r.hits[0].confidence == r.hits[1].confidence);
  CHECK(kb.entries()[r.hits.front().entry].id == "time");
  CHECK(kb.entries()[index.search("what are the hours").hits.front().entry].id == "hours");
}

TEST_CASE("the robot's name said to it is not what an utterance is about (issue 37)") {
  KnowledgeBase kb;
  kb.set_robot("jinny");
  kb.put({"introduce", "who I am", {"name", "jinny"}, {"Who are you?"}, "I am Jinny.", "", {}});
  kb.put({"thanks", "thanks", {"thanks"}, {"Thank you."}, "You are welcome.", "", {}});
  const KnowledgeIndex index(kb);
  const Retrieval r = index.search("thanks, jinny");
  REQUIRE_FALSE(r.hits.empty());
  CHECK(kb.entries()[r.hits.front().entry].id == "thanks");
  CHECK(r.hits.front().confidence == Approx(1.0));  // before: 0.5, tied with the introduction
  // Alone, the name is what the visitor asks about.
  const Retrieval alone = index.search("Jinny?");
  REQUIRE_FALSE(alone.hits.empty());
  CHECK(kb.entries()[alone.hits.front().entry].id == "introduce");
}
