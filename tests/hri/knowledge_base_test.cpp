#include "tripodal/hri/knowledge_base.hpp"

#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <sstream>

using namespace tripodal;

namespace {

namespace fs = std::filesystem;

std::string read(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

void write(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary);
  out << text;
}

// A fresh folder per test, removed at the end.
struct TempDir {
  fs::path path;
  TempDir() {
    path = fs::temp_directory_path() / ("tripodal_hri_" + std::to_string(::getpid()) + "_" +
                                        std::to_string(reinterpret_cast<std::uintptr_t>(this)));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

std::string load_error(const std::string& xml) {
  try {
    (void)KnowledgeBase::load_from_string(xml, "kb.xml");
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "(loaded without error)";
}

const char* const kSmall = R"(<?xml version="1.0" encoding="UTF-8"?>
<knowledge version="4" robot="jinny">
  <entry id="greeting" topic="greetings">
    <keywords>hello, hi, good morning</keywords>
    <question>Hello!</question>
    <answer>Hello &amp; welcome! Braces: {{x}}.</answer>
  </entry>
  <entry id="time" topic="the time">
    <question>What time is it?</question>
    <answer>It is {time}.</answer>
    <action>guide me to node 1</action>
  </entry>
</knowledge>
)";

}  // namespace

TEST_CASE("Jinny's knowledge file loads: entries, keywords, questions, placeholders and actions") {
  const KnowledgeBase kb = KnowledgeBase::load(TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml");
  CHECK(kb.version() == 1);
  CHECK(kb.robot() == "jinny");
  CHECK(kb.entries().size() >= 20);
  const KnowledgeEntry* weather = kb.find("weather");
  REQUIRE(weather != nullptr);
  CHECK(weather->topic == "the weather");
  CHECK(weather->questions.front() == "How's the weather today?");
  CHECK(weather->keywords.front() == "weather");
  CHECK(weather->where.str() == TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml:63:3");
  const PlaceholderScan scan = scan_placeholders(weather->answer);
  REQUIRE(scan.placeholders.size() == 1);
  CHECK(scan.placeholders[0].name == "weather");
  REQUIRE(kb.find("show_node1") != nullptr);
  CHECK(kb.find("show_node1")->action == "guide me to node 1");
  CHECK(kb.find("no_such_entry") == nullptr);
}

TEST_CASE("a knowledge base written by to_xml reads back the same") {
  const KnowledgeBase kb = KnowledgeBase::load_from_string(kSmall, "small.xml");
  CHECK(kb.version() == 4);
  REQUIRE(kb.entries().size() == 2);
  CHECK(kb.entries()[0].keywords == std::vector<std::string>{"hello", "hi", "good morning"});
  CHECK(kb.entries()[0].answer == "Hello & welcome! Braces: {{x}}.");
  const KnowledgeBase again = KnowledgeBase::load_from_string(kb.to_xml(9), "again.xml");
  CHECK(again.version() == 9);
  CHECK(again.robot() == "jinny");
  CHECK(again.entries() == kb.entries());
}

TEST_CASE("placeholders: names of lower-case letters, digits and '_', doubled braces are literal") {
  CHECK(scan_placeholders("It is {time}, {battery_2}. {{not}} }}").placeholders.size() == 2);
  CHECK(scan_placeholders("It is {time").error == "unclosed '{' at byte 6; expected {provider} or '{{' for a brace");
  CHECK(scan_placeholders("a } b").error == "'}' at byte 2 closes nothing; write '}}' for a brace");
  CHECK(scan_placeholders("{Time}").error ==
        "placeholder '{Time}' at byte 0: expected a provider name of lower-case letters, digits and '_'");
  CHECK(scan_placeholders("{}").error == "placeholder '{}' at byte 0: expected a provider name of lower-case letters, digits and '_'");
}

TEST_CASE("malformed knowledge files: each error located at FILE:LINE:COL") {
  SECTION("malformed XML") {
    CHECK_THAT(load_error("<knowledge>\n  <entry id=\"a\" topic=\"t\">\n</knowledge>\n"),
               Catch::StartsWith("kb.xml:3:") && Catch::Contains("error: malformed XML"));
  }
  SECTION("not a knowledge file") {
    CHECK(load_error("<net id=\"x\"/>") == "kb.xml:1:1: error: root element <net>; expected <knowledge>\n");
  }
  SECTION("a bad version") {
    CHECK(load_error("<knowledge version=\"-2\"/>") == "kb.xml:1:21: error: version '-2': expected a whole number 0 or more\n");
  }
  SECTION("unknown elements and attributes, missing id and answer: all in one report") {
    const std::string e = load_error(R"(<knowledge version="1">
  <entry id="a" topic="t" colour="red">
    <keywords>x</keywords>
    <answr>typo</answr>
  </entry>
  <entry topic="t">
    <question>q?</question>
    <answer>fine</answer>
  </entry>
  <faq/>
</knowledge>
)");
    CHECK_THAT(e, Catch::Contains("kb.xml:2:27: error: unknown attribute 'colour' on <entry>; expected one of: id, topic"));
    CHECK_THAT(e, Catch::Contains("kb.xml:4:5: error: unknown element <answr> in <entry>; expected one of: keywords, question, answer, action"));
    CHECK_THAT(e, Catch::Contains("kb.xml:2:3: error: entry 'a' has no <answer>; expected one"));
    CHECK_THAT(e, Catch::Contains("kb.xml:6:3: error: <entry> has no id attribute; expected id=\"...\""));
    CHECK_THAT(e, Catch::Contains("kb.xml:10:3: error: unknown element <faq> in <knowledge>; expected <entry>"));
  }
  SECTION("a duplicate id, with a note at the first") {
    const std::string e = load_error(R"(<knowledge>
  <entry id="hello" topic="t"><keywords>hi</keywords><answer>Hi.</answer></entry>
  <entry id="hello" topic="t"><keywords>hey</keywords><answer>Hey.</answer></entry>
</knowledge>
)");
    CHECK_THAT(e, Catch::Contains("kb.xml:3:14: error: duplicate entry id 'hello'; ids must be unique"));
    CHECK_THAT(e, Catch::Contains("kb.xml:2:3: note: entry 'hello' first defined here"));
  }
  SECTION("empty answer, bad placeholder, bad id, empty keywords, nothing to match, two actions") {
    const std::string e = load_error(R"(<knowledge>
  <entry id="a" topic="t"><keywords>x</keywords><answer>  </answer></entry>
  <entry id="b" topic="t"><keywords>x</keywords><answer>It is {time.</answer></entry>
  <entry id="c d" topic="t"><keywords>x</keywords><answer>ok</answer></entry>
  <entry id="e" topic="t"><keywords> , </keywords><answer>ok</answer></entry>
  <entry id="f" topic="t"><answer>ok</answer></entry>
  <entry id="g" topic=""><keywords>x</keywords><answer>ok</answer><action>go</action><action>come</action></entry>
</knowledge>
)");
    CHECK_THAT(e, Catch::Contains("kb.xml:2:49: error: entry 'a': <answer> is empty; expected what the robot says"));
    CHECK_THAT(e, Catch::Contains("kb.xml:3:49: error: entry 'b': answer: unclosed '{' at byte 6; expected {provider} or '{{' for a brace"));
    CHECK_THAT(e, Catch::Contains("kb.xml:4:14: error: entry id 'c d': expected letters, digits, '_', '-' or '.'"));
    CHECK_THAT(e, Catch::Contains("kb.xml:5:27: error: entry 'e': <keywords> is empty; expected words separated by commas"));
    CHECK_THAT(e, Catch::Contains("kb.xml:6:3: error: entry 'f' has neither <keywords> nor <question>; expected at least one"));
    CHECK_THAT(e, Catch::Contains("kb.xml:7:24: error: entry 'g': the topic is empty; expected a few words"));
    CHECK_THAT(e, Catch::Contains("kb.xml:7:86: error: entry 'g' has a second <action>; expected at most one"));
  }
  SECTION("a file that cannot be read") {
    CHECK_THROWS_WITH(KnowledgeBase::load("/nonexistent/kb.xml"), "/nonexistent/kb.xml: error: cannot read the file\n");
  }
}

TEST_CASE("save writes the next version atomically, a stale copy is refused and the file is unchanged") {
  const TempDir dir;
  const fs::path file = dir.path / "kb.xml";
  write(file, kSmall);
  KnowledgeBase alice = KnowledgeBase::load(file);
  KnowledgeBase bob = KnowledgeBase::load(file);
  REQUIRE(alice.version() == 4);

  KnowledgeEntry entry{"exit", "the way out", {"exit", "door"}, {"Where is the exit?"}, "Behind you.", "", {}};
  alice.put(entry);
  alice.save(file);
  CHECK(alice.version() == 5);
  const KnowledgeBase reread = KnowledgeBase::load(file);
  CHECK(reread.version() == 5);
  REQUIRE(reread.find("exit") != nullptr);
  CHECK(*reread.find("exit") == entry);
  // Only the file and its lock remain: the temporary file was renamed.
  std::vector<std::string> names;
  for (const auto& f : fs::directory_iterator(dir.path)) names.push_back(f.path().filename().string());
  std::sort(names.begin(), names.end());
  CHECK(names == std::vector<std::string>{"kb.xml", "kb.xml.lock"});

  // Bob read version 4 before Alice saved version 5: his save is refused, nothing is written.
  const std::string before = read(file);
  REQUIRE(bob.remove("greeting"));
  try {
    bob.save(file);
    FAIL("a stale save was accepted");
  } catch (const StaleVersionError& e) {
    CHECK(e.expected() == 4);
    CHECK(e.found() == 5);
    CHECK_THAT(e.what(), Catch::Contains("kb.xml: stale version: this copy was read at version 4 but the file is at version 5"));
  }
  CHECK(read(file) == before);
  CHECK(bob.version() == 4);

  // After reloading, Bob's edit goes through as version 6.
  bob = KnowledgeBase::load(file);
  REQUIRE(bob.remove("greeting"));
  bob.save(file);
  CHECK(KnowledgeBase::load(file).version() == 6);
  CHECK(KnowledgeBase::load(file).find("greeting") == nullptr);
  CHECK(KnowledgeBase::load(file).find("exit") != nullptr);
}

TEST_CASE("a new base saves as version 1 where no file is, and not over an existing one") {
  const TempDir dir;
  KnowledgeBase kb;
  kb.put({"hello", "greetings", {"hello"}, {}, "Hello!", "", {}});
  kb.save(dir.path / "new.xml");
  CHECK(kb.version() == 1);
  CHECK(KnowledgeBase::load(dir.path / "new.xml").entries() == kb.entries());
  KnowledgeBase other;
  other.put({"bye", "goodbye", {"bye"}, {}, "Bye!", "", {}});
  CHECK_THROWS_AS(other.save(dir.path / "new.xml"), StaleVersionError);
}

TEST_CASE("put refuses an entry the loader would refuse, and leaves the base unchanged") {
  KnowledgeBase kb = KnowledgeBase::load_from_string(kSmall, "small.xml");
  const auto before = kb.entries();
  CHECK_THROWS_WITH(kb.put({"bad id", "t", {"x"}, {}, "ok", "", {}}),
                    "entry id 'bad id': expected letters, digits, '_', '-' or '.'");
  CHECK_THROWS_WITH(kb.put({"greeting", "t", {}, {}, "It is {time", "", {}}),
                    "entry 'greeting' has neither keywords nor questions; expected at least one; entry 'greeting': answer: "
                    "unclosed '{' at byte 6; expected {provider} or '{{' for a brace");
  CHECK(kb.entries() == before);
  kb.put({"greeting", "greetings", {"hey"}, {}, "Hey!", "", {}});
  CHECK(kb.find("greeting")->answer == "Hey!");
  CHECK(kb.entries().size() == 2);
  CHECK(kb.remove("greeting"));
  CHECK_FALSE(kb.remove("greeting"));
}
