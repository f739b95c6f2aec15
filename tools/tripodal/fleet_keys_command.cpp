// `tripodal fleet-keys --out DIR --robot NAME ... [--operator NAME ...] [--observer NAME ...]`: a
// fleet's DDS Security keys (tripodal/dds/security.hpp, docs/distribution.md "Security"), made
// with Debian's openssl: the fleet CA, a certificate and key per identity, the signed governance
// document and each identity's signed permissions.
#include <memory>
#include <ostream>

#include "cli_tool.hpp"
#include "tripodal/dds/security.hpp"

namespace tripodal::tool {
namespace {

using namespace cli;

constexpr std::string_view kDescription =
    "Makes the DDS Security keys of a fleet in DIR with openssl: ca.pem (the fleet's CA; kept and\n"
    "reused when DIR has one), NAME.pem and NAME_key.pem per identity, governance.p7s (only\n"
    "participants the CA vouches for join; discovery, liveliness and every topic's data are\n"
    "encrypted) and NAME_permissions.p7s (robots and operators publish and subscribe every topic of\n"
    "the domain, observers only subscribe). A robot uses them from its profile's dds section\n"
    "(security: {keys: DIR, identity: NAME}). An identity that exists in DIR is refused, not\n"
    "overwritten. Keep ca_key.pem off the robots. --revoke NAME adds NAME's certificate to the CA's\n"
    "revocation list DIR/crl.pem, which every participant using DIR then checks peers against (copy\n"
    "it to the robots).";

constexpr std::string_view kExitCodes =
    "exit codes: 0 ok, 1 a name is refused, 2 bad command line, 3 openssl failed or DIR is not writable";

struct Args {
  std::string out;
  std::vector<std::string> robots, operators, observers;
  unsigned domain = 0;
  int days = 365;
  std::vector<std::string> revoke;
};

int revoke(const Args& a, std::ostream& out, std::ostream& err) {
  try {
    for (const std::string& n : a.revoke) dds::revoke_fleet_identity(a.out, n);
  } catch (const std::exception& e) {
    err << "tripodal fleet-keys: " << e.what() << '\n';
    return kIoError;
  }
  out << "revoked " << a.revoke.size() << (a.revoke.size() == 1 ? " identity" : " identities") << "; revocation list " << a.out
      << "/crl.pem\n";
  return kOk;
}

int make(const Args& a, std::ostream& out, std::ostream& err) {
  dds::FleetKeysOptions o;
  o.out = a.out;
  o.domain_id = a.domain;
  o.valid_days = a.days;
  for (const auto& n : a.robots) o.identities.emplace_back(n, dds::FleetRole::robot);
  for (const auto& n : a.operators) o.identities.emplace_back(n, dds::FleetRole::operator_tool);
  for (const auto& n : a.observers) o.identities.emplace_back(n, dds::FleetRole::observer);
  try {
    dds::make_fleet_keys(o);
  } catch (const std::invalid_argument& e) {
    err << "tripodal fleet-keys: " << e.what() << '\n';
    return kBadInput;
  } catch (const std::exception& e) {
    err << "tripodal fleet-keys: " << e.what() << '\n';
    return kIoError;
  }
  out << "fleet keys in " << a.out << " for domain " << a.domain << ": " << o.identities.size() << " identities (";
  for (std::size_t k = 0; k < o.identities.size(); ++k) out << (k == 0 ? "" : ", ") << o.identities[k].first;
  out << "), valid " << a.days << " days\n";
  return kOk;
}

cli::Action setup(CLI::App& cmd) {
  auto a = std::make_shared<Args>();
  cmd.add_option("--out", a->out, "DIR: where the keys go (created)")->required();
  cmd.add_option("--robot", a->robots, "NAME: a robot's identity (repeatable)");
  cmd.add_option("--operator", a->operators, "NAME: an operator tool's identity: the monitor, the fleet tool (repeatable)");
  cmd.add_option("--observer", a->observers, "NAME: an identity that may only read (repeatable)");
  cmd.add_option("--domain", a->domain, "ID: the fleet's DDS domain")->check(CLI::Range(0, 232))->capture_default_str();
  cmd.add_option("--days", a->days, "N: how long the certificates and permissions are valid")
      ->check(CLI::Range(1, 36500))
      ->capture_default_str();
  cmd.add_option("--revoke", a->revoke, "NAME: revoke the identity NAME of DIR (its certificate on DIR/crl.pem; repeatable)");
  return [a](std::ostream& out, std::ostream& err) {
    if (!a->revoke.empty()) {
      if (!a->robots.empty() || !a->operators.empty() || !a->observers.empty()) {
        err << "tripodal fleet-keys: --revoke goes alone, not with new identities\n";
        return static_cast<int>(kUsage);
      }
      return revoke(*a, out, err);
    }
    if (a->robots.empty() && a->operators.empty() && a->observers.empty()) {
      err << "tripodal fleet-keys: give at least one identity (--robot, --operator or --observer)\n";
      return static_cast<int>(kUsage);
    }
    return make(*a, out, err);
  };
}

}  // namespace

TRIPODAL_CLI_COMMAND("", "fleet-keys", "make a fleet's DDS Security keys (CA, identities, governance, permissions) with openssl",
                     kDescription, kExitCodes, &setup);

}  // namespace tripodal::tool
