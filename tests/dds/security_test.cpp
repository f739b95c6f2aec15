// DDS Security for a fleet (include/tripodal/dds/security.hpp): keys made by make_fleet_keys with
// Debian's openssl, participants secured with Cyclone DDS's OMG DDS Security plugins. A robot hears
// an operator the fleet's CA vouches for; it does not hear a participant without security, nor one
// whose certificate another CA signed; an observer may read but not write.
#include "tripodal/dds/security.hpp"

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "child_process.hpp"
#include "dds_test_support.hpp"
#include "tripodal/dds/endpoint.hpp"

using namespace tripodal::dds;
using namespace tripodal::dds::test;
using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

constexpr std::uint32_t kDomainNumber = 50;

// The fleet's keys and a foreign CA's, made once for the test run.
const fs::path& keys() {
  static const fs::path dir = [] {
    const fs::path d = fs::temp_directory_path() / ("tripodal_keys_" + std::to_string(::getpid()));
    fs::remove_all(d);
    FleetKeysOptions o;
    o.out = d / "fleet";
    o.domain_id = test_domain(kDomainNumber);
    o.identities = {{"robot1", FleetRole::robot}, {"operator", FleetRole::operator_tool}, {"dashboard", FleetRole::observer}};
    make_fleet_keys(o);
    FleetKeysOptions foreign = o;
    foreign.out = d / "foreign";
    foreign.organisation = "tripodal fleet";  // same names, another CA
    foreign.identities = {{"operator", FleetRole::operator_tool}};
    make_fleet_keys(foreign);
    return d;
  }();
  return dir;
}

ParticipantOptions secured(const fs::path& dir, const std::string& identity) {
  ParticipantOptions o = test_options(kDomainNumber);
  o.security = fleet_identity(dir, identity);
  return o;
}

msg::Twist forward(double v) {
  msg::Twist t;
  t.linear.x = v;
  return t;
}

}  // namespace

TEST_CASE("security: a fleet's keys are made by openssl, each identity with its files") {
  const fs::path fleet = keys() / "fleet";
  for (const char* f :
       {"ca.pem", "governance.p7s", "robot1.pem", "robot1_key.pem", "robot1_permissions.p7s", "dashboard_permissions.p7s"}) {
    INFO(f);
    CHECK(fs::is_regular_file(fleet / f));
  }
  // Keys are for their owner only.
  CHECK((fs::status(fleet / "robot1_key.pem").permissions() & fs::perms::others_read) == fs::perms::none);
  // The observer's permissions grant no publication.
  std::ifstream xml(fleet / "dashboard_permissions.xml");
  const std::string text((std::istreambuf_iterator<char>(xml)), std::istreambuf_iterator<char>());
  CHECK(text.find("<publish>") == std::string::npos);
  CHECK(text.find("<subscribe>") != std::string::npos);
  // An identity is never made twice, and names are checked.
  FleetKeysOptions again;
  again.out = fleet;
  again.identities = {{"robot1", FleetRole::robot}};
  CHECK_THROWS_WITH(make_fleet_keys(again), Catch::Contains("robot1.pem exists"));
  again.identities = {{"robot 2", FleetRole::robot}};
  CHECK_THROWS_WITH(make_fleet_keys(again), Catch::Contains("'robot 2' is not an identity name"));
  CHECK_THROWS_WITH(fleet_identity(fleet, "robot9"), Catch::Contains("robot9.pem") && Catch::Contains("tripodal fleet keys"));
}

TEST_CASE("security: a secured robot hears the fleet's operator, not a participant without security or another CA's") {
  const fs::path fleet = keys() / "fleet";
  const std::string topic = ros_topic("cmd_vel", test_namespace());
  Participant robot(secured(fleet, "robot1"));
  Subscriber<msg::Twist> cmd_vel(robot, topic, {.kind = TopicKind::command});

  {
    Participant op(secured(fleet, "operator"));
    Publisher<msg::Twist> pub(op, topic, {.kind = TopicKind::command});
    REQUIRE(pub.wait_for_subscribers(1, 10s));
    pub.publish(forward(0.3));
    const auto got = cmd_vel.take_one(5s);
    REQUIRE(got.has_value());
    CHECK(got->linear.x == 0.3);
  }
  {
    // Without security, from another process (Cyclone DDS refuses a participant without security
    // in a process whose domain has secured ones): the robot's domain refuses unauthenticated
    // participants, so the peer's cmd_vel writer finds no subscriber (exit 3) and nothing arrives.
    ChildProcess intruder(TRIPODAL_DDS_PEER, {"cmd-vel", std::to_string(test_domain(kDomainNumber)), test_namespace(), "3"});
    CHECK(intruder.wait(20s) == 3);
    CHECK_FALSE(cmd_vel.take_one(500ms).has_value());
  }
  {
    // A certificate from another CA with the same name, from another process: authentication
    // fails, nothing matches (exit 3), nothing arrives. (In one process Cyclone DDS shares the
    // domain's security plugins between its participants, so this must be another process.)
    ChildProcess foreign(TRIPODAL_DDS_PEER, {"cmd-vel", std::to_string(test_domain(kDomainNumber)), test_namespace(), "3",
                                             (keys() / "foreign").string(), "operator"});
    CHECK(foreign.wait(20s) == 3);
    CHECK_FALSE(cmd_vel.take_one(500ms).has_value());
  }
  {
    // The fleet's operator from another process: heard (the same check across processes).
    ChildProcess op(TRIPODAL_DDS_PEER, {"cmd-vel", std::to_string(test_domain(kDomainNumber)), test_namespace(), "2",
                                        (keys() / "fleet").string(), "operator"});
    CHECK(op.wait(20s) == 0);
    const auto got = cmd_vel.take_one(2s);
    REQUIRE(got.has_value());
    CHECK(got->linear.x > 0.0);
  }
}

TEST_CASE("security: an observer may not command a robot, and may read") {
  const fs::path fleet = keys() / "fleet";
  const std::string topic = ros_topic("cmd_vel", test_namespace() + "_observer");
  Participant dashboard(secured(fleet, "dashboard"));
  // Access control refuses the writer: its permissions grant no publication.
  CHECK_THROWS_WITH(Publisher<msg::Twist>(dashboard, topic, {.kind = TopicKind::command}),
                    Catch::Contains("Not Allowed By Security"));
  Subscriber<msg::Twist> watch(dashboard, topic, {.kind = TopicKind::command});
  CHECK(watch.matched_publishers() == 0);
}

TEST_CASE("security: missing or malformed security files are refused naming the file") {
  const fs::path fleet = keys() / "fleet";
  ParticipantOptions o = secured(fleet, "robot1");
  o.security->governance = fleet / "no_such_governance.p7s";
  CHECK_THROWS_WITH(Participant(o), Catch::Contains("no_such_governance.p7s does not exist"));
  // A permissions document that is not signed S/MIME: Cyclone refuses the participant.
  const fs::path bad = keys() / "bad_permissions.p7s";
  std::ofstream(bad) << "<dds><permissions></permissions></dds>\n";
  o = secured(fleet, "robot1");
  o.security->permissions = bad;
  CHECK_THROWS_AS(Participant(o), DdsError);
}
