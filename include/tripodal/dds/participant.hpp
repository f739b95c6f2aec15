// A DDS domain participant on Cyclone DDS, the root of every publisher and subscriber of a process
// (tripodal::dds area; docs/distribution.md, "Network and domains").
#pragma once

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "tripodal/dds/messages.hpp"
#include "tripodal/dds/security.hpp"

namespace tripodal::dds {

// Any failure of the DDS layer: the message names the operation, the topic or domain, and Cyclone
// DDS's return code.
class DdsError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

enum class Network {
  loopback,  // 127.0.0.1 only, unicast discovery: nothing leaves the host (tests, one-machine fleets)
  system,    // Cyclone DDS's own choice (CYCLONEDDS_URI or its defaults): to reach other machines
};

struct ParticipantOptions {
  std::uint32_t domain_id = 0;  // ROS 2's ROS_DOMAIN_ID; 0..232 (UDP ports 7400 + 250 * id + ...)
  Network network = Network::loopback;
  // How long a peer process may stay silent before its participant, and with it every writer of
  // automatic liveliness, is declared gone (Cyclone's Discovery/LeaseDuration; its default is 10 s).
  std::chrono::milliseconds participant_lease{std::chrono::seconds(10)};
  // Participants discovered per host on loopback (Discovery/MaxAutoParticipantIndex).
  std::uint32_t max_participants = 32;
  // DDS Security (security.hpp): the identity's files; unset, the participant is not secured
  // (and a secured fleet will not talk to it).
  std::optional<SecurityFiles> security;
};

namespace detail {
struct Domain;     // a Cyclone domain created with our configuration, shared by its participants
class NodeGraph;   // the participant's ros_discovery_info
}

// Whether ROS 2 accepts `name` as a node name: letters, digits and '_', not starting with a digit,
// at most 255 characters.
bool is_ros_node_name(std::string_view name) noexcept;

// The Cyclone DDS XML configuration of a loopback participant: the loopback interface only,
// multicast off, unicast discovery of the participants of this host. Exposed for the documentation
// and the tests; Participant applies it.
std::string loopback_config(const ParticipantOptions& options);

// One participant of a domain. Participants of the same process and domain share one Cyclone
// domain (and its configuration; a second participant with a different network or lease is an
// error). Not copyable nor movable: publishers and subscribers keep a reference to it and must
// be destroyed before it.
class Participant {
 public:
  explicit Participant(const ParticipantOptions& options = {});
  ~Participant();
  Participant(const Participant&) = delete;
  Participant& operator=(const Participant&) = delete;

  std::uint32_t domain_id() const noexcept { return options_.domain_id; }
  const ParticipantOptions& options() const noexcept { return options_; }
  // Cyclone's entity handle (dds_entity_t), for the transport's own use.
  std::int32_t handle() const noexcept { return handle_; }
  // The participant's GUID, which ROS 2 calls its gid.
  msg::Gid gid() const noexcept;

  // Makes this participant a ROS 2 node (`ros2 node list` shows "<ns>/<name>"): as rmw does, it
  // publishes rmw_dds_common/ParticipantEntitiesInfo on the DDS topic "ros_discovery_info"
  // (reliable, transient local, keep last 1) with the node and the gids of every reader and
  // writer of the participant, again whenever one is created or deleted. Called again: renames.
  // `ns` is "/" or "/a/b" ("" and "a/b" are taken as "/" and "/a/b"). Throws std::invalid_argument
  // naming the bad name, DdsError when the writer cannot be created.
  void declare_node(std::string_view name, std::string_view ns = "/");
  // What the participant publishes on ros_discovery_info (no node until declare_node).
  msg::ParticipantEntitiesInfo graph_info() const;
  // For the endpoints, which register with it.
  const std::shared_ptr<detail::NodeGraph>& graph() const noexcept { return graph_; }

 private:
  ParticipantOptions options_;
  std::shared_ptr<detail::Domain> domain_;
  std::shared_ptr<detail::NodeGraph> graph_;
  std::int32_t handle_ = 0;
};

}  // namespace tripodal::dds
