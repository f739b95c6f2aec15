#include "tripodal/hri/hri_module.hpp"

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <catch2/catch.hpp>
#include <iostream>
#include <map>
#include <string>

using namespace tripodal;

namespace {

using namespace std::chrono_literals;

// The exhibit hall of the paper's section 5.2: node 0 and node 1.
class ExhibitHall final : public TaskKnowledge {
 public:
  ListResult list(std::string_view function, std::string_view argument) const override {
    if (function != "node") return {false, {}, "no list named '" + std::string(function) + "'"};
    if (argument == "0" || argument == "1") return {true, {"node" + std::string(argument)}, {}};
    return {false, {}, "unknown node '" + std::string(argument) + "' (known: 0, 1)"};
  }
  std::vector<std::string> known(std::string_view function) const override {
    if (function == "node") return {"0", "1"};
    return {};
  }
};

// Jinny's HRI over the shipped knowledge and tasks, with fixed local providers and a planner
// double that records what it was asked to start.
struct Jinny {
  SimClock clock;
  KnowledgeBase base = KnowledgeBase::load(TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml");
  TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  ExhibitHall hall;
  AnswerProviders providers;
  double battery = 0.82;
  std::vector<std::string> started;
  std::string refuse_with;  // what the planner double answers; empty: it starts the task
  HriModule hri;

  static AnswerProviders make_providers(const SimClock& clock, const double& battery) {
    AnswerProviders p;
    p.add("time", std::make_unique<ClockTimeProvider>(clock, 14h + 5min));
    p.add("battery", std::make_unique<BatteryProvider>([&battery] { return battery; }));
    p.add("weather", std::make_unique<WeatherTableProvider>(clock, 14h + 5min,
                                                            std::vector<std::string>{"sunny, 27 degrees", "light rain, 22 degrees"}));
    return p;
  }

  explicit Jinny(HriOptions options = {})
      : providers(make_providers(clock, battery)),
        hri(base, tasks, hall, providers, [this](const Understanding& u) {
          if (!refuse_with.empty()) return refuse_with;
          started.push_back(to_string(u.plan));
          return std::string();
        }, std::move(options)) {}
};

struct Expected {
  std::string say;
  std::string outcome;
  std::string entry;
  std::string task;
};

std::vector<Expected> utterance_set(const std::string& file) {
  const YAML::Node doc = YAML::LoadFile(TRIPODAL_TEST_DATA_DIR "/hri/" + file);
  std::vector<Expected> out;
  for (const auto& u : doc["utterances"]) {
    out.push_back({u["say"].as<std::string>(), u["outcome"].as<std::string>(),
                   u["entry"] ? u["entry"].as<std::string>() : std::string(),
                   u["task"] ? u["task"].as<std::string>() : std::string()});
  }
  return out;
}

}  // namespace

namespace {

// The share of `file`'s utterances typed to Jinny that get the expected outcome; prints the misses.
double typed_accuracy(const std::string& file) {
  Jinny jinny;
  const std::vector<Expected> set = utterance_set(file);
  std::size_t right = 0;
  std::string misses;
  // Per kind of the issue (answer, command, refusal, out of domain): right, of.
  std::map<std::string, std::pair<std::size_t, std::size_t>> per_kind;
  for (const auto& e : set) {
    const HriReply r = jinny.hri.handle(e.say);
    const bool ok = to_string(r.kind) == e.outcome && r.entry_id == e.entry && r.task == e.task;
    const std::string kind = e.outcome == "answered"       ? "answer"
                             : e.outcome == "task_started" ? "command"
                             : e.outcome == "task_refused" ? "refusal"
                                                           : "out of domain";
    ++per_kind[kind].second;
    if (ok) ++per_kind[kind].first;
    if (e.outcome == "not_understood") {
      std::cout << "  (not understood as expected: \"" << e.say << "\", best confidence " << r.confidence << ")\n";
    }
    if (ok) {
      ++right;
    } else {
      misses += "  \"" + e.say + "\": expected " + e.outcome + " " + e.entry + " " + e.task + ", got " +
                std::string(to_string(r.kind)) + " " + r.entry_id + " " + r.task + " (confidence " +
                std::to_string(r.confidence) + "): " + r.text + "\n";
    }
  }
  const double accuracy = set.empty() ? 0.0 : static_cast<double>(right) / static_cast<double>(set.size());
  std::cout << "HRI typed utterance set " << file << ": " << right << "/" << set.size() << " right, accuracy " << accuracy * 100.0
            << " %;";
  for (const auto& [kind, f] : per_kind) std::cout << " " << kind << " " << f.first << "/" << f.second;
  std::cout << "\n" << misses;
  return accuracy;
}

}  // namespace

TEST_CASE("the typed utterance set is classified and answered right at least 95 % of the time") {
  REQUIRE(utterance_set("utterances.yaml").size() >= 60);
  CHECK(typed_accuracy("utterances.yaml") >= 0.95);
}

TEST_CASE("the development typed utterance set is answered right at least 90 % of the time") {
  REQUIRE(utterance_set("utterances_dev.yaml").size() >= 40);
  CHECK(typed_accuracy("utterances_dev.yaml") >= 0.90);
}

TEST_CASE("the held-out typed utterance set is answered right at least 85 % of the time") {
  // Phrasings nothing was tuned on: measured 90 % (36/40) when they were first run.
  REQUIRE(utterance_set("utterances_heldout.yaml").size() >= 40);
  CHECK(typed_accuracy("utterances_heldout.yaml") >= 0.85);
}

TEST_CASE("answers fill their placeholders from the providers, which follow the injected clock") {
  Jinny jinny;
  HriReply r = jinny.hri.handle("What time is it?");
  CHECK(r.kind == HriReply::Kind::answered);
  CHECK(r.text == "It is 14:05.");
  jinny.clock.advance(1h + 30s);
  CHECK(jinny.hri.handle("what time is it").text == "It is 15:05.");
  CHECK(jinny.hri.handle("How's weather today?").text == "The weather today: sunny, 27 degrees.");
  jinny.clock.advance(24h);
  CHECK(jinny.hri.handle("How's weather today?").text == "The weather today: light rain, 22 degrees.");
  CHECK(jinny.hri.handle("how much battery do you have").text == "My battery is at 82 percent.");
  jinny.battery = 0.305;
  CHECK(jinny.hri.handle("how much battery do you have").text == "My battery is at 31 percent.");
  jinny.battery = -1.0;
  CHECK(jinny.hri.handle("how much battery do you have").text == "My battery is at unknown.");
  CHECK(jinny.started.empty());
}

TEST_CASE("a command input becomes a plan for the planner, and an entry's action starts one after the answer") {
  Jinny jinny;
  const HriReply guide = jinny.hri.handle("Could you guide me to node 1, please?");
  CHECK(guide.kind == HriReply::Kind::task_started);
  CHECK(guide.task == "guide");
  CHECK(to_string(guide.plan) == "PrAutoMove(goal=node1)");
  CHECK(guide.text == "All right, I am starting the guide task.");

  const HriReply show = jinny.hri.handle("Show me the cleaning robot");
  CHECK(show.kind == HriReply::Kind::answered);
  CHECK(show.entry_id == "show_node1");
  CHECK_THAT(show.text, Catch::StartsWith("Follow me, I will take you to PSR-2"));
  CHECK(to_string(show.plan) == "PrAutoMove(goal=node1)");
  CHECK(jinny.started == std::vector<std::string>{"PrAutoMove(goal=node1)", "PrAutoMove(goal=node1)"});
}

TEST_CASE("the planner's refusal is spoken back in plain words, without the list of command forms") {
  Jinny jinny;
  const HriReply unknown_node = jinny.hri.handle("guide me to node 7");
  CHECK(unknown_node.kind == HriReply::Kind::task_refused);
  CHECK(unknown_node.text == "Sorry, there is no node 7 here. I can guide you to node 0 or 1.");

  // Spoken to a visitor, never the parser's trace.
  const HriReply kitchen = jinny.hri.handle("guide me to the kitchen");
  CHECK(kitchen.kind == HriReply::Kind::task_refused);
  CHECK(kitchen.text == "Sorry, I did not understand that request. I can guide you to node 0 or 1.");
  CHECK_THAT(kitchen.text, !Catch::Contains("Possible commands"));
  CHECK_THAT(kitchen.text, !Catch::Contains("expected"));

  // The planner itself may refuse a task it understood (busy, faulted): its reason is spoken.
  jinny.refuse_with = "the robot is charging";
  const HriReply busy = jinny.hri.handle("dance for us");
  CHECK(busy.kind == HriReply::Kind::task_refused);
  CHECK(busy.text == "Sorry, I cannot start the dance task now: the robot is charging.");
  const HriReply show = jinny.hri.handle("Show me the cleaning robot");
  CHECK(show.kind == HriReply::Kind::answered);
  CHECK_THAT(show.text, Catch::EndsWith("But I cannot do it now: the robot is charging."));
  CHECK(show.task.empty());
  CHECK(jinny.started.empty());
}

TEST_CASE("below the confidence threshold the HRI says it did not understand and offers the closest topics") {
  Jinny jinny;
  const HriReply r = jinny.hri.handle("What is the capital of France?");
  CHECK(r.kind == HriReply::Kind::not_understood);
  CHECK(r.closest_topics.size() == 3);
  CHECK_THAT(r.text, Catch::StartsWith("Sorry, I did not understand that. I can tell you about "));
  // A question sharing a word with an entry but about something else: the closest topic offered.
  const HriReply r2 = jinny.hri.handle("what time does the football match on tv start tonight");
  CHECK(r2.kind == HriReply::Kind::not_understood);
  // ("tonight" is related to "night", the greeting's "good night", through the lexicon: offered too.)
  CHECK(std::find(r2.closest_topics.begin(), r2.closest_topics.end(), "the time") != r2.closest_topics.end());
}

TEST_CASE("empty, huge and binary utterances get a polite refusal and nothing runs") {
  Jinny jinny;
  const std::string huge(1 << 20, 'a');
  std::string binary = "guide me to node 1";
  binary[5] = '\0';
  const std::string bad_utf8 = "guide me to node 1 \xC3\x28";
  std::string long_command;
  while (long_command.size() < 600) long_command += "guide me to node 1 ";
  for (const std::string& input : {std::string(), std::string("  \t\n "), std::string("?!..."), huge, binary, bad_utf8, long_command}) {
    const HriReply r = jinny.hri.handle(input);
    CHECK(r.kind == HriReply::Kind::refused_input);
    CHECK_THAT(r.text, Catch::StartsWith("Sorry") || Catch::StartsWith("I did not catch anything"));
    CHECK(r.task.empty());
    CHECK(r.entry_id.empty());
  }
  CHECK(jinny.hri.handle(huge).text == "Sorry, that is too long for me. Please ask me in a sentence or two.");
  CHECK(jinny.hri.handle(binary).text == "Sorry, I can only understand words. Please type or say your question again.");
  CHECK(jinny.started.empty());
}

TEST_CASE("an answer naming a provider the application did not plug in is refused at the entry") {
  const KnowledgeBase base = KnowledgeBase::load_from_string(R"(<knowledge version="1">
  <entry id="stock" topic="stocks">
    <keywords>stock</keywords>
    <answer>Today: {stocks}.</answer>
  </entry>
</knowledge>
)",
                                                             "kb.xml");
  const TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  const ExhibitHall hall;
  AnswerProviders providers;
  providers.add("time", std::make_unique<FixedProvider>("noon"));
  CHECK_THROWS_WITH(HriModule(base, tasks, hall, providers, {}),
                    "kb.xml:2:3: error: entry 'stock': the answer names {stocks}, which no provider gives; providers: time\n");
}

TEST_CASE("typo correction maps unknown words to the nearest known word and keeps numbers") {
  Jinny jinny;
  CHECK(jinny.hri.index().correct("Gide me to node 12, whats the wether") == "guide me to node 12 whats the weather");
  // Too far from any word: kept as it is.
  CHECK(jinny.hri.index().correct("xylophone") == "xylophone");
}

TEST_CASE("a heard utterance is handled in typed form, and not at all when the recognizer is unsure") {
  Jinny jinny;
  const HriReply sure = jinny.hri.handle_heard({"guide me to node one", 0.6});
  CHECK(sure.kind == HriReply::Kind::task_started);
  CHECK(to_string(sure.plan) == "PrAutoMove(goal=node1)");
  const HriReply unsure = jinny.hri.handle_heard({"guide me to node one", 0.0005});
  CHECK(unsure.kind == HriReply::Kind::not_understood);
  CHECK(unsure.text == "Sorry, I did not catch that. Could you say it again?");
  CHECK(jinny.started.size() == 1);
  CHECK(jinny.hri.handle_heard({"tell me about p s r two", 0.1}).entry_id == "node1_robot");
  CHECK(jinny.hri.handle_heard({"", 0.0}).kind == HriReply::Kind::refused_input);
}

TEST_CASE("a heard sentence that is not understood gives way to the first alternative that is a command") {
  using Alternative = SpeechRecognizer::Result::Alternative;
  Jinny jinny;
  // The best sentence misheard one word ("to" for "at"); the second alternative is the command.
  SpeechRecognizer::Result heard{"explain the robot to node one", 0.01, {}};
  heard.alternatives = {Alternative{"explain the robot at to node one", -0.1}, Alternative{"explain the robot at node one", -0.2}};
  // Not what was heard best: asked about first, started on a yes.
  const HriReply r = jinny.hri.handle_heard(heard);
  CHECK(r.kind == HriReply::Kind::confirm_task);
  CHECK(r.task == "explain");
  CHECK(r.text == "Did you say \"explain the robot at node 1\"? Please say yes or no.");
  REQUIRE(jinny.hri.last_exchange().has_value());
  CHECK(jinny.hri.last_exchange()->input == "explain the robot at node one");
  CHECK(jinny.started.empty());
  CHECK(jinny.hri.handle_heard({"yes", 0.3, {}}).kind == HriReply::Kind::task_started);
  CHECK(jinny.started == std::vector<std::string>{"PrAutoMove(goal=node1) -> PrExplain(topic=the robot at node 1)"});

  // Too far behind the best (max_alternative_log_gap): the best is answered as heard.
  heard.alternatives = {Alternative{"explain the robot at node one", -3.0}};
  CHECK(jinny.hri.handle_heard(heard).kind == HriReply::Kind::task_refused);
  CHECK(jinny.started.size() == 1);

  // Only commands are taken from the alternatives: retrieval finds some entry in almost anything.
  // (The best sentence is answered as heard, "eyes" read as a question about the senses.)
  SpeechRecognizer::Result question{"what is the me to node eyes", 0.05, {Alternative{"what is the robot at node one", -0.1}}};
  const HriReply from_best = jinny.hri.handle_heard(question);
  CHECK(from_best.entry_id != "node1_robot");
  CHECK(from_best.task.empty());

  // A best sentence that is understood is acted on, whatever the alternatives say.
  SpeechRecognizer::Result clear{"what time is it", 0.4, {Alternative{"guide me to node one", -0.01}}};
  CHECK(jinny.hri.handle_heard(clear).entry_id == "time");
  CHECK(jinny.started.size() == 1);

  // An unsure recognition is not acted on, alternatives or not; a gap of 0 turns them off.
  CHECK(jinny.hri.handle_heard({"explain the robot to node one", 0.0001, {Alternative{"explain the robot at node one", -0.1}}}).kind ==
        HriReply::Kind::not_understood);
  HriOptions off;
  off.max_alternative_log_gap = 0.0;
  Jinny strict(off);
  heard.alternatives = {Alternative{"explain the robot at node one", -0.2}};
  heard.confidence = 0.3;
  CHECK(strict.hri.handle_heard(heard).kind == HriReply::Kind::task_refused);
  CHECK(strict.started.empty());
}

TEST_CASE("a command heard with little confidence is asked about and started only on a yes") {
  Jinny jinny;
  // "thank you jinny" misheard as a command: asked, not started; "no" cancels it.
  HriReply r = jinny.hri.handle_heard({"dance to jinny", 0.008, {}});
  CHECK(r.kind == HriReply::Kind::confirm_task);
  CHECK(r.task == "dance");
  CHECK(r.text == "Did you say \"dance to jinny\"? Please say yes or no.");
  CHECK(jinny.started.empty());
  r = jinny.hri.handle_heard({"no", 0.4, {}});
  CHECK(r.kind == HriReply::Kind::task_cancelled);
  CHECK(r.task == "dance");
  CHECK(r.text == "All right, I will not do that.");
  CHECK(jinny.started.empty());
  // The question is answered once: a second "no" is an input of its own.
  CHECK(jinny.hri.handle("no").kind == HriReply::Kind::not_understood);

  // A yes, spoken or typed, in any of its forms, starts the task asked about.
  for (const char* yes : {"yes", "yes please", "Sure!", "ok", "go ahead", "please", "jinny yes"}) {
    CHECK(jinny.hri.handle_heard({"guide me to node one", 0.01, {}}).kind == HriReply::Kind::confirm_task);
    CHECK(jinny.hri.handle(yes).kind == HriReply::Kind::task_started);
  }
  CHECK(jinny.started.size() == 7);
  for (const char* no : {"no", "No thanks.", "don't", "cancel that", "nope"}) {
    CHECK(jinny.hri.handle_heard({"guide me to node one", 0.01, {}}).kind == HriReply::Kind::confirm_task);
    CHECK(jinny.hri.handle(no).kind == HriReply::Kind::task_cancelled);
  }
  CHECK(jinny.started.size() == 7);

  // Anything else drops the question and is handled as itself; so does a button press.
  CHECK(jinny.hri.handle_heard({"guide me to node one", 0.01, {}}).kind == HriReply::Kind::confirm_task);
  CHECK(jinny.hri.handle("What time is it?").entry_id == "time");
  CHECK(jinny.hri.handle("yes").kind != HriReply::Kind::task_started);
  CHECK(jinny.hri.handle_heard({"guide me to node one", 0.01, {}}).kind == HriReply::Kind::confirm_task);
  CHECK(jinny.hri.handle_button("nothing bound").kind == HriReply::Kind::not_understood);
  CHECK(jinny.hri.handle("yes").kind != HriReply::Kind::task_started);
  CHECK(jinny.hri.handle_heard({"guide me to node one", 0.01, {}}).kind == HriReply::Kind::confirm_task);
  CHECK(jinny.hri.handle(std::string(1, '\0')).kind == HriReply::Kind::refused_input);
  CHECK(jinny.hri.handle("yes").kind != HriReply::Kind::task_started);
  // A "yes" too unsure to act on is not caught; the question stays for the visitor to repeat.
  CHECK(jinny.hri.handle_heard({"guide me to node one", 0.01, {}}).kind == HriReply::Kind::confirm_task);
  CHECK(jinny.hri.handle_heard({"yes", 0.0001, {}}).kind == HriReply::Kind::not_understood);
  CHECK(jinny.hri.handle_heard({"yes", 0.5, {}}).kind == HriReply::Kind::task_started);
  CHECK(jinny.started.size() == 8);

  // Heard surely (confirm_heard_tasks_below, 0.5) and parsed whole, a command starts at once;
  // typed commands never ask. Issue 37: a misheard question heard at 0.06 started the guide.
  CHECK(jinny.hri.handle_heard({"guide me to node one", 0.06, {}}).kind == HriReply::Kind::confirm_task);
  CHECK(jinny.hri.handle_heard({"guide me to node one", 0.6, {}}).kind == HriReply::Kind::task_started);
  CHECK(jinny.hri.handle("guide me to node 1").kind == HriReply::Kind::task_started);
  CHECK(jinny.started.size() == 10);
  // An answer whose entry starts a task is asked about too; a yes gives the answer and starts it.
  r = jinny.hri.handle_heard({"i want to see p s r one", 0.01, {}});
  CHECK(r.kind == HriReply::Kind::confirm_task);
  CHECK(r.entry_id == "show_node0");
  CHECK(r.task == "guide");
  CHECK(jinny.started.size() == 10);
  r = jinny.hri.handle("yes");
  CHECK(r.kind == HriReply::Kind::answered);
  CHECK(r.entry_id == "show_node0");
  CHECK(r.task == "guide");
  CHECK(jinny.started.size() == 11);
  // An answer without an action is given at once, however unsure.
  CHECK(jinny.hri.handle_heard({"what time is it", 0.01, {}}).entry_id == "time");
  // A threshold of 0 never asks.
  HriOptions never;
  never.confirm_heard_tasks_below = 0.0;
  Jinny trusting(never);
  CHECK(trusting.hri.handle_heard({"dance to jinny", 0.008, {}}).kind == HriReply::Kind::task_started);
}

TEST_CASE("a word corrected into a command's verb does not make a question a command") {
  Jinny jinny;
  // "cook" is one letter from "look" (look at me): the question is not a refused command.
  const HriReply r = jinny.hri.handle("Can you cook pasta?");
  CHECK(r.kind == HriReply::Kind::not_understood);
  CHECK(jinny.started.empty());
  // A misspelt verb of a whole command is still understood, and a real verb still refused.
  CHECK(jinny.hri.handle("gide me to node 1").kind == HriReply::Kind::task_started);
  CHECK(jinny.hri.handle("take me to node").kind == HriReply::Kind::task_refused);
}

TEST_CASE("an entry that starts a task answers only when it covers the input as surely as a command (issue 37)") {
  Jinny jinny;
  // "see" and "time" are in the visit to PSR-1 ("I want to see PSR-1"), not enough to start it.
  HriReply r = jinny.hri.handle("See you next time");
  CHECK(r.task.empty());
  CHECK(jinny.started.empty());
  // Said whole, the visit still starts.
  r = jinny.hri.handle("I want to see the cleaning robot");
  CHECK(r.entry_id == "show_node1");
  CHECK(jinny.started.size() == 1);
}

TEST_CASE("LED buttons: a press is the request bound to the button, an unbound button does nothing") {
  HriOptions options;
  options.buttons = {{"hello", "Introduce yourself."}, {"tour", "Guide me to node 1"}};
  Jinny jinny(options);
  CHECK(jinny.hri.buttons() == std::vector<std::string>{"hello", "tour"});
  const HriReply hello = jinny.hri.handle_button("hello");
  CHECK(hello.kind == HriReply::Kind::answered);
  CHECK(hello.entry_id == "introduce");
  const HriReply tour = jinny.hri.handle_button("tour");
  CHECK(tour.kind == HriReply::Kind::task_started);
  CHECK(jinny.started == std::vector<std::string>{"PrAutoMove(goal=node1)"});
  const HriReply other = jinny.hri.handle_button("panic");
  CHECK(other.kind == HriReply::Kind::not_understood);
  CHECK(other.text == "Sorry, that button does nothing here.");
  CHECK(jinny.started.size() == 1);
}

TEST_CASE("the internal state the HRI displays: task, process, fault") {
  Jinny jinny;
  CHECK(jinny.hri.status() == "idle | no process | no fault");
  jinny.hri.set_internal_state({"guide", "running", "PrAutoMove(goal=node1)", ""});
  CHECK(jinny.hri.internal_state().process == "PrAutoMove(goal=node1)");
  CHECK(jinny.hri.status() == "task guide: running | process PrAutoMove(goal=node1) | no fault");
  jinny.hri.set_internal_state({"guide", "failed", "", "path blocked"});
  CHECK(jinny.hri.status() == "task guide: failed | no process | fault: path blocked");
  CHECK(display_text({}) == "idle | no process | no fault");
}

TEST_CASE("the visitor development set (issue 37) is answered right typed") {
  // 441 utterances in two batches written in one sitting each from the base's answers and the task
  // list (issue 37); this part was tuned on. First batch: 98/135 at commit ea75fae, before the
  // lexicon; 108/135 with it. Both batches: 225/265 before the second round (answers, word counts,
  // senses in use), 234/265 after it. Third round (ties, the robot's name, question words, adjectives
  // said of the robot, "to us"; a third batch of 72): 306/337 (the first 265: 242/265).
  REQUIRE(utterance_set("visitors_dev.yaml").size() >= 330);
  CHECK(typed_accuracy("visitors_dev.yaml") >= 0.89);
}

TEST_CASE("the visitor held-out set (issue 37) is answered right typed") {
  // Never tuned on: 143/176 before the second round, 141/176 after it, 143/176 after the third (the
  // first batch alone: 61/90 at commit ea75fae, 67/90 with the lexicon).
  REQUIRE(utterance_set("visitors_heldout.yaml").size() >= 170);
  CHECK(typed_accuracy("visitors_heldout.yaml") >= 0.79);
}

TEST_CASE("no typed utterance of any set starts a task it did not ask for") {
  std::size_t inputs = 0;
  for (const char* file :
       {"utterances.yaml", "utterances_dev.yaml", "utterances_heldout.yaml", "visitors_dev.yaml", "visitors_heldout.yaml"}) {
    for (const auto& e : utterance_set(file)) {
      Jinny jinny;  // fresh: no question left open by the previous input
      const HriReply r = jinny.hri.handle(e.say);
      ++inputs;
      const bool started = r.kind == HriReply::Kind::task_started || (r.kind == HriReply::Kind::answered && !r.task.empty());
      INFO(file << ": \"" << e.say << "\" -> " << to_string(r.kind) << " " << r.task);
      if (started) CHECK(r.task == e.task);
    }
  }
  CHECK(inputs >= 640);
}
