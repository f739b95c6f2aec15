// Private to the dds area: a participant's place in the ROS 2 graph, the ros_discovery_info sample
// (rmw_dds_common/ParticipantEntitiesInfo) that names its node and the gids of its endpoints, kept
// up to date as endpoints come and go. Shared by the participant and its endpoints, so that an
// endpoint that outlives its participant (a misuse) finds it closed rather than dangling.
#pragma once

#include <dds/dds.h>

#include <map>
#include <mutex>
#include <optional>
#include <string>

#include "tripodal/dds/messages.hpp"

namespace tripodal::dds::detail {

msg::Gid gid_of(dds_entity_t entity);

class NodeGraph {
 public:
  explicit NodeGraph(dds_entity_t participant);
  NodeGraph(const NodeGraph&) = delete;
  NodeGraph& operator=(const NodeGraph&) = delete;

  // Creates the ros_discovery_info writer (once) and publishes the node.
  void declare(std::string ns, std::string name);
  void add(dds_entity_t endpoint, bool reader);
  void remove(dds_entity_t endpoint) noexcept;
  // With the participant: no more writes.
  void close() noexcept;
  [[nodiscard]] const msg::Gid& participant_gid() const noexcept { return gid_; }
  [[nodiscard]] msg::ParticipantEntitiesInfo info() const;

 private:
  void publish_locked();
  [[nodiscard]] msg::ParticipantEntitiesInfo info_locked() const;

  mutable std::mutex mutex_;
  dds_entity_t participant_ = 0;
  dds_entity_t topic_ = 0;
  dds_entity_t writer_ = 0;
  msg::Gid gid_{};
  std::optional<std::pair<std::string, std::string>> node_;  // namespace, name
  std::map<dds_entity_t, msg::Gid> readers_, writers_;
};

}  // namespace tripodal::dds::detail
