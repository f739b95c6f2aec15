// Participants and the Cyclone DDS domains they share within a process.
#include "tripodal/dds/participant.hpp"

#include <dds/dds.h>

#include <map>
#include <mutex>
#include <string>

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
  handle_ = dds_create_participant(options.domain_id, nullptr, nullptr);
  detail::check(handle_, where + ": dds_create_participant");
}

Participant::~Participant() {
  if (handle_ > 0) dds_delete(handle_);
  // The domain (and Cyclone's threads and sockets for it) goes with its last participant.
  std::lock_guard lock(domains_mutex);
  domain_.reset();
}

}  // namespace tripodal::dds
