#include "tripodal/dds/security.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <set>
#include <stdexcept>

#include "tripodal/dds/participant.hpp"

extern char** environ;

namespace tripodal::dds {

namespace fs = std::filesystem;

namespace {

// Runs `openssl args...` in `dir`; throws DdsError with what it wrote to stderr when it fails.
void openssl(const fs::path& dir, std::vector<std::string> args) {
  args.insert(args.begin(), "openssl");
  std::vector<char*> argv;
  argv.reserve(args.size() + 1);
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  int err_pipe[2];
  if (::pipe(err_pipe) != 0) throw DdsError("fleet keys: pipe: " + std::string(std::strerror(errno)));
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addclose(&actions, err_pipe[0]);
  posix_spawn_file_actions_adddup2(&actions, err_pipe[1], STDERR_FILENO);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addchdir_np(&actions, dir.c_str());
  pid_t pid = 0;
  const int rc = posix_spawnp(&pid, "openssl", &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  ::close(err_pipe[1]);
  std::string err;
  char buf[512];
  for (ssize_t n; (n = ::read(err_pipe[0], buf, sizeof buf)) > 0;) err.append(buf, static_cast<std::size_t>(n));
  ::close(err_pipe[0]);
  if (rc != 0) throw DdsError("fleet keys: cannot run openssl (install Debian's openssl): " + std::string(std::strerror(rc)));
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    std::string cmd;
    for (const auto& a : args) cmd += (cmd.empty() ? "" : " ") + a;
    throw DdsError("fleet keys: '" + cmd + "' failed in " + dir.string() + ": " + err);
  }
}

void write_file(const fs::path& file, const std::string& text) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) throw DdsError("fleet keys: cannot write " + file.string());
}

std::string governance_xml(std::uint32_t domain) {
  const std::string d = std::to_string(domain);
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<!-- Made by `tripodal fleet keys`: the fleet's domain is protected. Only participants the fleet's
     CA vouches for join; discovery, liveliness and every topic's data are encrypted; every topic
     needs a permission to be read or written. -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_governance.xsd">
  <domain_access_rules>
    <domain_rule>
      <domains><id>)" +
         d + R"(</id></domains>
      <allow_unauthenticated_participants>false</allow_unauthenticated_participants>
      <enable_join_access_control>true</enable_join_access_control>
      <discovery_protection_kind>ENCRYPT</discovery_protection_kind>
      <liveliness_protection_kind>ENCRYPT</liveliness_protection_kind>
      <rtps_protection_kind>NONE</rtps_protection_kind>
      <topic_access_rules>
        <topic_rule>
          <topic_expression>*</topic_expression>
          <enable_discovery_protection>true</enable_discovery_protection>
          <enable_liveliness_protection>true</enable_liveliness_protection>
          <enable_read_access_control>true</enable_read_access_control>
          <enable_write_access_control>true</enable_write_access_control>
          <metadata_protection_kind>ENCRYPT</metadata_protection_kind>
          <data_protection_kind>ENCRYPT</data_protection_kind>
        </topic_rule>
      </topic_access_rules>
    </domain_rule>
  </domain_access_rules>
</dds>
)";
}

std::string permissions_xml(const std::string& subject, const std::string& name, FleetRole role, std::uint32_t domain, int days) {
  const std::string d = std::to_string(domain);
  // Validity from the start of this year to `days` after: a robot's clock a little behind is no
  // reason to refuse its permissions.
  const std::time_t now = std::time(nullptr);
  std::tm utc{};
  gmtime_r(&now, &utc);
  const int year = utc.tm_year + 1900;
  const std::time_t end = now + static_cast<std::time_t>(days) * 86400;
  std::tm end_utc{};
  gmtime_r(&end, &end_utc);
  char until[32];
  std::strftime(until, sizeof until, "%Y-%m-%dT%H:%M:%S", &end_utc);
  const std::string publish = role == FleetRole::observer ? "" : "        <publish><topics><topic>*</topic></topics></publish>\n";
  return R"(<?xml version="1.0" encoding="UTF-8"?>
<!-- Made by `tripodal fleet keys` for )" +
         name + R"(. -->
<dds xmlns:xsi="http://www.w3.org/2001/XMLSchema-instance" xsi:noNamespaceSchemaLocation="http://www.omg.org/spec/DDS-SECURITY/20170901/omg_shared_ca_permissions.xsd">
  <permissions>
    <grant name=")" +
         name + R"(">
      <subject_name>)" +
         subject + R"(</subject_name>
      <validity><not_before>)" +
         std::to_string(year) + R"(-01-01T00:00:00</not_before><not_after>)" + until + R"(</not_after></validity>
      <allow_rule>
        <domains><id>)" +
         d + R"(</id></domains>
)" + publish +
         R"(        <subscribe><topics><topic>*</topic></topics></subscribe>
      </allow_rule>
      <default>DENY</default>
    </grant>
  </permissions>
</dds>
)";
}

}  // namespace

SecurityFiles fleet_identity(const fs::path& keys_dir, std::string_view identity) {
  const std::string name(identity);
  SecurityFiles f{keys_dir / "ca.pem", keys_dir / (name + ".pem"),  keys_dir / (name + "_key.pem"),
                  keys_dir / "ca.pem", keys_dir / "governance.p7s", keys_dir / (name + "_permissions.p7s")};
  std::string missing;
  for (const fs::path& p : {f.identity_ca, f.identity_certificate, f.private_key, f.governance, f.permissions}) {
    if (!fs::is_regular_file(p)) missing += (missing.empty() ? "" : ", ") + p.string();
  }
  if (!missing.empty()) {
    throw DdsError("dds security: identity '" + name + "' in " + keys_dir.string() + ": missing " + missing +
                   " (made by `tripodal fleet keys --out " + keys_dir.string() + " --robot " + name + "`)");
  }
  return f;
}

void make_fleet_keys(const FleetKeysOptions& o) {
  std::set<std::string> names;
  for (const auto& [name, role] : o.identities) {
    if (!is_ros_node_name(name)) {
      throw std::invalid_argument("fleet keys: '" + name +
                                  "' is not an identity name (letters, digits and '_', not starting with a digit)");
    }
    if (name == "ca" || name == "governance" || !names.insert(name).second) {
      throw std::invalid_argument("fleet keys: the identity '" + name +
                                  "' is given twice or is a reserved name (ca, governance)");
    }
  }
  if (o.valid_days <= 0) throw std::invalid_argument("fleet keys: the validity must be at least one day");
  fs::create_directories(o.out);
  for (const auto& [name, role] : o.identities) {
    if (fs::exists(o.out / (name + ".pem"))) {
      throw DdsError("fleet keys: " + (o.out / (name + ".pem")).string() +
                     " exists: an identity is not made twice (remove it first)");
    }
  }
  const std::string days = std::to_string(o.valid_days);
  if (!fs::exists(o.out / "ca.pem")) {
    openssl(o.out, {"ecparam", "-name", "prime256v1", "-genkey", "-noout", "-out", "ca_key.pem"});
    openssl(o.out, {"req", "-x509", "-new", "-key", "ca_key.pem", "-out", "ca.pem", "-days", std::to_string(o.valid_days * 10),
                    "-sha256", "-subj", "/CN=" + o.organisation + " CA/O=" + o.organisation});
    fs::permissions(o.out / "ca_key.pem", fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
  }
  write_file(o.out / "governance.xml", governance_xml(o.domain_id));
  openssl(o.out, {"smime", "-sign", "-in", "governance.xml", "-text", "-out", "governance.p7s", "-signer", "ca.pem", "-inkey",
                  "ca_key.pem"});
  for (const auto& [name, role] : o.identities) {
    openssl(o.out, {"ecparam", "-name", "prime256v1", "-genkey", "-noout", "-out", name + "_key.pem"});
    fs::permissions(o.out / (name + "_key.pem"), fs::perms::owner_read | fs::perms::owner_write, fs::perm_options::replace);
    openssl(o.out,
            {"req", "-new", "-key", name + "_key.pem", "-out", name + ".csr", "-subj", "/CN=" + name + "/O=" + o.organisation});
    openssl(o.out, {"x509", "-req", "-in", name + ".csr", "-CA", "ca.pem", "-CAkey", "ca_key.pem", "-CAcreateserial", "-out",
                    name + ".pem", "-days", days, "-sha256"});
    fs::remove(o.out / (name + ".csr"));
    // The subject as access control compares it: the certificate's, in RFC 4514 order.
    write_file(o.out / (name + "_permissions.xml"),
               permissions_xml("CN=" + name + ",O=" + o.organisation, name, role, o.domain_id, o.valid_days));
    openssl(o.out, {"smime", "-sign", "-in", name + "_permissions.xml", "-text", "-out", name + "_permissions.p7s", "-signer",
                    "ca.pem", "-inkey", "ca_key.pem"});
  }
}

fs::path security_plugin_dir() {
  if (const char* dir = std::getenv("TRIPODAL_DDS_SECURITY_DIR")) {
    if (fs::is_regular_file(fs::path(dir) / "libdds_security_auth.so")) return dir;
    throw DdsError(std::string("dds security: $TRIPODAL_DDS_SECURITY_DIR=") + dir + " has no libdds_security_auth.so");
  }
  for (const char* dir :
       {"/usr/lib/x86_64-linux-gnu/libddsc0debian", "/usr/lib/aarch64-linux-gnu/libddsc0debian",
        "/usr/lib/arm-linux-gnueabihf/libddsc0debian", "/usr/lib/x86_64-linux-gnu", "/usr/lib", "/usr/local/lib"}) {
    if (fs::is_regular_file(fs::path(dir) / "libdds_security_auth.so")) return dir;
  }
  throw DdsError(
      "dds security: Cyclone DDS's security plugins (libdds_security_auth.so) are not installed "
      "(Debian's libddsc0debian has them; or set $TRIPODAL_DDS_SECURITY_DIR)");
}

}  // namespace tripodal::dds
