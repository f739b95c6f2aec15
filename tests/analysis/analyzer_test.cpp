// The whole analysis and its report: deadlocks with paths and events, bounds and safeness,
// unboundedness, dead transitions, never-marked places, the outcome check, parameters, and the
// text and JSON forms.
#include <catch2/catch.hpp>

#include <cctype>
#include <cmath>
#include <limits>

#include "analysis_test_nets.hpp"
#include "tripodal/analysis/analyzer.hpp"
#include "tripodal/core/diagnostic.hpp"

using namespace tripodal;
using namespace tripodal::analysis;

namespace {

// A small PrAutoMove-like process: start, move, then arrive (success) or get lost; once lost,
// a recovery event may bring it back, or a fault is declared.
PetriNet process_net() {
  PetriNet net;
  net.id = "PrMove";
  net.add_place(Place{.id = "idle", .initial_tokens = 1});
  net.add_place(Place{.id = "moving"});
  net.add_place(Place{.id = "lost"});
  net.add_place(Place{.id = "arrived", .outcome = Outcome::success});
  net.add_place(Place{.id = "failed", .outcome = Outcome::fault, .fault_message = "localization fault"});
  net.add_transition(Transition{.id = "start"});
  net.add_transition(Transition{.id = "arrive", .event = "BhMove.done"});
  net.add_transition(Transition{.id = "lose", .event = "localizer.lost"});
  net.add_transition(Transition{.id = "recover", .event = "localizer.ok"});
  net.add_transition(Transition{.id = "give_up", .delay = from_seconds(5.0)});
  net.add_arc("idle", "start");
  net.add_arc("start", "moving");
  net.add_arc("moving", "arrive");
  net.add_arc("arrive", "arrived");
  net.add_arc("moving", "lose");
  net.add_arc("lose", "lost");
  net.add_arc("lost", "recover");
  net.add_arc("recover", "moving");
  net.add_arc("lost", "give_up");
  net.add_arc("give_up", "failed");
  return net;
}

// A minimal JSON syntax checker: enough to prove the report is one well-formed value.
class JsonChecker {
 public:
  explicit JsonChecker(std::string_view s) : s_(s) {}
  bool ok() {
    value();
    space();
    return good_ && i_ == s_.size();
  }

 private:
  void space() {
    while (i_ < s_.size() && std::isspace(static_cast<unsigned char>(s_[i_])) != 0) ++i_;
  }
  bool eat(char c) {
    space();
    if (i_ < s_.size() && s_[i_] == c) {
      ++i_;
      return true;
    }
    return false;
  }
  void fail() { good_ = false; i_ = s_.size(); }
  void string() {
    if (!eat('"')) return fail();
    while (i_ < s_.size() && s_[i_] != '"') {
      const auto c = static_cast<unsigned char>(s_[i_]);
      if (c < 0x20) return fail();
      if (c == '\\') {
        ++i_;
        if (i_ >= s_.size()) return fail();
        if (s_[i_] == 'u') {
          for (int k = 0; k < 4; ++k) {
            if (++i_ >= s_.size() || std::isxdigit(static_cast<unsigned char>(s_[i_])) == 0) return fail();
          }
        } else if (std::string_view("\"\\/bfnrt").find(s_[i_]) == std::string_view::npos) {
          return fail();
        }
      }
      ++i_;
    }
    if (!eat('"')) fail();
  }
  void value() {
    space();
    if (i_ >= s_.size()) return fail();
    const char c = s_[i_];
    if (c == '{') {
      ++i_;
      if (eat('}')) return;
      do {
        space();
        string();
        if (!eat(':')) return fail();
        value();
      } while (good_ && eat(','));
      if (!eat('}')) fail();
    } else if (c == '[') {
      ++i_;
      if (eat(']')) return;
      do value();
      while (good_ && eat(','));
      if (!eat(']')) fail();
    } else if (c == '"') {
      string();
    } else {
      const std::size_t start = i_;
      while (i_ < s_.size() && (std::isalnum(static_cast<unsigned char>(s_[i_])) != 0 || s_[i_] == '-' ||
                                s_[i_] == '+' || s_[i_] == '.')) {
        ++i_;
      }
      const std::string_view word = s_.substr(start, i_ - start);
      if (word.empty()) return fail();
      if (word != "true" && word != "false" && word != "null" &&
          (std::isdigit(static_cast<unsigned char>(word[0])) == 0 && word[0] != '-')) {
        fail();
      }
    }
  }
  std::string_view s_;
  std::size_t i_ = 0;
  bool good_ = true;
};

}  // namespace

TEST_CASE("Kanban2 report: 4,600 states, 28,120 edges, no deadlock, 2-bounded", "[analysis][report]") {
  const PetriNet net = test::kanban_net(2);
  const AnalysisReport r = analyze(net, {.semantics = Semantics::interleaving});
  CHECK(r.states == 4600);
  CHECK(r.edges == 28120);
  CHECK(r.deadlock_count == 0);
  CHECK(r.bounded == Verdict::pass);
  CHECK(r.safe == Verdict::fail);
  CHECK_FALSE(r.coverability_ran);  // the invariants bound every place
  CHECK(r.bytes_per_marking == 4);
  CHECK(r.dead_transitions.empty());
  CHECK(r.never_marked.empty());
  CHECK(r.outcome == Verdict::not_applicable);
  CHECK(r.p_invariants.invariants.size() == 6);
  CHECK(r.ok());
  const std::string text = format_text(r, net);
  CHECK_THAT(text, Catch::Contains("4600 states, 28120 edges (complete"));
  CHECK_THAT(text, Catch::Contains("P1 + Pm1 + Pout1 + Pback1 = 2") || Catch::Contains("P1 + Pm1 + Pback1 + Pout1 = 2"));
  CHECK_THAT(text, Catch::Contains("verdict: OK"));
}

TEST_CASE("Engine semantics explore a process net: outcome reachable from everywhere", "[analysis][report]") {
  const PetriNet net = process_net();
  const AnalysisReport r = analyze(net);
  CHECK(r.complete());
  CHECK(r.states == 5);  // idle, moving, lost, arrived, failed
  CHECK(r.deadlock_count == 0);
  CHECK(r.outcome == Verdict::pass);
  CHECK(r.outcome_states == 2);
  CHECK(r.safe == Verdict::pass);
  CHECK(r.ok());
}

TEST_CASE("A lost robot that can neither recover nor give up fails the outcome check, with a path", "[analysis][report]") {
  PetriNet net = process_net();
  net.transition(*net.find_transition("give_up")).guard = Guard::parse("mode == 'persistent'");
  net.parameters.push_back(VariableDecl{.name = "mode", .type = ValueType::string,
                                        .default_value = Value{std::string("careful")}});
  // Without give_up, "lost" still waits for localizer.ok: not a deadlock, and an outcome is reachable.
  CHECK(analyze(net).outcome == Verdict::pass);
  // Remove the recovery: lost is now a deadlock that cannot reach an outcome.
  net.transition(*net.find_transition("recover")).guard = Guard::parse("mode == 'never'");
  const AnalysisReport r = analyze(net);
  REQUIRE(r.deadlock_count == 1);
  const Witness& d = r.deadlocks[0];
  CHECK(d.marking[*net.find_place("lost")] == 1);
  REQUIRE(d.path.size() == 2);
  CHECK(net.transition(d.path[0]).id == "start");
  CHECK(net.transition(d.path[1]).id == "lose");
  CHECK(r.outcome == Verdict::fail);
  CHECK(r.stuck_count == 1);
  CHECK(r.dead_transitions.size() == 2);
  CHECK(r.never_marked == std::vector<PlaceIndex>{*net.find_place("failed")});
  CHECK_FALSE(r.ok());
  const std::string text = format_text(r, net);
  CHECK_THAT(text, Catch::Contains("deadlocks: 1"));
  CHECK_THAT(text, Catch::Contains("path (2 firings): start -> lose [localizer.lost]"));
  CHECK_THAT(text, Catch::Contains("events needed: localizer.lost"));
  CHECK_THAT(text, Catch::Contains("outcome check: FAIL: 1 reachable markings"));
  CHECK_THAT(text, Catch::Contains("dead transitions: recover, give_up"));
  // With the parameter that enables give_up, the fault outcome is reachable again.
  AnalysisOptions o;
  o.parameters = parse_parameter_assignments(net, {"mode=persistent"});
  const AnalysisReport fixed = analyze(net, o);
  CHECK(fixed.deadlock_count == 0);
  CHECK(fixed.outcome == Verdict::pass);
}

TEST_CASE("A cycle away from the outcomes is not a deadlock but fails the outcome check", "[analysis][report]") {
  PetriNet net = process_net();
  net.transition(*net.find_transition("give_up")).guard = Guard::parse("false");
  net.transition(*net.find_transition("recover")).guard = Guard::parse("false");
  net.add_place(Place{.id = "searching"});
  net.add_transition(Transition{.id = "search", .event = "BhSearch.start"});
  net.add_transition(Transition{.id = "search_failed", .event = "BhSearch.failed"});
  net.add_arc("lost", "search");
  net.add_arc("search", "searching");
  net.add_arc("searching", "search_failed");
  net.add_arc("search_failed", "lost");
  const AnalysisReport r = analyze(net);
  CHECK(r.deadlock_count == 0);
  CHECK(r.outcome == Verdict::fail);
  CHECK(r.stuck_count == 2);
  REQUIRE(r.stuck.size() == 2);
  CHECK(r.stuck[0].path.size() == 2);  // start -> lose
  CHECK(r.stuck[1].path.size() == 3);  // ... -> search
}

TEST_CASE("An unbounded net: Karp-Miller proves it, the exploration stops at the limit", "[analysis][report][limits]") {
  PetriNet net;
  net.id = "leak";
  net.add_place(Place{.id = "ready", .initial_tokens = 1});
  net.add_place(Place{.id = "requests"});
  net.add_transition(Transition{.id = "request"});
  net.add_arc("ready", "request");
  net.add_arc("request", "ready");
  net.add_arc("request", "requests");
  const AnalysisReport r = analyze(net, {.semantics = Semantics::interleaving, .max_states = 10'000});
  CHECK(r.stop == StopReason::max_states);
  CHECK(r.states == 10'000);
  CHECK(r.bounded == Verdict::fail);
  CHECK(r.safe == Verdict::fail);
  CHECK(r.bounds[1].kind == BoundKind::unbounded);
  CHECK(r.bounds[0].kind == BoundKind::at_least);
  CHECK_FALSE(r.ok());
  const std::string text = format_text(r, net);
  CHECK_THAT(text, Catch::Contains("INCOMPLETE: stopped by max_states"));
  CHECK_THAT(text, Catch::Contains("UNBOUNDED"));
  CHECK_THAT(text, Catch::Contains("requests: unbounded"));
  CHECK_THAT(text, Catch::Contains("repeating request after (initial marking) grows requests"));
  // Under engine semantics Karp-Miller only suspects it (it runs on the interleaving
  // over-approximation); the pumping cycle found on the explored path, replayed under the engine's
  // rules (request is urgent and fires again and again), confirms it.
  const AnalysisReport e = analyze(net, {.max_states = 1'000});
  CHECK(e.bounds[1].may_be_unbounded);
  REQUIRE(e.growth.has_value());
  CHECK(e.growth->confirmed());
  CHECK(e.growth->place == 1);
  CHECK(e.bounded == Verdict::fail);
  CHECK_THAT(format_text(e, net), Catch::Contains("grows without end: requests: after (initial marking), repeating request"));
  // Capped by an inhibitor arc (request only while fewer than 3 requests), the place is bounded:
  // the exploration completes and no growth is reported.
  net.add_arc("requests", "request", 3, ArcKind::inhibitor);
  const AnalysisReport capped = analyze(net, {.max_states = 1'000});
  CHECK(capped.complete());
  CHECK_FALSE(capped.growth.has_value());
  CHECK(capped.bounded == Verdict::pass);
}

TEST_CASE("Parameters: typed from the declarations, bad ones reported together", "[analysis][report]") {
  PetriNet net = process_net();
  net.parameters.push_back(VariableDecl{.name = "speed", .type = ValueType::number});
  net.parameters.push_back(VariableDecl{.name = "wheel_type", .type = ValueType::string});
  const ParameterValues v = parse_parameter_assignments(net, {"speed=0.5", "wheel_type=omni"});
  CHECK(v.at("speed") == Value{0.5});
  CHECK(v.at("wheel_type") == Value{std::string("omni")});
  REQUIRE_THROWS_WITH(parse_parameter_assignments(net, {"speed=fast", "colour=red", "oops"}),
                      Catch::Contains("--param 'speed=fast': expected a number for parameter 'speed'") &&
                          Catch::Contains("unknown parameter 'colour' (declared: speed, wheel_type)") &&
                          Catch::Contains("--param 'oops': expected NAME=VALUE"));
  REQUIRE_THROWS_WITH(analyze(net, {.parameters = {{"speed", Value{1.0}}}}),
                      Catch::Contains("missing required parameter 'wheel_type' (string)"));
}

TEST_CASE("The JSON report is well-formed and escapes names", "[analysis][report][json]") {
  PetriNet net = process_net();
  net.id = "say \"hi\"\n\tback\\slash \x01";
  net.transition(*net.find_transition("recover")).guard = Guard::parse("false");
  net.transition(*net.find_transition("give_up")).guard = Guard::parse("false");
  const AnalysisReport r = analyze(net);
  const std::string json = format_json(r, net);
  CHECK(JsonChecker(json).ok());
  CHECK_THAT(json, Catch::Contains(R"("id":"say \"hi\"\n\tback\\slash \u0001")"));
  CHECK_THAT(json, Catch::Contains(R"("deadlocks":{"count":1,"examples":[{"marking":{"lost":1},"path":[{"transition":"start","event":null},{"transition":"lose","event":"localizer.lost"}],"events":["localizer.lost"])"));
  CHECK_THAT(json, Catch::Contains(R"("outcome":{"verdict":"fail")"));
  CHECK_THAT(json, Catch::Contains(R"("ok":false)"));
  const std::string kanban = format_json(analyze(test::kanban_net(1), {.semantics = Semantics::interleaving}), test::kanban_net(1));
  CHECK(JsonChecker(kanban).ok());
  CHECK_THAT(kanban, Catch::Contains(R"("states":160)"));
  CHECK_FALSE(JsonChecker(R"({"a":1,})").ok());  // the checker itself rejects bad JSON
  CHECK_FALSE(JsonChecker("{\"a\":\"\x01\"}").ok());
}

TEST_CASE("The JSON report writes a number that is not finite as null", "[analysis][report][json]") {
  const PetriNet net = process_net();
  AnalysisReport r = analyze(net);
  r.exploration_s = std::nan("");
  r.bytes_per_state = std::numeric_limits<double>::infinity();
  const std::string json = format_json(r, net);
  CHECK(JsonChecker(json).ok());
  CHECK_THAT(json, Catch::Contains(R"("exploration_s":null,"states_per_s":0.0)") &&
                       Catch::Contains(R"("bytes_per_state":null)"));
  CHECK_THAT(json, !Catch::Contains("nan") && !Catch::Contains("inf"));
}
