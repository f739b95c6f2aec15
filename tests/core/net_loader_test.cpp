// The native XML loader: a complete net loads with every field; every kind of error is reported
// with FILE:LINE:COL, all of a file's errors at once; structural warnings.
#include <catch2/catch.hpp>

#include <filesystem>
#include <fstream>

#include "tripodal/core/engine.hpp"
#include "tripodal/core/net_loader.hpp"

using namespace tripodal;

namespace {

const char* const kGood = R"xml(<?xml version="1.0" encoding="UTF-8"?>
<net id="demo" name="Demo" level="low" version="1" description="a demo net">
  <parameter name="wheel_type" type="string" default="omni" description="base"/>
  <parameter name="speed_mps" type="number" default="0.5"/>
  <fact name="battery_low" type="boolean" default="false"/>
  <place id="idle" tokens="1" capacity="1" description="Idle (Standby)"/>
  <place id="work" name="W" description="Execute behavior BhCleaning">
    <behavior name="BhCleaning">
      <param name="speed" value="$speed_mps"/>
      <param name="mode" value="spiral"/>
    </behavior>
  </place>
  <place id="sub"><process name="PrAutoMove"><param name="goal" value="dock"/></process></place>
  <place id="done" outcome="success"/>
  <place id="failed" outcome="fault" message="localization fault"/>
  <transition id="start" guard="wheel_type == 'omni' &amp;&amp; !battery_low" priority="2"/>
  <transition id="finish" event="BhCleaning.done" description="completed"/>
  <transition id="timeout" delay="2500ms"/>
  <transition id="go" event="go"/>
  <arc source="idle" target="start"/>
  <arc source="start" target="work" weight="2"/>
  <arc source="work" target="finish" weight="2"/>
  <arc source="idle" target="finish" kind="inhibitor"/>
  <arc source="work" target="timeout" kind="read"/>
  <arc source="timeout" target="failed"/>
  <arc source="finish" target="done"/>
  <arc source="done" target="go"/>
  <arc source="go" target="sub"/>
</net>
)xml";

std::string errors_of(const std::string& text, const LoadOptions& options = {}) {
  Diagnostics d;
  const auto net = load_net_from_string(text, "bad.xml", d, options);
  CHECK_FALSE(net.has_value());
  CHECK(d.has_errors());
  return d.str();
}

// A minimal valid net with `extra` inserted before </net>.
std::string with(const std::string& extra) {
  return "<net id=\"n\">\n"
         "  <parameter name=\"wheel_type\" type=\"string\"/>\n"
         "  <place id=\"p\" tokens=\"1\"/>\n"
         "  <place id=\"q\"/>\n"
         "  <transition id=\"t\"/>\n"
         "  <arc source=\"p\" target=\"t\"/>\n"
         "  <arc source=\"t\" target=\"q\"/>\n" +
         extra + "</net>\n";
}

}  // namespace

TEST_CASE("native loader: a complete net loads with every field") {
  Diagnostics d;
  const auto net = load_net_from_string(kGood, "good.xml", d);
  INFO(d.str());
  REQUIRE(net.has_value());
  CHECK_FALSE(d.has_errors());
  CHECK(net->id == "demo");
  CHECK(net->name == "Demo");
  CHECK(net->description == "a demo net");
  CHECK(net->level == NetLevel::low);
  REQUIRE(net->parameters.size() == 2);
  CHECK(net->parameters[0].type == ValueType::string);
  CHECK(std::get<std::string>(*net->parameters[0].default_value) == "omni");
  CHECK(std::get<double>(*net->parameters[1].default_value) == 0.5);
  REQUIRE(net->facts.size() == 1);
  CHECK(std::get<bool>(*net->facts[0].default_value) == false);
  REQUIRE(net->places().size() == 5);
  const Place& idle = net->place(*net->find_place("idle"));
  CHECK(idle.initial_tokens == 1);
  CHECK(idle.capacity == Tokens{1});
  CHECK(idle.description == "Idle (Standby)");
  CHECK(idle.where.str() == "good.xml:6:3");
  const Place& work = net->place(*net->find_place("work"));
  CHECK(work.name == "W");
  REQUIRE(work.behavior.has_value());
  CHECK(work.behavior->behavior == "BhCleaning");
  REQUIRE(work.behavior->params.size() == 2);
  CHECK(work.behavior->params[0].name == "speed");
  CHECK(work.behavior->params[0].value == "$speed_mps");
  const Place& sub = net->place(*net->find_place("sub"));
  REQUIRE(sub.process.has_value());
  CHECK(sub.process->process == "PrAutoMove");
  CHECK(net->place(*net->find_place("done")).outcome == Outcome::success);
  const Place& failed = net->place(*net->find_place("failed"));
  CHECK(failed.outcome == Outcome::fault);
  CHECK(failed.fault_message == "localization fault");

  const Transition& start = net->transition(*net->find_transition("start"));
  REQUIRE(start.guard.has_value());
  CHECK(start.guard->text() == "wheel_type == 'omni' && !battery_low");
  CHECK(start.priority == 2);
  REQUIRE(start.outputs.size() == 1);
  CHECK(start.outputs[0].weight == 2);
  const Transition& finish = net->transition(*net->find_transition("finish"));
  CHECK(finish.event == "BhCleaning.done");
  REQUIRE(finish.inhibitors.size() == 1);
  CHECK(net->place(finish.inhibitors[0].place).id == "idle");
  CHECK(finish.inputs.at(0).weight == 2);
  const Transition& timeout = net->transition(*net->find_transition("timeout"));
  CHECK(timeout.delay == std::chrono::milliseconds(2500));
  REQUIRE(timeout.reads.size() == 1);
  CHECK(timeout.reads[0].where.str() == "good.xml:24:3");

  // It runs: start fires (guard true), work gets 2 tokens.
  Engine engine(*net);
  engine.step(Time{});
  CHECK(engine.tokens(*net->find_place("work")) == 2);
}

TEST_CASE("native loader: delays take units") {
  for (const auto& [text, ns] : std::vector<std::pair<std::string, std::int64_t>>{
           {"2s", 2'000'000'000}, {"500ms", 500'000'000}, {"1.5min", 90'000'000'000}, {"250us", 250'000},
           {"7ns", 7}, {"0s", 0}, {"1h", 3'600'000'000'000}}) {
    Diagnostics d;
    const auto net = load_net_from_string(with("  <transition id=\"u\" delay=\"" + text + "\"/>\n"), "d.xml", d);
    INFO(text << "\n" << d.str());
    REQUIRE(net.has_value());
    CHECK(net->transition(*net->find_transition("u")).delay.count() == ns);
  }
}

TEST_CASE("native loader: malformed XML is located") {
  const auto e = errors_of("<net id=\"n\">\n  <place id=\"p\">\n</net>\n");
  CHECK_THAT(e, Catch::Contains("bad.xml:3:1: error: malformed XML: end tag </net> does not match the open element "
                                "<place> (line 2, column 3)"));
  CHECK_THAT(errors_of(""), Catch::Contains("bad.xml:1:1: error: malformed XML: empty document"));
  CHECK_THAT(errors_of("<net id=\"n\">\n  <place id=\"p tokens=\"1\"/>\n</net>"), Catch::Contains("bad.xml:2:"));
}

TEST_CASE("native loader: every error of a file is reported, each with line and column") {
  const std::string text =
      "<net id=\"n\" colour=\"red\">\n"                                    // 1: unknown attribute
      "  <parameter name=\"wheel_type\" type=\"string\"/>\n"              // 2
      "  <place id=\"p\" tokens=\"-1\"/>\n"                                // 3: bad token count
      "  <place id=\"p\"/>\n"                                              // 4: duplicate id
      "  <place tokens=\"1\"/>\n"                                          // 5: missing id
      "  <plac id=\"x\"/>\n"                                               // 6: unknown element
      "  <transition id=\"t\" guard=\"wheel_type == 'omni' &amp;&amp; \" delay=\"5\"/>\n"  // 7: guard, delay
      "  <transition id=\"u\" guard=\"wheel_typ == 'omni'\" delay=\"-2s\"/>\n"  // 8: unknown param, negative
      "  <arc source=\"p\" target=\"zz\"/>\n"                              // 9: unknown node
      "  <arc source=\"p\" target=\"p\"/>\n"                               // 10: two places
      "  <arc source=\"t\" target=\"u\"/>\n"                               // 11: two transitions
      "  <arc source=\"p\" target=\"t\" weight=\"0\"/>\n"                  // 12: non-positive weight
      "  <arc source=\"t\" target=\"p\" kind=\"read\"/>\n"                 // 13: read arc from transition
      "</net>\n";
  const auto e = errors_of(text);
  CHECK_THAT(e, Catch::Contains("bad.xml:1:13: error: unknown attribute 'colour' on <net>; expected one of: id"));
  CHECK_THAT(e, Catch::Contains("bad.xml:3:25: error: bad token count '-1': expected a whole number >= 0"));
  CHECK_THAT(e, Catch::Contains("bad.xml:4:14: error: duplicate id 'p' (first defined at bad.xml:3:3)"));
  CHECK_THAT(e, Catch::Contains("bad.xml:5:3: error: missing attribute 'id' on <place>"));
  CHECK_THAT(e, Catch::Contains("bad.xml:6:3: error: unknown element <plac> in <net>; expected one of: parameter"));
  // The guard ends early: the fault is its end, the closing quote (each entity is one guard column).
  CHECK_THAT(e, Catch::Contains("bad.xml:7:61: error: guard of transition 't' does not parse"));
  CHECK_THAT(e, Catch::Contains("bad.xml:7:70: error: delay '5' has no unit: write e.g. '5s' or '5ms'"));
  CHECK_THAT(e, Catch::Contains("bad.xml:8:29: error: unknown parameter 'wheel_typ' in guard of transition 'u'"));
  CHECK_THAT(e, Catch::Contains("declared parameters: wheel_type"));
  CHECK_THAT(e, Catch::Contains("bad.xml:8:57: error: negative delay '-2s'"));
  CHECK_THAT(e, Catch::Contains("bad.xml:9:27: error: arc to unknown node 'zz'"));
  CHECK_THAT(e, Catch::Contains("bad.xml:10:3: error: arc between two places 'p' and 'p'"));
  CHECK_THAT(e, Catch::Contains("bad.xml:11:3: error: arc between two transitions 't' and 'u'"));
  CHECK_THAT(e, Catch::Contains("bad.xml:12:38: error: non-positive weight '0': expected a whole number >= 1"));
  CHECK_THAT(e, Catch::Contains("bad.xml:13:3: error: a read arc goes from a place to a transition"));
  Diagnostics d;
  load_net_from_string(text, "bad.xml", d);
  CHECK(d.error_count() == 14);
}

TEST_CASE("native loader: a duplicate node keeps the first definition, and its own errors are still reported") {
  const std::string text =
      "<net id=\"n\">\n"
      "  <place id=\"p\" name=\"\" tokens=\"2\" description=\"first\"/>\n"     // 2: empty name: the id
      "  <place id=\"p\" tokens=\"x\" description=\"second\"/>\n"             // 3: duplicate, bad tokens
      "  <transition id=\"p\" delay=\"5\"/>\n"                                // 4: id of a place, bad delay
      "  <transition id=\"t\" name=\"go\"/>\n"                                // 5
      "  <arc source=\"p\" target=\"t\"/>\n"
      "</net>\n";
  const auto e = errors_of(text);
  CHECK_THAT(e, Catch::Contains("bad.xml:3:14: error: duplicate id 'p' (first defined at bad.xml:2:3)"));
  CHECK_THAT(e, Catch::Contains("bad.xml:3:25: error: bad token count 'x'"));
  CHECK_THAT(e, Catch::Contains("bad.xml:4:19: error: duplicate id 'p' (first defined at bad.xml:2:3)"));
  CHECK_THAT(e, Catch::Contains("bad.xml:4:29: error: delay '5' has no unit"));
  // The duplicate's message comes before the errors in the rest of its element.
  CHECK(e.find("bad.xml:3:14") < e.find("bad.xml:3:25"));

  // Without the bad lines the net loads: the first definition is the one kept.
  Diagnostics d;
  const auto net = load_net_from_string(
      "<net id=\"n\">\n  <place id=\"p\" name=\"\" tokens=\"2\" description=\"first\"/>\n"
      "  <transition id=\"t\" name=\"go\"/>\n  <arc source=\"p\" target=\"t\"/>\n</net>\n",
      "good.xml", d);
  REQUIRE(net);
  CHECK(d.empty());
  REQUIRE(net->places().size() == 1);
  CHECK(net->place(0).name == "p");
  CHECK(net->place(0).description == "first");
  CHECK(net->place(0).initial_tokens == 2);
  CHECK(net->place(0).where.str() == "good.xml:2:3");
  CHECK(net->transition(0).name == "go");
  CHECK(net->transition(0).inputs.at(0).where.str() == "good.xml:4:3");
}

TEST_CASE("native loader: guard errors point into the guard") {
  // "wheel_type == == 1": the second '==' is at guard column 15; the value starts at column 29.
  const auto e = errors_of(with("  <transition id=\"g\" guard=\"wheel_type == == 1\"/>\n"));
  CHECK_THAT(e, Catch::Contains("bad.xml:8:43: error: guard of transition 'g' does not parse"));
  const auto typed = errors_of(with("  <transition id=\"g\" guard=\"wheel_type > 2\"/>\n"));
  CHECK_THAT(typed, Catch::Contains("bad.xml:8:29: error: guard of transition 'g' uses 'wheel_type' as a number, "
                                    "but it is declared string"));
}

TEST_CASE("native loader: declarations, bindings, outcomes and attributes are checked") {
  CHECK_THAT(errors_of(with("  <parameter name=\"x\" type=\"integer\"/>\n")),
             Catch::Contains("bad.xml:8:29: error: unknown type 'integer': expected boolean, number or string"));
  CHECK_THAT(errors_of(with("  <parameter name=\"x\" type=\"number\" default=\"fast\"/>\n")),
             Catch::Contains("bad.xml:8:46: error: default 'fast' of 'x' is not a number"));
  CHECK_THAT(errors_of(with("  <fact name=\"wheel_type\" type=\"string\"/>\n")),
             Catch::Contains("bad.xml:8:15: error: duplicate declaration of 'wheel_type'"));
  CHECK_THAT(errors_of(with("  <place id=\"b\"><behavior name=\"BhX\"><param name=\"v\" value=\"$nope\"/></behavior></place>\n")),
             Catch::Contains("bad.xml:8:61: error: unknown parameter '$nope' passed to behavior BhX"));
  CHECK_THAT(errors_of(with("  <place id=\"b\"><behavior name=\"A\"/><process name=\"B\"/></place>\n")),
             Catch::Contains("bad.xml:8:37: error: place 'b' already binds a behavior"));
  CHECK_THAT(errors_of(with("  <place id=\"b\" message=\"m\"/>\n")),
             Catch::Contains("bad.xml:8:17: error: a message belongs to a fault place"));
  CHECK_THAT(errors_of(with("  <place id=\"b\" outcome=\"great\"/>\n")),
             Catch::Contains("bad.xml:8:26: error: unknown outcome 'great': expected success or fault"));
  CHECK_THAT(errors_of(with("  <place id=\"b\" tokens=\"3\" capacity=\"2\"/>\n")),
             Catch::Contains("bad.xml:8:38: error: place 'b' starts with 3 tokens, more than its capacity 2"));
  CHECK_THAT(errors_of(with("  <transition id=\"e\" event=\"9lives\"/>\n")),
             Catch::Contains("bad.xml:8:29: error: bad event name '9lives'"));
  CHECK_THAT(errors_of(with("  <transition id=\"e\" priority=\"high\"/>\n")),
             Catch::Contains("bad.xml:8:32: error: bad priority 'high': expected an integer"));
  CHECK_THAT(errors_of(with("  <transition id=\"e\" delay=\"3 parsecs\"/>\n")),
             Catch::Contains("error: unknown unit 'parsecs' in delay '3 parsecs'"));
  CHECK_THAT(errors_of(with("  <arc source=\"p\" target=\"t\" kind=\"reset\"/>\n")),
             Catch::Contains("bad.xml:8:36: error: unknown arc kind 'reset': expected normal, read or inhibitor"));
  CHECK_THAT(errors_of("<petrinet/>"), Catch::Contains("bad.xml:1:1: error: unexpected root element <petrinet>: expected <net>"));
  CHECK_THAT(errors_of("<net id=\"n\" version=\"2\"/>"),
             Catch::Contains("bad.xml:1:22: error: format version '2' is not supported"));
  CHECK_THAT(errors_of("<net id=\"n\" level=\"middle\"/>"), Catch::Contains("unknown level 'middle'"));
  CHECK_THAT(errors_of("<net id=\"n\">text</net>"), Catch::Contains("bad.xml:1:1: error: unexpected text in <net>"));
}

TEST_CASE("native loader: unknown behaviors and processes when predicates are given") {
  LoadOptions options;
  options.is_known_behavior = [](std::string_view n) { return n == "BhCleaning"; };
  options.is_known_process = [](std::string_view n) { return n == "PrAutoMove"; };
  const auto e = errors_of(with("  <place id=\"a\"><behavior name=\"BhClening\"/></place>\n"
                                "  <place id=\"b\"><process name=\"PrAutoMuve\"/></place>\n"
                                "  <place id=\"c\"><behavior name=\"BhCleaning\"/></place>\n"),
                           options);
  CHECK_THAT(e, Catch::Contains("bad.xml:8:33: error: unknown behavior 'BhClening'"));
  CHECK_THAT(e, Catch::Contains("bad.xml:9:32: error: unknown process 'PrAutoMuve'"));
  CHECK_THAT(e, !Catch::Contains("'BhCleaning'"));
  Diagnostics d;
  CHECK(load_net_from_string(with("  <place id=\"a\"><behavior name=\"BhClening\"/></place>\n"), "ok.xml", d));
}

TEST_CASE("native loader: structural warnings do not fail the load") {
  Diagnostics d;
  const auto net = load_net_from_string(with("  <place id=\"orphan\"/>\n"
                                             "  <transition id=\"never\"/>\n"
                                             "  <arc source=\"orphan\" target=\"never\"/>\n"
                                             "  <arc source=\"never\" target=\"q\"/>\n"),
                                        "w.xml", d);
  REQUIRE(net.has_value());
  CHECK_FALSE(d.has_errors());
  CHECK_THAT(d.str(), Catch::Contains("w.xml:8:3: warning: place 'orphan' can never be marked"));
  CHECK_THAT(d.str(), Catch::Contains("w.xml:9:3: warning: transition 'never' can never be enabled: place(s) orphan"));
  Diagnostics quiet;
  LoadOptions no_warnings;
  no_warnings.structural_warnings = false;
  CHECK(load_net_from_string(with("  <place id=\"orphan\"/>\n"), "w.xml", quiet, no_warnings));
  CHECK(quiet.empty());
}

TEST_CASE("native loader: files, errors as exceptions, and save/load round trip") {
  const auto dir = std::filesystem::temp_directory_path() / "tripodal_net_loader_test";
  std::filesystem::create_directories(dir);
  Diagnostics d;
  CHECK_FALSE(load_net(dir / "missing.xml", d));
  CHECK_THAT(d.str(), Catch::Contains("missing.xml: error: cannot read the file"));
  REQUIRE_THROWS_WITH(load_net_or_throw(dir / "missing.xml"), Catch::Contains("cannot read the file"));

  Diagnostics d2;
  const auto net = load_net_from_string(kGood, "good.xml", d2);
  REQUIRE(net);
  save_net(*net, dir / "copy.xml");
  const PetriNet again = load_net_or_throw(dir / "copy.xml");
  CHECK(net_to_string(again, NetFormat::native_xml) == net_to_string(*net, NetFormat::native_xml));
  CHECK(again.where.file == (dir / "copy.xml").string());
  const std::string text = net_to_string(*net, NetFormat::native_xml);
  CHECK_THAT(text, Catch::Contains("<transition id=\"timeout\" delay=\"2500ms\"/>"));
  CHECK_THAT(text, Catch::Contains("guard=\"wheel_type == 'omni' &amp;&amp; !battery_low\""));
  std::filesystem::remove_all(dir);
}
