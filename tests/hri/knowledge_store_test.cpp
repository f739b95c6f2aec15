// The RKMS administration store: changes validated field by field, saved atomically with the
// file's version moved on, per-entry versions refusing stale edits, the history, and the state
// read back from disk equal to the store's.
#include "tripodal/hri/knowledge_store.hpp"

#include <catch2/catch.hpp>

#include <atomic>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <thread>

#include "tripodal/hri/hri_service.hpp"

using namespace tripodal;
namespace fs = std::filesystem;

namespace {

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// A fresh folder holding a copy of Jinny's knowledge (version 1, 25 entries).
struct Folder {
  fs::path dir;
  fs::path file;
  Folder() {
    dir = fs::temp_directory_path() / ("tripodal_rkms_" + std::to_string(::getpid()) + "_" +
                                       std::to_string(std::chrono::steady_clock::now().time_since_epoch().count()));
    fs::create_directories(dir);
    file = dir / "jinny.xml";
    fs::copy_file(TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml", file);
  }
  ~Folder() {
    std::error_code ec;
    fs::remove_all(dir, ec);
  }
  Folder(const Folder&) = delete;
  Folder& operator=(const Folder&) = delete;
};

KnowledgeStoreOptions fixed_time() {
  KnowledgeStoreOptions o;
  o.now = [] { return std::chrono::system_clock::time_point(std::chrono::seconds(1795000000)); };
  return o;
}

KnowledgeEntry parking() {
  return {"parking", "the parking", {"parking", "car", "park"}, {"Where can I park my car?"},
          "The car park is behind the hall, entrance B.", "", {}};
}

// The store's entries as the loader reads them from its file: what a restarted robot would know.
void require_disk_equals_store(const KnowledgeStore& store) {
  const KnowledgeBase disk = KnowledgeBase::load(store.file());
  const KnowledgeBase mem = store.base();
  REQUIRE(disk.version() == mem.version());
  REQUIRE(disk.entries() == mem.entries());
}

}  // namespace

TEST_CASE("store: add, edit and delete are saved, each as the next version of the file") {
  Folder f;
  KnowledgeStore store(f.file, fixed_time());
  REQUIRE(store.version() == 1);
  REQUIRE(store.entries().size() == 25);
  REQUIRE(store.get("weather")->version == 1);

  const KnowledgeEdit added = store.add(parking(), "alice");
  REQUIRE(added.ok());
  CHECK(added.version == 2);
  CHECK(added.entry_version == 2);
  CHECK(added.message == "entry 'parking' added as version 2");
  REQUIRE(store.get("parking"));
  CHECK(store.get("parking")->entry == parking());
  CHECK(slurp(f.file).find("<knowledge version=\"2\" robot=\"jinny\">") != std::string::npos);
  require_disk_equals_store(store);

  KnowledgeEntry changed = parking();
  changed.answer = "The car park is behind the hall, entrance C.";
  const KnowledgeEdit edited = store.edit("parking", changed, 2, "bob");
  REQUIRE(edited.ok());
  CHECK(edited.version == 3);
  CHECK(store.get("parking")->entry.answer == "The car park is behind the hall, entrance C.");
  CHECK(store.get("parking")->version == 3);
  CHECK(store.get("weather")->version == 1);  // untouched entries keep theirs
  require_disk_equals_store(store);

  const KnowledgeEdit removed = store.remove("parking", 3, "carol");
  REQUIRE(removed.ok());
  CHECK(removed.version == 4);
  CHECK_FALSE(store.get("parking"));
  CHECK(store.entries().size() == 25);
  require_disk_equals_store(store);
  // Only the file, its lock and the history are left: no temporary file.
  std::size_t files = 0;
  for ([[maybe_unused]] const auto& e : fs::directory_iterator(f.dir)) ++files;
  CHECK(files == 3);
}

TEST_CASE("store: an entry saved with line breaks, entities and spaces reads back equal from the file") {
  Folder f;
  KnowledgeStore store(f.file);
  KnowledgeEntry e{"quotes.and-amps_1", "  <odd> & \"quoted\" topic  ", {" R&D ", "a<b"}, {"What is 1 < 2 & \"so\"?\r\nReally?"},
                   "Line one,\r\nline two & {{braces}} and {time}.\n", "guide me to node 1", {}};
  REQUIRE(store.add(e, "").ok());
  const KnowledgeBase disk = KnowledgeBase::load(f.file);
  const KnowledgeEntry* back = disk.find("quotes.and-amps_1");
  REQUIRE(back != nullptr);
  CHECK(back->topic == "<odd> & \"quoted\" topic");
  CHECK(back->keywords == std::vector<std::string>{"R&D", "a<b"});
  CHECK(back->questions == std::vector<std::string>{"What is 1 < 2 & \"so\"?\nReally?"});
  CHECK(back->answer == "Line one,\nline two & {{braces}} and {time}.");
  CHECK(*back == store.get("quotes.and-amps_1")->entry);
  require_disk_equals_store(store);
}

TEST_CASE("store: a stale edit or delete is refused and changes nothing") {
  Folder f;
  KnowledgeStore store(f.file);
  REQUIRE(store.add(parking(), "alice").ok());  // version 2
  // Two editors read parking at version 2; the first saves.
  KnowledgeEntry first = parking();
  first.answer = "Entrance C.";
  REQUIRE(store.edit("parking", first, 2, "first").ok());
  const std::string file_before = slurp(f.file);
  const auto history_before = store.history().size();

  KnowledgeEntry second = parking();
  second.answer = "Entrance D.";
  const KnowledgeEdit stale = store.edit("parking", second, 2, "second");
  CHECK(stale.status == KnowledgeEdit::Status::stale);
  CHECK(stale.message ==
        "entry 'parking' was changed since you read it (you edited version 2, it is now at version 3); nothing was saved: "
        "reload it and apply your change again");
  CHECK(stale.entry_version == 3);
  REQUIRE(stale.current);
  CHECK(stale.current->answer == "Entrance C.");
  const KnowledgeEdit stale_delete = store.remove("parking", 2, "second");
  CHECK(stale_delete.status == KnowledgeEdit::Status::stale);

  CHECK(slurp(f.file) == file_before);
  CHECK(store.history().size() == history_before);
  CHECK(store.get("parking")->entry.answer == "Entrance C.");
  CHECK(store.version() == 3);

  // Deleted meanwhile: not found, still nothing changes.
  REQUIRE(store.remove("parking", 3, "first").ok());
  CHECK(store.edit("parking", second, 3, "second").status == KnowledgeEdit::Status::not_found);
  CHECK(store.add(KnowledgeEntry{"weather", "t", {"x"}, {}, "a", "", {}}, "x").status == KnowledgeEdit::Status::exists);
}

TEST_CASE("store: the file changed on disk since the store read it: the save is refused, the file kept") {
  Folder f;
  KnowledgeStore store(f.file);
  KnowledgeStore other(f.file);  // a second robot process, or a hand edit
  REQUIRE(other.add(parking(), "other").ok());
  const std::string file_before = slurp(f.file);
  const KnowledgeEdit r = store.remove("weather", 1, "me");
  CHECK(r.status == KnowledgeEdit::Status::stale);
  CHECK_THAT(r.message, Catch::Contains("this copy was read at version 1 but the file is at version 2"));
  CHECK(slurp(f.file) == file_before);
  CHECK(store.get("weather"));
  store.reload();
  CHECK(store.version() == 2);
  CHECK(store.get("parking")->version == 2);  // from the history the other store wrote
  REQUIRE(store.remove("weather", 1, "me").ok());
}

TEST_CASE("store: invalid entries are refused naming the field, and nothing is saved") {
  Folder f;
  KnowledgeStore store(f.file);
  const std::string before = slurp(f.file);
  const auto refused_at = [&](KnowledgeEntry e, const std::string& field, const std::string& message_part) {
    const KnowledgeEdit r = store.add(std::move(e), "x");
    REQUIRE(r.status == KnowledgeEdit::Status::invalid);
    REQUIRE_FALSE(r.errors.empty());
    CHECK(r.errors.front().field == field);
    CHECK_THAT(r.errors.front().message, Catch::Contains(message_part));
  };
  KnowledgeEntry e = parking();
  e.id = "bad id";
  refused_at(e, "id", "expected letters, digits, '_', '-' or '.'");
  e = parking();
  e.topic = "   ";
  refused_at(e, "topic", "the topic is empty");
  e = parking();
  e.answer = "";
  refused_at(e, "answer", "the answer is empty");
  e = parking();
  e.answer = "It is {time";
  refused_at(e, "answer", "unclosed '{' at byte 6");
  e = parking();
  e.keywords = {"car", "a,b"};
  refused_at(e, "keywords[1]", "holds a comma");
  e = parking();
  e.keywords.clear();
  e.questions.clear();
  refused_at(e, "keywords", "neither keywords nor questions");
  // Oversize and binary fields: refused politely, before anything reads them.
  e = parking();
  e.answer = std::string(1 << 20, 'a');
  refused_at(e, "answer", "answer is 1048576 bytes long; expected at most 4000");
  e = parking();
  e.questions = {std::string("Where\0is it?", 12)};
  refused_at(e, "questions[0]", "not text: U+0000 at character 5 (byte 5)");
  e = parking();
  e.topic = "\xff\xfe parking";
  refused_at(e, "topic", "not text");
  e = parking();
  e.action = "guide me\nto node 1";
  refused_at(e, "action", "holds a line break");
  e = parking();
  e.keywords.assign(65, "car");
  refused_at(e, "keywords", "65 keywords; expected at most 64");
  // Renaming through an edit.
  KnowledgeEntry w = store.get("weather")->entry;
  w.id = "weather2";
  const KnowledgeEdit renamed = store.edit("weather", w, 1, "x");
  REQUIRE(renamed.status == KnowledgeEdit::Status::invalid);
  CHECK(renamed.errors.front().field == "id");

  CHECK(slurp(f.file) == before);
  CHECK(store.history().empty());
  CHECK(store.version() == 1);
}

TEST_CASE("store: a save that cannot be written leaves the old file and the store as they were") {
  Folder f;
  KnowledgeStore store(f.file);
  const std::string before = slurp(f.file);
  // The temporary file's name is taken by a folder: creating it fails (as it would in a folder
  // the robot may not write, which a test running as root cannot make).
  const fs::path blocker = f.dir / (".jinny.xml.tmp." + std::to_string(::getpid()));
  fs::create_directory(blocker);
  const KnowledgeEdit r = store.add(parking(), "alice");
  CHECK(r.status == KnowledgeEdit::Status::failed);
  CHECK_THAT(r.message, Catch::StartsWith("the knowledge file could not be saved; it is unchanged: cannot create"));
  CHECK(slurp(f.file) == before);
  CHECK_FALSE(store.get("parking"));
  CHECK(store.version() == 1);
  CHECK(store.history().empty());
  CHECK_FALSE(fs::exists(store.history_file()));
  fs::remove(blocker);
  REQUIRE(store.add(parking(), "alice").ok());
  require_disk_equals_store(store);
}

TEST_CASE("store: the history records who, when, what, before and after, and survives a restart") {
  Folder f;
  {
    KnowledgeStore store(f.file, fixed_time());
    REQUIRE(store.add(parking(), "alice").ok());
    KnowledgeEntry changed = parking();
    changed.answer = "Entrance C.";
    REQUIRE(store.edit("parking", changed, 2, "bob").ok());
    REQUIRE(store.remove("age", 1, "carol").ok());
    const auto h = store.history();
    REQUIRE(h.size() == 3);
    CHECK(h[0].version == 2);
    CHECK(h[0].author == "alice");
    CHECK(h[0].kind == KnowledgeChange::Kind::add);
    CHECK(h[0].time_utc == "2026-11-18T11:06:40Z");
    CHECK_FALSE(h[0].before);
    CHECK(*h[0].after == parking());
    CHECK(h[1].kind == KnowledgeChange::Kind::edit);
    CHECK(h[1].before->answer == "The car park is behind the hall, entrance B.");
    CHECK(h[1].after->answer == "Entrance C.");
    CHECK(h[2].kind == KnowledgeChange::Kind::remove);
    CHECK(h[2].id == "age");
    CHECK(h[2].before->topic == "my age");
    CHECK_FALSE(h[2].after);
    CHECK(store.history(1).front().version == 4);
  }
  // A crash in the middle of an append leaves half a line: it is skipped.
  std::ofstream(f.dir / "jinny.xml.history", std::ios::app) << "{\"version\":5,\"op\":\"ed";
  KnowledgeStore again(f.file);
  CHECK(again.history().size() == 3);
  CHECK(again.version() == 4);
  CHECK(again.get("parking")->version == 3);
  CHECK(again.get("weather")->version == 1);
  // The history tells who changed an entry since: an editor who read parking at 2 is refused.
  CHECK(again.edit("parking", parking(), 2, "late").status == KnowledgeEdit::Status::stale);
  require_disk_equals_store(again);
}

TEST_CASE("store: a hand-edited file makes every entry as new as the file") {
  Folder f;
  {
    KnowledgeStore store(f.file);
    REQUIRE(store.add(parking(), "alice").ok());  // history ends at 2
  }
  std::string text = slurp(f.file);
  text.replace(text.find("version=\"2\""), 11, "version=\"7\"");
  std::ofstream(f.file, std::ios::trunc) << text;
  KnowledgeStore store(f.file);
  CHECK(store.get("weather")->version == 7);
  CHECK(store.get("parking")->version == 7);
  CHECK(store.edit("parking", parking(), 2, "x").status == KnowledgeEdit::Status::stale);
}

TEST_CASE("store: search finds entries containing every word of the query") {
  Folder f;
  KnowledgeStore store(f.file);
  CHECK(store.search("").size() == 25);
  const auto rain = store.search("RAIN");
  REQUIRE_FALSE(rain.empty());
  CHECK(rain.front().entry.id == "weather");
  CHECK(store.search("node 1 guide").size() < store.search("node").size());
  CHECK(store.search("no such words here").empty());
}

namespace {

class NoPlaces final : public TaskKnowledge {
 public:
  ListResult list(std::string_view, std::string_view) const override { return {false, {}, "none"}; }
};

// Jinny's three placeholders, from fixed text.
AnswerProviders fixed_providers() {
  AnswerProviders providers;
  providers.add("time", std::make_unique<FixedProvider>("14:05"));
  providers.add("battery", std::make_unique<FixedProvider>("82 percent"));
  providers.add("weather", std::make_unique<FixedProvider>("sunny"));
  return providers;
}

}  // namespace

TEST_CASE("StoreBackedHri answers from an edit at once and refuses a provider the robot lacks") {
  Folder f;
  KnowledgeStore store(f.file);
  const TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  const NoPlaces places;
  const AnswerProviders providers = fixed_providers();
  StoreBackedHri hri(store, tasks, places, providers, [](const Understanding&) { return std::string(); });

  CHECK(hri.ask("where can I park my car").kind == HriReply::Kind::not_understood);
  REQUIRE(store.add(parking(), "alice").ok());
  const HriReply parked = hri.ask("where can I park my car");
  CHECK(parked.kind == HriReply::Kind::answered);
  CHECK(parked.entry_id == "parking");
  CHECK(parked.text == "The car park is behind the hall, entrance B.");
  CHECK(hri.indexed_version() == 2);

  KnowledgeEntry stock = parking();
  stock.answer = "The stock is {stock}.";
  const KnowledgeEdit r = store.edit("parking", stock, 2, "x");
  REQUIRE(r.status == KnowledgeEdit::Status::invalid);
  CHECK(r.errors.front().field == "answer");
  CHECK(r.errors.front().message == "the answer names {stock}, which this robot does not provide (it has: {battery}, {time}, {weather})");

  REQUIRE(store.remove("parking", 2, "x").ok());
  CHECK(hri.ask("where can I park my car").kind == HriReply::Kind::not_understood);
}

TEST_CASE("StoreBackedHri displays the internal state and the last exchange, kept when an edit re-indexes it", "[hri][store][display]") {
  Folder f;
  KnowledgeStore store(f.file);
  const TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  const NoPlaces places;
  const AnswerProviders providers = fixed_providers();
  StoreBackedHri hri(store, tasks, places, providers, [](const Understanding&) { return std::string("the robot is charging"); });

  CHECK_FALSE(hri.display().last.has_value());
  CHECK(display_text(hri.display().state) == "idle | no process | no fault");
  hri.module().set_internal_state({"guide", "running", "PrAutoMove(goal=node1)", ""});
  (void)hri.ask("How's the weather today?");
  HriDisplay d = hri.display();
  REQUIRE(d.last.has_value());
  CHECK(d.last->source == "typed");
  CHECK(d.last->input == "How's the weather today?");
  CHECK(d.last->kind == HriReply::Kind::answered);
  CHECK(d.last->entry == "weather");
  CHECK(d.last->reply == "The weather today: sunny.");
  CHECK(display_text(d.state) == "task guide: running | process PrAutoMove(goal=node1) | no fault");

  // A command the planner refuses: its reason, in plain words, is what the display shows.
  (void)hri.ask("dance for us");
  d = hri.display();
  CHECK(d.last->kind == HriReply::Kind::task_refused);
  CHECK(d.last->task == "dance");
  CHECK(d.last->reply == "Sorry, I cannot start the dance task now: the robot is charging.");

  // An edit makes the next input re-index: the new module shows what the old one showed.
  REQUIRE(store.add(parking(), "alice").ok());
  (void)hri.module();
  CHECK(hri.indexed_version() == 2);
  d = hri.display();
  CHECK(d.last->input == "dance for us");
  CHECK(d.state.process == "PrAutoMove(goal=node1)");

  // Inputs refused unread are described, never copied; a button and a recognition name theirs.
  (void)hri.ask(std::string(1 << 20, 'x'));
  CHECK(hri.display().last->input == "(1048576 bytes: too long)");
  (void)hri.ask(std::string("ab\0cd", 5));
  CHECK(hri.display().last->input == "(5 bytes: not text)");
  CHECK(hri.display().last->kind == HriReply::Kind::refused_input);
  (void)hri.module().handle_button("nothing");
  CHECK(hri.display().last->source == "button");
  CHECK(hri.display().last->reply == "Sorry, that button does nothing here.");
  (void)hri.module().handle_heard({"where can i park my car", 0.5});
  CHECK(hri.display().last->source == "heard");
  CHECK(hri.display().last->entry == "parking");
}

TEST_CASE("store: changes from two threads are all saved, each under a version of its own", "[hri][store][threads]") {
  Folder f;
  KnowledgeStore store(f.file);
  // Catch2's assertions are not thread-safe: the threads count, the test thread checks.
  std::atomic<int> saved{0};
  const auto writer = [&store, &saved](const std::string& prefix) {
    for (int i = 0; i < 10; ++i) {
      KnowledgeEntry e = parking();
      e.id = prefix + std::to_string(i);
      if (store.add(e, prefix).ok()) ++saved;
      (void)store.search("car");  // readers in between
    }
  };
  std::thread a(writer, "a");
  std::thread b(writer, "b");
  a.join();
  b.join();
  REQUIRE(saved == 20);
  const auto h = store.history();
  REQUIRE(h.size() == 20);
  for (std::size_t i = 0; i < h.size(); ++i) CHECK(h[i].version == i + 2);
  CHECK(store.version() == 21);
  CHECK(store.entries().size() == 45);
  require_disk_equals_store(store);
}

TEST_CASE("store: a text XML cannot hold (U+FFFE, U+FFFF, controls, bad UTF-8) is refused at its place, and later saves and the file still load",
          "[hri][store][xml]") {
  Folder f;
  KnowledgeStore store(f.file);
  const std::string before = slurp(f.file);
  const auto refused = [&](KnowledgeEntry e, const std::string& field, const std::string& where) {
    const KnowledgeEdit r = store.add(std::move(e), "x");
    REQUIRE(r.status == KnowledgeEdit::Status::invalid);
    REQUIRE_FALSE(r.errors.empty());
    CHECK(r.errors.front().field == field);
    CHECK_THAT(r.errors.front().message, Catch::Contains("is not text") && Catch::Contains(where));
  };
  KnowledgeEntry e = parking();
  e.answer = "Behind the hall \xEF\xBF\xBE entrance B.";  // U+FFFE at character 16
  refused(e, "answer", "U+FFFE at character 16 (byte 16)");
  e = parking();
  e.questions = {"Where \xC3\xA9 \xEF\xBF\xBF?"};  // U+FFFF after "é": character 8, byte 9
  refused(e, "questions[0]", "U+FFFF at character 8 (byte 9)");
  e = parking();
  e.topic = "the \xED\xA0\x80 parking";  // an encoded lone surrogate
  refused(e, "topic", "byte 0xED at character 4 (byte 4) is not UTF-8");
  e = parking();
  e.keywords = {"car", std::string("pa\x01rk")};
  refused(e, "keywords[1]", "U+0001 at character 2 (byte 2)");
  CHECK(slurp(f.file) == before);
  CHECK(store.version() == 1);

  // Nothing refused was kept: the next change saves, and the file loads again (Jinny would start).
  REQUIRE(store.add(parking(), "x").ok());
  CHECK(store.version() == 2);
  require_disk_equals_store(store);
  CHECK(KnowledgeBase::load(f.file).find("parking") != nullptr);
}

TEST_CASE("KnowledgeBase::save refuses a text XML cannot hold, naming entry, field and place, and writes nothing", "[hri][store][xml]") {
  Folder f;
  KnowledgeBase base = KnowledgeBase::load(f.file);
  const std::string before = slurp(f.file);
  KnowledgeEntry e = parking();
  e.answer = "ok \xEF\xBF\xBF";
  base.put(e);
  CHECK_THROWS_WITH(base.save(f.file), Catch::Contains("entry 'parking' answer: U+FFFF at character 3 (byte 3)") &&
                                           Catch::Contains("nothing was saved"));
  CHECK(slurp(f.file) == before);
  CHECK(base.version() == 1);
}

TEST_CASE("store: history lines whose fields have the wrong JSON type are skipped, the store still loads", "[hri][store]") {
  Folder f;
  {
    KnowledgeStore store(f.file, fixed_time());
    REQUIRE(store.add(parking(), "alice").ok());
  }
  // Edited by hand: each line a field of another type than the store writes.
  std::ofstream(f.dir / "jinny.xml.history", std::ios::app)
      << R"({"version":3,"op":5,"id":"x"})" << "\n"
      << R"({"version":3,"op":"edit","id":["x"]})" << "\n"
      << R"({"version":3,"op":"edit","id":"parking","time":7})" << "\n"
      << R"({"version":3,"op":"edit","id":"parking","after":{"keywords":"car"}})" << "\n"
      << R"({"version":3,"op":"edit","id":"parking","after":{"keywords":[1,2]}})" << "\n"
      << R"({"version":3,"op":"edit","id":"parking","before":{"answer":false}})" << "\n";
  const KnowledgeStore again(f.file);
  REQUIRE(again.history().size() == 1);
  CHECK(again.history().front().author == "alice");
  CHECK(again.get("parking")->version == 2);
}
