// CProcess and the process registry: typed parameters, configuration checks, factories.
#include <catch2/catch.hpp>

#include "doubles.hpp"
#include "tripodal/processes/process_registry.hpp"

using namespace tripodal;
using namespace tripodal::test;

namespace {

ProcessDefinition def(std::string name, PetriNet net, std::vector<BindingParam> params = {}) {
  ProcessDefinition d;
  d.name = std::move(name);
  d.net = std::move(net);
  d.parameters = std::move(params);
  d.where = SourceLocation{"robot.yaml", 12, 5};
  return d;
}

}  // namespace

TEST_CASE("CProcess binds defaults, configured values and plan values by the net's types", "[processes]") {
  PetriNet net = pr_cleaning();
  net.parameters.push_back(decl("speed_m_s", ValueType::number, Value{0.3}));
  CProcess p(def("PrCleaning", net, {BindingParam{"wheel_type", "two_wheel", {}}}));
  CHECK(p.behaviors() == std::vector<std::string>{"BhCleaning"});

  BoundParameters b = p.bind({BindingParam{"section", "A", {}}, BindingParam{"speed_m_s", "0.5", {}}});
  REQUIRE(b.ok);
  CHECK(std::get<std::string>(b.values.at("wheel_type")) == "two_wheel");
  CHECK(std::get<std::string>(b.values.at("section")) == "A");
  CHECK(std::get<double>(b.values.at("speed_m_s")) == 0.5);

  BoundParameters missing = p.bind({});
  CHECK_FALSE(missing.ok);
  CHECK(missing.error == "PrCleaning: parameter 'section' is required");

  BoundParameters bad = p.bind({BindingParam{"section", "A", {}}, BindingParam{"speed_m_s", "fast", {}}});
  CHECK_FALSE(bad.ok);
  CHECK(bad.error == "PrCleaning: parameter 'speed_m_s' expects a number, got 'fast'");

  BoundParameters unknown = p.bind({BindingParam{"room", "3211", {}}});
  CHECK_FALSE(unknown.ok);
  CHECK(unknown.error == "PrCleaning: parameter 'room' is not declared by its net");
}

TEST_CASE("CProcess refuses a bad definition with every problem located", "[processes]") {
  PetriNet net = pr_cleaning();
  net.parameters.push_back(decl("speed_m_s", ValueType::number));
  net.place(*net.find_place("P1")).behavior->params.push_back(BindingParam{"radius_m", "$radius", {"cleaning.xml", 7, 3}});
  try {
    CProcess p(def("PrCleaning", net,
                   {BindingParam{"speed_m_s", "fast", {"robot.yaml", 14, 20}}, BindingParam{"colour", "red", {"robot.yaml", 15, 9}}}));
    FAIL("no error");
  } catch (const ConfigError& e) {
    const std::string m = e.what();
    CHECK_THAT(m, Catch::Contains("robot.yaml:14:20: error: process 'PrCleaning': parameter 'speed_m_s' expects a number, got 'fast'"));
    CHECK_THAT(m, Catch::Contains("robot.yaml:15:9: error: process 'PrCleaning': parameter 'colour' is not declared by net 'PrCleaning' (declared: section, wheel_type, speed_m_s)"));
    CHECK_THAT(m, Catch::Contains("cleaning.xml:7:3: error: process 'PrCleaning': place 'P1' passes $radius to BhCleaning, but the net declares no parameter 'radius'"));
    CHECK(e.diagnostics().error_count() == 3);
  }
  // A typo of a declared name gets the suggestion (issue 40: every unknown name in a net).
  try {
    CProcess p(def("PrCleaning", pr_cleaning(), {BindingParam{"wheel_typ", "omni", {"robot.yaml", 16, 9}}}));
    FAIL("no error");
  } catch (const ConfigError& e) {
    CHECK_THAT(std::string(e.what()), Catch::Contains("parameter 'wheel_typ' is not declared by net 'PrCleaning' "
                                                      "(declared: section, wheel_type); did you mean 'wheel_type'?"));
  }

  PetriNet no_outcome;
  no_outcome.id = "loop";
  no_outcome.add_place(place("P0", 1));
  REQUIRE_THROWS_WITH(CProcess(def("PrLoop", no_outcome)),
                      Catch::Contains("robot.yaml:12:5: error: process 'PrLoop': net 'loop' has no outcome place"));
  PetriNet high = pr_auto_move();
  high.level = NetLevel::high;
  REQUIRE_THROWS_WITH(CProcess(def("PrHigh", high)), Catch::Contains("is a high-level net"));
}

TEST_CASE("resolve_binding_params substitutes $name and keeps literals as text", "[processes]") {
  ParameterValues run{{"section", Value{std::string("B")}}, {"speed", Value{0.4}}};
  ParameterValues out;
  std::string error;
  REQUIRE(resolve_binding_params({{"section", "$section", {}}, {"v", "$speed", {}}, {"pattern", "balloon", {}}}, run, out, error));
  CHECK(std::get<std::string>(out.at("section")) == "B");
  CHECK(std::get<double>(out.at("v")) == 0.4);
  CHECK(std::get<std::string>(out.at("pattern")) == "balloon");
  CHECK_FALSE(resolve_binding_params({{"x", "$nope", {}}}, run, out, error));
  CHECK(error == "parameter 'x' refers to $nope, which the process does not have");
}

namespace {
// An application process that derives its goal from a room name, as a robot would from its map.
class PrGoToRoom final : public CProcess {
 public:
  using CProcess::CProcess;
  // Its own type manifest: the one inherited from CProcess is that of the type "net".
  static const ModuleManifest& static_manifest() {
    static const ModuleManifest m = ManifestBuilder("go_to_room", ModuleKind::process, Layer::sequencing)
                                        .description("goes to the door of the room named by 'goal'")
                                        .build();
    return m;
  }

 protected:
  std::string on_bind(ParameterValues& values) const override {
    const auto& goal = std::get<std::string>(values.at("goal"));
    if (goal.rfind("room ", 0) != 0) return "PrGoToRoom: goal must name a room, got '" + goal + "'";
    values["goal"] = Value{goal.substr(5) + ".door"};
    return {};
  }
};
}  // namespace

TEST_CASE("ProcessRegistry builds processes by factory type and refuses duplicates", "[processes]") {
  ProcessRegistry reg;
  reg.add(def("PrCleaning", pr_cleaning()));
  reg.types().add<PrGoToRoom>();
  CHECK(reg.types().names() == std::vector<std::string>{"go_to_room", "net"});
  CHECK(reg.types().manifest("go_to_room").kind == ModuleKind::process);
  ProcessDefinition g = def("PrGoToRoom", pr_auto_move());
  g.type = "go_to_room";
  reg.add(std::move(g));
  CHECK(reg.names() == std::vector<std::string>{"PrCleaning", "PrGoToRoom"});
  REQUIRE(reg.find("PrGoToRoom") != nullptr);
  CHECK(reg.find("PrNope") == nullptr);
  BoundParameters b = reg.find("PrGoToRoom")->bind({BindingParam{"goal", "room 2111", {}}});
  REQUIRE(b.ok);
  CHECK(std::get<std::string>(b.values.at("goal")) == "2111.door");
  CHECK(reg.find("PrGoToRoom")->bind({BindingParam{"goal", "kitchen", {}}}).error ==
        "PrGoToRoom: goal must name a room, got 'kitchen'");

  REQUIRE_THROWS_WITH(reg.add(def("PrCleaning", pr_cleaning())),
                      Catch::Contains("robot.yaml:12:5: error: process 'PrCleaning' is defined twice"));
  ProcessDefinition u = def("PrX", pr_cleaning());
  u.type = "scripted";
  REQUIRE_THROWS_WITH(reg.add(std::move(u)),
                      Catch::Contains("robot.yaml:12:5: error: unknown process type 'scripted'; known: go_to_room, net") &&
                          !Catch::Contains("did you mean"));
  ProcessDefinition n = def("PrY", pr_cleaning());
  n.type = "nett";
  REQUIRE_THROWS_WITH(reg.add(std::move(n)),
                      Catch::Contains("unknown process type 'nett'; known: go_to_room, net; did you mean 'net'?"));
  CHECK_FALSE(reg.contains("PrY"));
  REQUIRE_THROWS_AS(reg.types().add<CProcess>(), std::invalid_argument);
}

TEST_CASE("A process declares a manifest: its net's parameters and the behaviors it binds", "[processes]") {
  PetriNet net = pr_cleaning();
  net.parameters.push_back(decl("speed_m_s", ValueType::number, Value{0.3}));
  const CProcess p(def("PrCleaning", net));
  const ModuleManifest& m = p.manifest();
  CHECK(m.name == "PrCleaning");
  CHECK(m.kind == ModuleKind::process);
  CHECK(m.layer == Layer::sequencing);
  CHECK_THAT(m.description, Catch::Contains("binding BhCleaning"));
  REQUIRE(m.find_parameter("speed_m_s") != nullptr);
  CHECK(m.find_parameter("speed_m_s")->type == ValueType::number);
  CHECK(m.find_parameter("speed_m_s")->default_value == Value{0.3});
  REQUIRE(m.find_parameter("section") != nullptr);
  CHECK_FALSE(m.find_parameter("section")->default_value.has_value());  // required, as the net declares it
  CHECK(m.parameters.size() == net.parameters.size());

  // A process type of an application gets its manifest the same way.
  const PrGoToRoom g(def("PrGoToRoom", pr_auto_move()));
  CHECK(g.manifest().name == "PrGoToRoom");
  CHECK(g.manifest().kind == ModuleKind::process);
  CHECK(PrGoToRoom::static_manifest().name == "go_to_room");
  CHECK(CProcess::static_manifest().name == "net");
}

TEST_CASE("Every registered process type can be created by name and describes itself", "[processes]") {
  ProcessRegistry reg;
  reg.types().add<PrGoToRoom>();
  for (const auto& type : reg.types().names()) {
    INFO(type);
    const ModuleManifest& m = reg.types().manifest(type);
    CHECK(m.name == type);
    CHECK(m.kind == ModuleKind::process);
    CHECK(m.layer == Layer::sequencing);
    CHECK_FALSE(m.description.empty());
    ProcessDefinition d = def("Pr_" + type, pr_auto_move());
    d.type = type;
    const std::unique_ptr<CProcess> p = reg.types().create(type, std::move(d));
    REQUIRE(p);
    CHECK(p->name() == "Pr_" + type);
    CHECK(p->type() == type);
    CHECK(p->manifest().find_parameter("goal") != nullptr);
  }
}
