// Issue 37: Jinny understands requests in many phrasings, refuses what does not exist with what
// there is, and never starts a task it was not asked for: a property over a corpus of typed and
// (simulated) spoken inputs, development and held-out parts reported apart; bad input never
// starts anything.
#include <yaml-cpp/yaml.h>

#include <catch2/catch.hpp>
#include <iostream>
#include <map>
#include <string>

#include "tripodal/hri/hri_module.hpp"

using namespace tripodal;

namespace {

using namespace std::chrono_literals;

// The exhibit hall: node 0 and node 1.
class Hall final : public TaskKnowledge {
 public:
  ListResult list(std::string_view function, std::string_view argument) const override {
    if (function != "node") return {false, {}, "no list named '" + std::string(function) + "'"};
    if (argument == "0" || argument == "1") return {true, {"node" + std::string(argument)}, {}};
    return {false, {}, "unknown node '" + std::string(argument) + "' (known: 0, 1)"};
  }
  std::vector<std::string> known(std::string_view function) const override {
    return function == "node" ? std::vector<std::string>{"0", "1"} : std::vector<std::string>{};
  }
};

struct Jinny {
  SimClock clock;
  KnowledgeBase base = KnowledgeBase::load(TRIPODAL_SOURCE_DIR "/configs/hri/jinny.xml");
  TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  Hall hall;
  AnswerProviders providers;
  std::vector<std::string> started;  // the plans the planner double was asked to start
  HriModule hri;

  Jinny()
      : providers(make_providers(clock)),
        hri(base, tasks, hall, providers, [this](const Understanding& u) {
          started.push_back(to_string(u.plan));
          return std::string();
        }) {}

  static AnswerProviders make_providers(const SimClock& clock) {
    AnswerProviders p;
    p.add("time", std::make_unique<ClockTimeProvider>(clock, 14h));
    p.add("battery", std::make_unique<BatteryProvider>([] { return 0.8; }));
    p.add("weather", std::make_unique<FixedProvider>("sunny"));
    return p;
  }
};

struct Case {
  std::string say;
  std::string kind;
  std::string plan;  // empty: no task may start
};

std::vector<Case> corpus(const std::string& file) {
  const YAML::Node doc = YAML::LoadFile(TRIPODAL_TEST_DATA_DIR "/hri/" + file);
  std::vector<Case> out;
  for (const auto& c : doc["corpus"]) {
    out.push_back({c["say"].as<std::string>(), c["kind"].as<std::string>(), c["plan"] ? c["plan"].as<std::string>() : std::string()});
  }
  return out;
}

const std::vector<std::string> kKinds = {"command", "unknown", "question", "chat", "typo"};

struct Tally {
  std::map<std::string, std::pair<int, int>> per_kind;  // right, of
  int wrong_tasks = 0;
  std::string misses;
  void add(const Case& c, bool right, const std::string& what) {
    auto& [r, n] = per_kind[c.kind];
    ++n;
    if (right) {
      ++r;
    } else {
      misses += "  [" + c.kind + "] \"" + c.say + "\": " + what + "\n";
    }
  }
  void print(const std::string& title) const {
    std::cout << title << ": wrong tasks " << wrong_tasks << "\n";
    for (const auto& k : kKinds) {
      const auto it = per_kind.find(k);
      if (it == per_kind.end()) continue;
      std::cout << "  " << k << ": " << it->second.first << "/" << it->second.second << "\n";
    }
    std::cout << misses;
  }
  [[nodiscard]] double accuracy(const std::string& kind) const {
    const auto it = per_kind.find(kind);
    return it == per_kind.end() || it->second.second == 0 ? 0.0 : static_cast<double>(it->second.first) / it->second.second;
  }
};

// What one reply started, as a plan ("" when nothing).
std::string started_by(const Jinny& j, std::size_t before) {
  return j.started.size() > before ? j.started.back() : std::string();
}

Tally typed(const std::vector<Case>& set) {
  Tally t;
  for (const auto& c : set) {
    Jinny j;
    const HriReply r = j.hri.handle(c.say);
    const std::string plan = started_by(j, 0);
    if (j.started.size() > 1 || (!plan.empty() && plan != c.plan)) ++t.wrong_tasks;
    bool right = false;
    if (c.kind == "unknown") {
      // Refused with what there is, in a visitor's words.
      right = r.kind == HriReply::Kind::task_refused && plan.empty() && r.text.find("I can guide you to node 0 or 1.") != std::string::npos &&
              r.text.find("expected") == std::string::npos;
    } else if (!c.plan.empty()) {
      right = plan == c.plan;
    } else if (c.kind == "typo") {
      right = plan.empty();
    } else {
      right = plan.empty() && r.kind != HriReply::Kind::task_refused;
    }
    t.add(c, right, std::string(to_string(r.kind)) + " [" + plan + "] " + r.text);
  }
  return t;
}

// Each utterance heard as itself, surely (0.9) and unsurely (0.2), with a wrong command among the
// recognizer's alternatives; then each heard as a whole command it is not (the misheard
// question, posterior 0.3). A task may start at once only when it is the one asked for; a question
// asked (confirm_task) is answered "yes" only when it names the task asked for.
Tally spoken(const std::vector<Case>& set) {
  using Alternative = SpeechRecognizer::Result::Alternative;
  Tally t;
  for (const auto& c : set) {
    if (c.kind == "typo") continue;  // a spoken request has no typos
    bool right = true;
    std::string what;
    for (const double p : {0.9, 0.2}) {
      Jinny j;
      const SpeechRecognizer::Result heard{spoken_form(c.say), p, {Alternative{"guide me to node one", -0.3}}};
      HriReply r = j.hri.handle_heard(heard);
      std::string plan = started_by(j, 0);
      if (!plan.empty() && plan != c.plan) ++t.wrong_tasks;
      if (r.kind == HriReply::Kind::confirm_task && !c.plan.empty()) {
        r = j.hri.handle_heard({"yes", 0.9, {}});
        plan = started_by(j, 0);
      }
      const bool ok = c.plan.empty() ? plan.empty() : plan == c.plan;
      if (!ok) what += " p=" + std::to_string(p) + ": " + std::string(to_string(r.kind)) + " [" + plan + "] " + r.text;
      right = right && ok;
    }
    if (c.plan.empty()) {
      Jinny j;
      const HriReply r = j.hri.handle_heard({"take me to node one", 0.3, {}});
      if (!j.started.empty()) ++t.wrong_tasks;
      if (r.kind != HriReply::Kind::confirm_task) what += " misheard as a command: " + std::string(to_string(r.kind));
      right = right && r.kind == HriReply::Kind::confirm_task && j.started.empty();
    }
    t.add(c, right, what);
  }
  return t;
}

}  // namespace

TEST_CASE("consent: no input of the command corpus starts a task it did not ask for, typed or heard") {
  const auto dev = corpus("commands_dev.yaml");
  const auto held = corpus("commands_heldout.yaml");
  REQUIRE(dev.size() + held.size() >= 150);
  REQUIRE(held.size() * 4 >= (dev.size() + held.size()));

  const Tally dev_typed = typed(dev);
  const Tally held_typed = typed(held);
  const Tally dev_spoken = spoken(dev);
  const Tally held_spoken = spoken(held);
  dev_typed.print("commands_dev.yaml typed");
  held_typed.print("commands_heldout.yaml typed");
  dev_spoken.print("commands_dev.yaml heard (simulated recognizer)");
  held_spoken.print("commands_heldout.yaml heard (simulated recognizer)");

  // The property: nothing starts that was not asked for.
  CHECK(dev_typed.wrong_tasks == 0);
  CHECK(held_typed.wrong_tasks == 0);
  CHECK(dev_spoken.wrong_tasks == 0);
  CHECK(held_spoken.wrong_tasks == 0);

  // Accuracy per kind, floors a margin below what was measured (docs/hri.md has the figures).
  CHECK(dev_typed.accuracy("command") >= 0.9);
  CHECK(dev_typed.accuracy("unknown") >= 0.9);
  CHECK(dev_typed.accuracy("question") >= 0.85);
  CHECK(dev_typed.accuracy("chat") >= 0.9);
  CHECK(held_typed.accuracy("command") >= 0.85);
  CHECK(held_typed.accuracy("unknown") >= 0.85);
  CHECK(held_typed.accuracy("question") >= 0.8);
  CHECK(held_typed.accuracy("chat") >= 0.85);
  CHECK(dev_spoken.accuracy("command") >= 0.9);
  CHECK(held_spoken.accuracy("command") >= 0.85);
  CHECK(dev_spoken.accuracy("question") >= 0.9);
  CHECK(held_spoken.accuracy("question") >= 0.9);
}

TEST_CASE("consent: a request naming a node that does not exist is refused, never mapped to another, typed or heard") {
  using Alternative = SpeechRecognizer::Result::Alternative;
  Jinny j;
  HriReply r = j.hri.handle("take me to node seven");
  CHECK(r.kind == HriReply::Kind::task_refused);
  CHECK(r.text == "Sorry, there is no node 7 here. I can guide you to node 0 or 1.");
  // Heard, with the node the visitor did not ask for among the alternatives: refused all the same.
  r = j.hri.handle_heard({"guide me to node seven", 0.9, {Alternative{"guide me to node one", -0.05}}});
  CHECK(r.kind == HriReply::Kind::task_refused);
  CHECK(r.text == "Sorry, there is no node 7 here. I can guide you to node 0 or 1.");
  CHECK(j.started.empty());
}

TEST_CASE("consent: heard, only a command parsed whole and heard surely starts at once") {
  using Alternative = SpeechRecognizer::Result::Alternative;
  Jinny j;
  // The case: a question misheard as a command with a posterior above 0.05.
  HriReply r = j.hri.handle_heard({"guide me to node one", 0.2, {}});
  CHECK(r.kind == HriReply::Kind::confirm_task);
  CHECK(j.hri.handle_heard({"no", 0.9, {}}).kind == HriReply::Kind::task_cancelled);
  // Whole and sure, with fillers and politeness: at once.
  r = j.hri.handle_heard({"um jinny could you take us to node zero please", 0.8, {}});
  CHECK(r.kind == HriReply::Kind::task_started);
  CHECK(to_string(r.plan) == "PrAutoMove(goal=node0)");
  // A tail naming the listeners ("to us", "for me") is politeness, not part of the command.
  r = j.hri.handle_heard({"explain the robot at node one to us", 0.8, {}});
  CHECK(r.kind == HriReply::Kind::task_started);
  CHECK(r.task == "explain");
  // Sure, but only typo correction or an alternative made it a command: asked first.
  r = j.hri.handle_heard({"gide me to node one", 0.9, {}});
  CHECK(r.kind == HriReply::Kind::confirm_task);
  r = j.hri.handle_heard({"guide me two node one", 0.9, {Alternative{"guide me to node one", -0.2}}});
  CHECK(r.kind == HriReply::Kind::confirm_task);
  // An answer whose entry starts a task, heard surely: asked first (not the grammar's command).
  r = j.hri.handle_heard({"show me the cleaning robot", 0.9, {}});
  CHECK(r.kind == HriReply::Kind::confirm_task);
  CHECK(r.entry_id == "show_node1");
  CHECK(j.started.size() == 2);
  CHECK(j.started.front() == "PrAutoMove(goal=node0)");
}

TEST_CASE("consent: bad input is answered politely or ignored, never a crash, never a task") {
  Jinny j;
  std::string megabyte;
  while (megabyte.size() < (1U << 20)) megabyte += "guide me to node 1 ";
  const std::string controls = std::string("guide me\x01\x02 to node 1\x1b[2J") + '\0' + "\x7f";
  const std::vector<std::string> inputs = {
      megabyte, controls, "", "   \t\n  ", "\n\n", "Bitte führe mich zu Knoten eins.", "Wie spät ist es?",
      "¿Puedes llevarme al nodo uno, por favor?", "Llévame al nodo 1", "ノード1に連れて行って", "!!!???", "1 1 1 1",
  };
  for (const auto& in : inputs) {
    INFO("input of " << in.size() << " bytes");
    const HriReply typed = j.hri.handle(in);
    CHECK(typed.task.empty());
    CHECK_FALSE(typed.text.empty());
    if (in.size() < 1000) {
      const HriReply heard = j.hri.handle_heard({in, 0.9, {}});
      CHECK(heard.task.empty());
    }
  }
  CHECK(j.started.empty());
}
