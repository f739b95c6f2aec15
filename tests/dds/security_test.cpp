// DDS Security for a fleet (include/tripodal/dds/security.hpp): keys made by make_fleet_keys with
// Debian's openssl, participants secured with Cyclone DDS's OMG DDS Security plugins. A robot hears
// an operator the fleet's CA vouches for; it does not hear a participant without security, nor one
// whose certificate another CA signed; an observer may read but not write.
#include "tripodal/dds/security.hpp"

#include <algorithm>
#include <catch2/catch.hpp>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iterator>
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

namespace {

// Runs a shell command line (openssl), failing the test with its output when it fails.
void sh(const std::string& command) {
  const std::string log = (keys() / "sh.log").string();
  const int rc = std::system((command + " >" + log + " 2>&1").c_str());
  std::ifstream in(log);
  const std::string out((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  INFO(command << "\n" << out);
  REQUIRE(rc == 0);
}

// A copy of the fleet's keys folder, to change without touching the other tests' keys.
fs::path copy_of_fleet(const std::string& name) {
  const fs::path to = keys() / name;
  fs::remove_all(to);
  fs::copy(keys() / "fleet", to, fs::copy_options::recursive);
  return to;
}

std::string text_of(const fs::path& file) {
  std::ifstream in(file);
  return {(std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>()};
}

// The line (from 1) of the first occurrence of `needle` in `text`.
int line_of(const std::string& text, const std::string& needle) {
  const std::size_t at = text.find(needle);
  REQUIRE(at != std::string::npos);
  return 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
}

}  // namespace

TEST_CASE("security: an expired certificate of the fleet's own CA is refused") {
  // The operator's identity again, its certificate signed by the fleet's CA but valid in January
  // 2020 only (openssl ca with explicit dates).
  const fs::path dir = copy_of_fleet("expired");
  sh("cd '" + dir.string() +
     "' && openssl req -new -key operator_key.pem -out operator.csr -subj '/CN=operator/O=tripodal fleet'"
     " && mkdir -p exp_db && : > exp_db/index.txt && echo 1000 > exp_db/serial"
     " && printf '[ca]\\ndefault_ca = x\\n[x]\\ndatabase = exp_db/index.txt\\nnew_certs_dir = exp_db\\nserial = exp_db/serial\\n"
     "default_md = sha256\\npolicy = any\\n[any]\\ncommonName = supplied\\norganizationName = optional\\n' > exp_db/ca.cnf"
     " && openssl ca -batch -config exp_db/ca.cnf -cert ca.pem -keyfile ca_key.pem -startdate 20200101000000Z"
     " -enddate 20200201000000Z -in operator.csr -out operator.pem -notext");
  // In this process: Cyclone refuses to create the participant.
  CHECK_THROWS_AS(Participant(secured(dir, "operator")), DdsError);
  // From another process against a secured robot: the peer cannot join (it fails or matches
  // nothing), and nothing arrives.
  const std::string topic = ros_topic("cmd_vel", test_namespace() + "_expired");
  Participant robot(secured(keys() / "fleet", "robot1"));
  Subscriber<msg::Twist> cmd_vel(robot, topic, {.kind = TopicKind::command});
  ChildProcess peer(TRIPODAL_DDS_PEER, {"cmd-vel", std::to_string(test_domain(kDomainNumber)), test_namespace() + "_expired", "3",
                                        dir.string(), "operator"});
  CHECK(peer.wait(20s) != 0);
  CHECK_FALSE(cmd_vel.take_one(500ms).has_value());
}

TEST_CASE("security: a revoked certificate is refused by a robot that has the CA's revocation list") {
  // A robot's keys with the operator revoked (revoke_fleet_identity: crl.pem beside the keys,
  // which fleet_identity hands the participant); the operator still has its old keys folder.
  const fs::path robot_keys = copy_of_fleet("revoking");
  revoke_fleet_identity(robot_keys, "operator");
  REQUIRE(fs::is_regular_file(robot_keys / "crl.pem"));
  CHECK(fleet_identity(robot_keys, "robot1").crl == robot_keys / "crl.pem");
  CHECK(fleet_identity(keys() / "fleet", "robot1").crl.empty());
  CHECK_THROWS_WITH(revoke_fleet_identity(robot_keys, "nobody"), Catch::Contains("nobody.pem does not exist"));

  const std::string ns = test_namespace() + "_revoked";
  const std::string topic = ros_topic("cmd_vel", ns);
  Participant robot(secured(robot_keys, "robot1"));
  Subscriber<msg::Twist> cmd_vel(robot, topic, {.kind = TopicKind::command});
  {
    ChildProcess revoked(TRIPODAL_DDS_PEER, {"cmd-vel", std::to_string(test_domain(kDomainNumber)), ns, "3",
                                             (keys() / "fleet").string(), "operator"});
    CHECK(revoked.wait(20s) == 3);  // matched nothing: the robot refused its certificate
    CHECK_FALSE(cmd_vel.take_one(500ms).has_value());
  }
  {
    // An identity the list does not name, same CA, is still heard by the same robot.
    ChildProcess fine(TRIPODAL_DDS_PEER,
                      {"cmd-vel", std::to_string(test_domain(kDomainNumber)), ns, "2", (keys() / "fleet").string(), "robot1"});
    CHECK(fine.wait(20s) == 0);
    CHECK(cmd_vel.take_one(2s).has_value());
  }
}

TEST_CASE("security: malformed governance and permissions documents are refused with their lines") {
  const fs::path dir = copy_of_fleet("malformed");
  const std::string good = text_of(dir / "robot1_permissions.p7s");
  const auto refused = [&](const std::string& text) -> std::string {
    std::ofstream(dir / "robot1_permissions.p7s") << text;
    try {
      Participant p(secured(dir, "robot1"));
    } catch (const DdsError& e) {
      return e.what();
    }
    FAIL("the participant was created");
    return {};
  };
  const std::string file = (dir / "robot1_permissions.p7s").string();
  {
    // A tag left open: XML not well formed, at its line.
    std::string t = good;
    t.replace(t.find("</subject_name>"), 15, "</subject>");
    const std::string msg = refused(t);
    CHECK_THAT(msg, Catch::StartsWith(file + ":" + std::to_string(line_of(t, "</subject>")) +
                                      ": error: the permissions XML is not well formed"));
  }
  {
    // Every problem at once: a validity that ended, a date that does not parse, a bad default.
    std::string t = good;
    const std::size_t nb = t.find("<not_before>") + 12;
    t.replace(nb, t.find("</not_before>") - nb, "yesterday");
    const std::size_t na = t.find("<not_after>") + 11;
    t.replace(na, t.find("</not_after>") - na, "2020-02-01T00:00:00");
    t.replace(t.find("<default>DENY"), 13, "<default>MAYBE");
    const std::string msg = refused(t);
    const std::string at_validity = file + ":" + std::to_string(line_of(t, "<not_after>")) + ": error: ";
    CHECK_THAT(msg, Catch::Contains(at_validity + "<not_before> 'yesterday' is not a date YYYY-MM-DDTHH:MM:SS"));
    CHECK_THAT(msg, Catch::Contains(at_validity + "the permissions expired on 2020-02-01T00:00:00 (UTC)"));
    CHECK_THAT(msg, Catch::Contains(file + ":" + std::to_string(line_of(t, "<default>")) +
                                    ": error: <default> is 'MAYBE': expected ALLOW or DENY"));
  }
  {
    // A grant without its subject.
    std::string t = good;
    const std::size_t s = t.find("      <subject_name>");
    t.erase(s, t.find('\n', s) + 1 - s);
    CHECK_THAT(refused(t),
               Catch::Contains(file + ":" + std::to_string(line_of(t, "<grant")) + ": error: <grant> has no <subject_name>"));
  }
  std::ofstream(dir / "robot1_permissions.p7s") << good;
  // A governance document without its signature.
  std::ofstream(dir / "governance.p7s") << "<dds>\n  <domain_access_rules/>\n</dds>\n";
  try {
    Participant p(secured(dir, "robot1"));
    FAIL("created");
  } catch (const DdsError& e) {
    CHECK_THAT(std::string(e.what()),
               Catch::StartsWith((dir / "governance.p7s").string() + ":1: error: the governance document is not signed S/MIME"));
  }
}
