// PNML import and export: real files written by other tools (TAPAAL's ISO PNML, Petri Net Plans'
// JARP dialect), inhibitor encodings, round trips, and refusal of what a P/T net cannot hold.
#include <catch2/catch.hpp>

#include <filesystem>

#include "tripodal/core/engine.hpp"
#include "tripodal/core/net_loader.hpp"

using namespace tripodal;

namespace {

const std::filesystem::path kData = std::filesystem::path(TRIPODAL_TEST_DATA_DIR) / "pnml";
const std::filesystem::path kConfigs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs" / "petri";

struct Counts {
  std::size_t places = 0, transitions = 0, arcs = 0, tokens = 0, inhibitors = 0, reads = 0;
};

Counts count(const PetriNet& net) {
  Counts c;
  c.places = net.places().size();
  c.transitions = net.transitions().size();
  for (const auto& p : net.places()) c.tokens += p.initial_tokens;
  for (const auto& t : net.transitions()) {
    c.arcs += t.inputs.size() + t.outputs.size() + t.reads.size() + t.inhibitors.size();
    c.inhibitors += t.inhibitors.size();
    c.reads += t.reads.size();
  }
  return c;
}

PetriNet load_file(const std::filesystem::path& file) {
  Diagnostics d;
  auto net = load_net(file, d);
  INFO(d.str());
  REQUIRE(net.has_value());
  return std::move(*net);
}

std::string errors_of(const std::string& text) {
  Diagnostics d;
  CHECK_FALSE(load_net_from_string(text, "bad.pnml", d).has_value());
  CHECK(d.has_errors());
  return d.str();
}

std::string iso(const std::string& net_type, const std::string& page_content) {
  return "<?xml version=\"1.0\"?>\n"
         "<pnml xmlns=\"http://www.pnml.org/version-2009/grammar/pnml\">\n"
         "  <net id=\"n\" type=\"" + net_type + "\">\n"
         "    <page id=\"pg\">\n" + page_content +
         "    </page>\n"
         "  </net>\n"
         "</pnml>\n";
}

const std::string kPtNet = "http://www.pnml.org/version-2009/grammar/ptnet";
const std::string kTwoNodes =
    "      <place id=\"p\"><initialMarking><text>1</text></initialMarking></place>\n"  // line 5
    "      <transition id=\"t\"/>\n";                                                    // line 6

}  // namespace

TEST_CASE("PNML: Kanban2 (ISO 2009, TAPAAL) loads with its counts") {
  const PetriNet net = load_file(kData / "Kanban2-test001.pnml");
  const Counts c = count(net);
  CHECK(c.places == 16);
  CHECK(c.transitions == 16);
  CHECK(c.arcs == 40);
  CHECK(c.tokens == 8);
  CHECK(c.inhibitors == 0);
  CHECK(net.id == "ComposedModel");
  CHECK(net.name == "ComposedModel");
  const Place& p3 = net.place(*net.find_place("P3"));
  CHECK(p3.initial_tokens == 2);
  CHECK(p3.where.line == 5);
  CHECK(p3.where.column == 13);
}

TEST_CASE("PNML: inhibitor arcs from TAPAAL files (type attribute)") {
  const PetriNet dead = load_file(kData / "deadlock-test018.pnml");
  REQUIRE(dead.transitions().size() == 1);
  const Transition& t0 = dead.transition(0);
  REQUIRE(t0.inhibitors.size() == 1);
  CHECK(dead.place(t0.inhibitors[0].place).id == "P0");
  CHECK(t0.inputs.empty());
  REQUIRE(t0.outputs.size() == 1);
  // P0 holds a token, the inhibitor forbids T0: the initial marking is already dead.
  Engine engine(dead);
  CHECK_FALSE(engine.is_enabled(0));
  CHECK(engine.step(Time{}).firings == 0);

  const Counts c = count(load_file(kData / "inhibitors-test001.pnml"));
  CHECK(c.places == 5);
  CHECK(c.transitions == 4);
  CHECK(c.arcs == 10);
  CHECK(c.inhibitors == 2);
  CHECK(c.tokens == 2);
}

TEST_CASE("PNML: Petri Net Plans files in the JARP dialect load") {
  struct Expected {
    const char* file;
    std::size_t places, transitions, arcs;
  };
  for (const auto& e : {Expected{"pnp-sequence_loop.pnml", 5, 4, 8}, Expected{"pnp-fork_join.pnml", 12, 10, 22},
                        Expected{"pnp-interrupt.pnml", 9, 9, 18}}) {
    INFO(e.file);
    const PetriNet net = load_file(kData / e.file);
    const Counts c = count(net);
    CHECK(c.places == e.places);
    CHECK(c.transitions == e.transitions);
    CHECK(c.arcs == e.arcs);
    CHECK(c.tokens == 1);
    CHECK(net.name == "P/T net");
  }
  const PetriNet interrupt = load_file(kData / "pnp-interrupt.pnml");
  CHECK(interrupt.place(*interrupt.find_place("p2")).name == "gotopose_6_2_0.exec");
  CHECK(interrupt.place(*interrupt.find_place("p1")).initial_tokens == 1);
}

TEST_CASE("PNML: round trips keep the net") {
  SECTION("native -> PNML -> native, for the paper's nets") {
    for (const char* name : {"PrCleaning.xml", "PrCleaning-module.xml", "PrAutoMove.xml", "PrAutoMove-module.xml"}) {
      INFO(name);
      const PetriNet original = load_file(kConfigs / name);
      const std::string pnml = net_to_string(original, NetFormat::pnml);
      Diagnostics d;
      LoadOptions as_pnml;
      as_pnml.format = NetFormat::pnml;
      const auto back = load_net_from_string(pnml, "roundtrip.pnml", d, as_pnml);
      INFO(d.str() << pnml);
      REQUIRE(back.has_value());
      CHECK(net_to_string(*back, NetFormat::native_xml) == net_to_string(original, NetFormat::native_xml));
      const Counts a = count(original);
      const Counts b = count(*back);
      CHECK(a.arcs == b.arcs);
      CHECK(a.reads == b.reads);
    }
  }
  SECTION("PNML -> native -> PNML, for the files of other tools") {
    for (const char* name : {"Kanban2-test001.pnml", "inhibitors-test001.pnml", "deadlock-test018.pnml",
                             "pnp-fork_join.pnml", "pnp-interrupt.pnml"}) {
      INFO(name);
      const PetriNet original = load_file(kData / name);
      const std::string native = net_to_string(original, NetFormat::native_xml);
      Diagnostics d;
      const auto back = load_net_from_string(native, "roundtrip.xml", d);
      INFO(d.str());
      REQUIRE(back.has_value());
      CHECK(net_to_string(*back, NetFormat::pnml) == net_to_string(original, NetFormat::pnml));
    }
  }
  SECTION("a read arc travels as a marked self-loop, which other tools read as a plain loop") {
    const PetriNet net = load_file(kConfigs / "PrCleaning.xml");
    const std::string pnml = net_to_string(net, NetFormat::pnml);
    CHECK_THAT(pnml, Catch::Contains("<toolspecific tool=\"tripodal\" version=\"1\">"));
    CHECK_THAT(pnml, Catch::Contains("event=\"localizer.lost\"/>"));
    CHECK_THAT(pnml, Catch::Contains("source=\"P3\" target=\"t4\">"));
    CHECK_THAT(pnml, Catch::Contains("source=\"t4\" target=\"P3\">"));
    CHECK_THAT(pnml, Catch::Contains("<page id=\"page0\">"));
  }
}

TEST_CASE("PNML: the inhibitor encodings found in real files") {
  for (const std::string arc : {
           "      <arc id=\"a\" source=\"p\" target=\"t\" type=\"inhibitor\"/>\n",
           "      <arc id=\"a\" source=\"p\" target=\"t\"><type><text>inhibitor</text></type></arc>\n",
           "      <arc id=\"a\" source=\"p\" target=\"t\"><type value=\"inhibitor\"/></arc>\n"}) {
    Diagnostics d;
    const auto net = load_net_from_string(iso(kPtNet, kTwoNodes + arc), "i.pnml", d);
    INFO(arc << d.str());
    REQUIRE(net.has_value());
    REQUIRE(net->transition(0).inhibitors.size() == 1);
    CHECK(net->transition(0).inputs.empty());
  }
}

TEST_CASE("PNML: what a P/T net cannot hold is refused with a location") {
  CHECK_THAT(errors_of(iso("http://www.pnml.org/version-2009/grammar/symmetricnet", kTwoNodes)),
             Catch::Contains("bad.pnml:3:21: error: net type 'http://www.pnml.org/version-2009/grammar/symmetricnet' "
                             "is not a place/transition net"));
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <arc id=\"a\" source=\"p\" target=\"t\" type=\"transport\"/>\n")),
             Catch::Contains("bad.pnml:7:47: error: unknown arc type 'transport'"));
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <arc id=\"a\" source=\"p\" target=\"t\"><type><text>reset</text></type></arc>\n")),
             Catch::Contains("bad.pnml:7:41: error: unknown arc type 'reset'"));
  CHECK_THAT(errors_of(iso(kPtNet, "      <place id=\"p\"><hlinitialMarking><text>1'a</text></hlinitialMarking></place>\n")),
             Catch::Contains("bad.pnml:5:21: error: place 'p' has <hlinitialMarking>: colored/high-level places"));
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <referencePlace id=\"r\" ref=\"p\"/>\n")),
             Catch::Contains("bad.pnml:7:7: error: <referencePlace> is not supported"));
  CHECK_THAT(errors_of(iso(kPtNet, "      <place id=\"p\"><capacity><text>2</text></capacity></place>\n")),
             Catch::Contains("bad.pnml:5:21: error: unknown label <capacity> on place 'p'"));
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <arc id=\"a\" source=\"p\" target=\"t\"><inscription><text>0</text></inscription></arc>\n")),
             Catch::Contains("bad.pnml:7:54: error: non-positive weight '0'"));
  CHECK_THAT(errors_of(iso(kPtNet, "      <place id=\"p\"><initialMarking><text>many</text></initialMarking></place>\n")),
             Catch::Contains("bad.pnml:5:37: error: bad token count 'many'"));
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <arc id=\"a\" source=\"p\" target=\"q\"/>\n")),
             Catch::Contains("bad.pnml:7:38: error: arc to unknown node 'q'"));
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <transition id=\"p\"/>\n")),
             Catch::Contains("bad.pnml:7:23: error: duplicate id 'p' (first defined at bad.pnml:5:7)"));
  CHECK_THAT(errors_of("<pnml><net id=\"a\" type=\"PTNet\"/><net id=\"b\" type=\"PTNet\"/></pnml>"),
             Catch::Contains("bad.pnml:1:33: error: a second <net>"));
  CHECK_THAT(errors_of("<pnml><net id=\"a\"/></pnml>"), Catch::Contains("bad.pnml:1:7: error: missing attribute 'type' on <net>"));
  CHECK_THAT(errors_of("<pnml/>"), Catch::Contains("bad.pnml:1:1: error: no <net> in the PNML document"));
  CHECK_THAT(errors_of("<net id=\"x\"/>"), Catch::Contains("bad.pnml:1:1: error: unexpected root element <net>: expected <pnml>"));
}

TEST_CASE("PNML: pages, places, transitions and arcs share one id space, in any order") {
  // An arc's id taken again by a place declared after it, a page's by a transition, and many ids
  // (past the id table's first size) before a duplicate of the last one: each duplicate names
  // where the id was first defined.
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <arc id=\"a\" source=\"p\" target=\"t\"/>\n"
                                               "      <place id=\"a\"/>\n")),
             Catch::Contains("bad.pnml:8:18: error: duplicate id 'a' (first defined at bad.pnml:7:7)"));
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <transition id=\"pg\"/>\n")),
             Catch::Contains("bad.pnml:7:23: error: duplicate id 'pg' (first defined at bad.pnml:4:5)"));
  CHECK_THAT(errors_of(iso(kPtNet, kTwoNodes + "      <arc id=\"p\" source=\"p\" target=\"t\"/>\n")),
             Catch::Contains("bad.pnml:7:16: error: duplicate id 'p' (first defined at bad.pnml:5:7)"));
  std::string many;
  for (int i = 0; i < 3000; ++i) many += "      <place id=\"q" + std::to_string(i) + "\"/>\n";  // lines 5 to 3004
  many += "      <transition id=\"q2999\"/>\n";                                                 // line 3005
  const std::string errors = errors_of(iso(kPtNet, many));
  CHECK_THAT(errors, Catch::Contains("bad.pnml:3005:23: error: duplicate id 'q2999' (first defined at bad.pnml:3004:7)"));
  CHECK(errors.find("duplicate id 'q") == errors.rfind("duplicate id 'q"));  // that one only
}

TEST_CASE("PNML: read arcs fold back from their two halves in any order") {
  // The return half (t -> p) before the forward half, and two read arcs on one place.
  const std::string mark = "<toolspecific tool=\"tripodal\" version=\"1\"><arc kind=\"read\"/></toolspecific>";
  const std::string page = kTwoNodes +
                           "      <transition id=\"u\"/>\n"
                           "      <arc id=\"b1\" source=\"t\" target=\"p\">" +
                           mark +
                           "</arc>\n"
                           "      <arc id=\"f1\" source=\"p\" target=\"t\">" +
                           mark +
                           "</arc>\n"
                           "      <arc id=\"f2\" source=\"p\" target=\"u\">" +
                           mark +
                           "</arc>\n"
                           "      <arc id=\"b2\" source=\"u\" target=\"p\">" +
                           mark + "</arc>\n";
  Diagnostics d;
  const auto net = load_net_from_string(iso(kPtNet, page), "ok.pnml", d);
  INFO(d.str());
  REQUIRE(net.has_value());
  for (const auto& t : net->transitions()) {
    INFO(t.id);
    CHECK(t.reads.size() == 1);
    CHECK(t.inputs.empty());
    CHECK(t.outputs.empty());
  }
}

TEST_CASE("PNML: the tripodal extension is checked like the native format") {
  const std::string ts_version =
      kTwoNodes + "      <transition id=\"u\"><toolspecific tool=\"tripodal\" version=\"9\"><transition event=\"e\"/></toolspecific></transition>\n";
  CHECK_THAT(errors_of(iso(kPtNet, ts_version)), Catch::Contains("bad.pnml:7:65: error: tripodal extension version '9' is not supported"));
  const std::string bad_guard =
      kTwoNodes + "      <transition id=\"u\"><toolspecific tool=\"tripodal\" version=\"1\"><transition guard=\"x ==\"/></toolspecific></transition>\n";
  const auto e = errors_of(iso(kPtNet, bad_guard));
  CHECK_THAT(e, Catch::Contains("bad.pnml:7:91: error: guard of transition 'u' does not parse"));
  const std::string half_read =
      kTwoNodes + "      <arc id=\"a\" source=\"p\" target=\"t\"><toolspecific tool=\"tripodal\" version=\"1\"><arc kind=\"read\"/></toolspecific></arc>\n";
  CHECK_THAT(errors_of(iso(kPtNet, half_read)),
             Catch::Contains("bad.pnml:7:7: error: tripodal read arc 'p' -> 't' has no matching arc 't' -> 'p' of weight 1"));
  // Other tools' toolspecific blocks are theirs: ignored.
  Diagnostics d;
  CHECK(load_net_from_string(iso(kPtNet, kTwoNodes + "      <toolspecific tool=\"other\" version=\"3\"><anything/></toolspecific>\n"),
                             "ok.pnml", d));
}
