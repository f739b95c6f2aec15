// Participants and the Cyclone DDS domains they share within a process.
#include "tripodal/dds/participant.hpp"

#include <dds/dds.h>

#include <algorithm>
#include <filesystem>
#include <map>
#include <mutex>
#include <stdexcept>
#include <string>

#include "node_graph.hpp"
#include "qos_c.hpp"

namespace tripodal::dds {

std::string loopback_config(const ParticipantOptions& options) {
  // Discovery goes by unicast to the participant indices of 127.0.0.1 (multicast is off, so
  // nothing, not even discovery, reaches another host); Domain Id="any" applies it to the domain
  // the participant is created in.
  const auto lease_ms = std::to_string(options.participant_lease.count());
  return "<CycloneDDS><Domain Id=\"any\">"
         "<General>"
         "<Interfaces><NetworkInterface address=\"127.0.0.1\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast>"
         "</General>"
         "<Discovery>"
         "<ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>" + std::to_string(options.max_participants) + "</MaxAutoParticipantIndex>"
         "<Peers><Peer address=\"127.0.0.1\"/></Peers>"
         "<LeaseDuration>" + lease_ms + " ms</LeaseDuration>"
         "</Discovery>"
         "</Domain></CycloneDDS>";
}

// Deleted with its last participant.
struct detail::Domain {
  std::uint32_t id = 0;
  std::string config;
  dds_entity_t handle = 0;
  Domain() = default;
  Domain(const Domain&) = delete;
  Domain& operator=(const Domain&) = delete;
  ~Domain() {
    if (handle > 0) dds_delete(handle);
  }
};

namespace {
// The OMG DDS Security plugins and the identity's files, as participant QoS properties (Cyclone
// DDS reads "dds.sec.*"); the files are checked first so a missing one is named, not Cyclone's
// "Error".
void apply_security(dds_qos_t* qos, const SecurityFiles& f, const std::string& where) {
  for (const auto& p : {f.identity_ca, f.identity_certificate, f.private_key, f.permissions_ca, f.governance, f.permissions}) {
    if (!std::filesystem::is_regular_file(p)) throw DdsError(where + ": security file " + p.string() + " does not exist");
  }
  if (!f.crl.empty() && !std::filesystem::is_regular_file(f.crl)) {
    throw DdsError(where + ": security file " + f.crl.string() + " (the revocation list) does not exist");
  }
  // Cyclone says only "Error" of a malformed document: its place first.
  check_security_document(f.governance, false);
  check_security_document(f.permissions, true);
  const std::filesystem::path lib = security_plugin_dir();
  const auto file = [](const std::filesystem::path& p) { return "file:" + std::filesystem::absolute(p).string(); };
  const std::pair<const char*, std::string> props[] = {
      {"dds.sec.auth.library.path", (lib / "libdds_security_auth.so").string()},
      {"dds.sec.auth.library.init", "init_authentication"},
      {"dds.sec.auth.library.finalize", "finalize_authentication"},
      {"dds.sec.crypto.library.path", (lib / "libdds_security_crypto.so").string()},
      {"dds.sec.crypto.library.init", "init_crypto"},
      {"dds.sec.crypto.library.finalize", "finalize_crypto"},
      {"dds.sec.access.library.path", (lib / "libdds_security_ac.so").string()},
      {"dds.sec.access.library.init", "init_access_control"},
      {"dds.sec.access.library.finalize", "finalize_access_control"},
      {"dds.sec.auth.identity_ca", file(f.identity_ca)},
      {"dds.sec.auth.identity_certificate", file(f.identity_certificate)},
      {"dds.sec.auth.private_key", file(f.private_key)},
      {"dds.sec.access.permissions_ca", file(f.permissions_ca)},
      {"dds.sec.access.governance", file(f.governance)},
      {"dds.sec.access.permissions", file(f.permissions)},
  };
  for (const auto& [name, value] : props) dds_qset_prop(qos, name, value.c_str());
  // Cyclone DDS 0.10's authentication takes a CRL under its own name (not in the OMG spec).
  if (!f.crl.empty()) dds_qset_prop(qos, "org.eclipse.cyclonedds.sec.auth.crl", file(f.crl).c_str());
}

std::mutex domains_mutex;
std::map<std::uint32_t, std::weak_ptr<detail::Domain>>& domains() {
  static std::map<std::uint32_t, std::weak_ptr<detail::Domain>> registry;
  return registry;
}
}  // namespace

Participant::Participant(const ParticipantOptions& options) : options_(options) {
  const std::string where = "dds: participant of domain " + std::to_string(options.domain_id);
  if (options.domain_id > 232) {
    throw DdsError(where + ": the domain id must be in 0..232 (its UDP ports are 7400 + 250 * id + ...)");
  }
  if (options.network == Network::loopback) {
    const std::string config = loopback_config(options);
    std::lock_guard lock(domains_mutex);
    auto& slot = domains()[options.domain_id];
    domain_ = slot.lock();
    if (domain_ && domain_->config != config) {
      throw DdsError(where + ": this process already has the domain with another configuration "
                     "(network, participant_lease or max_participants differ)");
    }
    if (!domain_) {
      auto created = std::make_shared<detail::Domain>();
      created->id = options.domain_id;
      created->config = config;
      created->handle = dds_create_domain(options.domain_id, config.c_str());
      if (created->handle < 0) {
        const dds_return_t rc = created->handle;
        created->handle = 0;
        if (rc == DDS_RETCODE_PRECONDITION_NOT_MET) {
          throw DdsError(where + ": the domain already exists in this process with Cyclone DDS's default "
                         "configuration (a participant of Network::system came first)");
        }
        detail::check(rc, where + ": dds_create_domain with the loopback configuration");
      }
      domain_ = created;
      slot = created;
    }
  }
  // rmw's user data: the security enclave of the participant's nodes, "/" without security.
  const detail::QosPtr qos(dds_create_qos());
  static constexpr std::string_view kEnclave = "enclave=/;";
  dds_qset_userdata(qos.get(), kEnclave.data(), kEnclave.size());
  if (options.security) apply_security(qos.get(), *options.security, where);
  handle_ = dds_create_participant(options.domain_id, qos.get(), nullptr);
  detail::check(handle_, where + ": dds_create_participant");
  graph_ = std::make_shared<detail::NodeGraph>(handle_);
}

Participant::~Participant() {
  if (graph_) graph_->close();
  if (handle_ > 0) dds_delete(handle_);
  // The domain (and Cyclone's threads and sockets for it) goes with its last participant.
  std::lock_guard lock(domains_mutex);
  domain_.reset();
}

bool is_ros_node_name(std::string_view name) noexcept {
  if (name.empty() || name.size() > 255 || (name.front() >= '0' && name.front() <= '9')) return false;
  return std::all_of(name.begin(), name.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_';
  });
}

msg::Gid Participant::gid() const noexcept { return graph_->participant_gid(); }

void Participant::declare_node(std::string_view name, std::string_view ns) {
  if (!is_ros_node_name(name)) {
    throw std::invalid_argument("dds: '" + std::string(name) + "' is not a ROS 2 node name (letters, digits and '_', "
                                "not starting with a digit, at most 255 characters)");
  }
  while (!ns.empty() && ns.back() == '/') ns.remove_suffix(1);
  while (!ns.empty() && ns.front() == '/') ns.remove_prefix(1);
  const std::string full_ns = "/" + std::string(ns);
  std::size_t start = 1;
  while (start < full_ns.size()) {  // each part of a/b must be a name
    const std::size_t end = std::min(full_ns.find('/', start), full_ns.size());
    if (!is_ros_node_name(std::string_view(full_ns).substr(start, end - start)) || full_ns.size() > 256) {
      throw std::invalid_argument("dds: '" + full_ns + "' is not a ROS 2 namespace (names of letters, digits and '_', "
                                  "separated by '/', at most 256 characters)");
    }
    start = end + 1;
  }
  graph_->declare(full_ns, std::string(name));
}

msg::ParticipantEntitiesInfo Participant::graph_info() const { return graph_->info(); }

}  // namespace tripodal::dds
