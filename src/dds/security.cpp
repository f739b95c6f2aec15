#include "tripodal/dds/security.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <tinyxml2.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <fstream>
#include <iterator>
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
  if (fs::is_regular_file(keys_dir / "crl.pem")) f.crl = keys_dir / "crl.pem";
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

void revoke_fleet_identity(const fs::path& keys_dir, std::string_view identity) {
  const std::string name(identity);
  const fs::path cert = keys_dir / (name + ".pem");
  if (!fs::is_regular_file(keys_dir / "ca_key.pem")) {
    throw DdsError("fleet keys: " + (keys_dir / "ca_key.pem").string() + " does not exist: revoking needs the CA's key");
  }
  if (!fs::is_regular_file(cert))
    throw DdsError("fleet keys: " + cert.string() + " does not exist: no identity '" + name + "' to revoke");
  // openssl ca's database: the revoked serials, from which each list is made.
  const fs::path db = keys_dir / "ca_db";
  fs::create_directories(db);
  if (!fs::exists(db / "index.txt")) write_file(db / "index.txt", "");
  if (!fs::exists(db / "crlnumber")) write_file(db / "crlnumber", "01\n");
  write_file(db / "ca.cnf",
             "# Made by tripodal fleet keys --revoke: the CA's database for its revocation list.\n"
             "[ca]\ndefault_ca = fleet\n[fleet]\ndatabase = ca_db/index.txt\ncrlnumber = ca_db/crlnumber\n"
             "certificate = ca.pem\nprivate_key = ca_key.pem\nnew_certs_dir = ca_db\ndefault_md = sha256\n"
             "default_crl_days = 3650\npolicy = any\n[any]\ncommonName = supplied\norganizationName = optional\n");
  openssl(keys_dir, {"ca", "-config", "ca_db/ca.cnf", "-revoke", name + ".pem"});
  openssl(keys_dir, {"ca", "-config", "ca_db/ca.cnf", "-gencrl", "-out", "crl.pem"});
}

namespace {

// The signed document's XML and the line of the file it starts on (S/MIME "-text": MIME headers,
// then the text part's headers, a blank line, the document).
struct SignedText {
  std::string xml;
  int first_line = 1;
};

std::string located(const fs::path& file, int line, const std::string& what) {
  return file.string() + ":" + std::to_string(line) + ": error: " + what;
}

bool parse_date(const char* text) {
  if (text == nullptr) return false;
  std::tm tm{};
  const char* end = strptime(text, "%Y-%m-%dT%H:%M:%S", &tm);
  return end != nullptr && (*end == '\0' || *end == 'Z' || *end == '+' || *end == '-' || *end == '.');
}

std::time_t utc_time(const char* text) {
  std::tm tm{};
  strptime(text, "%Y-%m-%dT%H:%M:%S", &tm);
  return timegm(&tm);
}

}  // namespace

void check_security_document(const fs::path& file, bool permissions) {
  std::ifstream in(file, std::ios::binary);
  if (!in) throw DdsError(file.string() + ": error: cannot be read");
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const char* kind = permissions ? "permissions" : "governance";
  if (text.rfind("MIME-Version:", 0) != 0 || text.find("application/x-pkcs7-signature") == std::string::npos) {
    throw DdsError(located(file, 1,
                           std::string("the ") + kind +
                               " document is not signed S/MIME: sign it with the permissions CA (`openssl smime -sign -text "
                               "-signer ca.pem -inkey ca_key.pem`, as `tripodal fleet-keys` does)"));
  }
  SignedText doc;
  const std::size_t start = text.find("<?xml") != std::string::npos ? text.find("<?xml") : text.find("<dds");
  if (start == std::string::npos)
    throw DdsError(located(file, 1, std::string("no XML document inside the signed ") + kind + " file"));
  const std::size_t end = text.find("</dds>", start);
  doc.xml = text.substr(start, end == std::string::npos ? std::string::npos : end + 6 - start);
  doc.first_line = 1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(start), '\n'));
  tinyxml2::XMLDocument x;
  if (x.Parse(doc.xml.c_str(), doc.xml.size()) != tinyxml2::XML_SUCCESS) {
    throw DdsError(located(file, doc.first_line + std::max(x.ErrorLineNum(), 1) - 1,
                           std::string("the ") + kind + " XML is not well formed: " + x.ErrorStr()));
  }
  std::vector<std::string> errors;
  const auto line_of = [&](const tinyxml2::XMLElement* e) { return doc.first_line + e->GetLineNum() - 1; };
  const auto need = [&](const tinyxml2::XMLElement* parent, const char* child) -> const tinyxml2::XMLElement* {
    const tinyxml2::XMLElement* e = parent->FirstChildElement(child);
    if (e == nullptr)
      errors.push_back(located(file, line_of(parent), "<" + std::string(parent->Name()) + "> has no <" + child + ">"));
    return e;
  };
  const tinyxml2::XMLElement* root = x.RootElement();
  if (root == nullptr || std::string(root->Name()) != "dds") {
    throw DdsError(located(file, root != nullptr ? line_of(root) : doc.first_line,
                           std::string("the ") + kind + " document's root must be <dds>"));
  }
  if (!permissions) {
    if (const auto* rules = need(root, "domain_access_rules")) {
      if (rules->FirstChildElement("domain_rule") == nullptr)
        errors.push_back(located(file, line_of(rules), "<domain_access_rules> has no <domain_rule>"));
    }
  } else if (const auto* perms = need(root, "permissions")) {
    if (perms->FirstChildElement("grant") == nullptr)
      errors.push_back(located(file, line_of(perms), "<permissions> has no <grant>"));
    for (const auto* g = perms->FirstChildElement("grant"); g != nullptr; g = g->NextSiblingElement("grant")) {
      if (g->Attribute("name") == nullptr) errors.push_back(located(file, line_of(g), "<grant> has no name attribute"));
      if (const auto* subject = need(g, "subject_name"); subject != nullptr && (subject->GetText() == nullptr)) {
        errors.push_back(located(file, line_of(subject),
                                 "<subject_name> is empty: the certificate's subject, e.g. CN=robot1,O=tripodal fleet"));
      }
      if (const auto* v = need(g, "validity")) {
        for (const char* bound : {"not_before", "not_after"}) {
          const auto* b = need(v, bound);
          if (b == nullptr) continue;
          if (!parse_date(b->GetText())) {
            errors.push_back(located(
                file, line_of(b),
                "<" + std::string(bound) + "> '" + (b->GetText() ? b->GetText() : "") + "' is not a date YYYY-MM-DDTHH:MM:SS"));
          } else if (std::string(bound) == "not_after" && utc_time(b->GetText()) < std::time(nullptr)) {
            errors.push_back(located(file, line_of(b), std::string("the permissions expired on ") + b->GetText() + " (UTC)"));
          }
        }
      }
      if (g->FirstChildElement("allow_rule") == nullptr && g->FirstChildElement("deny_rule") == nullptr) {
        errors.push_back(located(file, line_of(g), "<grant> has neither <allow_rule> nor <deny_rule>"));
      }
      if (const auto* d = need(g, "default"); d != nullptr && d->GetText() != nullptr) {
        const std::string v = d->GetText();
        if (v != "ALLOW" && v != "DENY")
          errors.push_back(located(file, line_of(d), "<default> is '" + v + "': expected ALLOW or DENY"));
      }
    }
  }
  if (!errors.empty()) {
    std::string all;
    for (const std::string& e : errors) all += (all.empty() ? "" : "\n") + e;
    throw DdsError(all);
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
