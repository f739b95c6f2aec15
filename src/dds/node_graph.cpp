// The ros_discovery_info of a participant: how ROS 2's tools learn which nodes a process holds.
#include "node_graph.hpp"

#include "qos_c.hpp"
#include "tripodal/dds/participant.hpp"
#include "type_support.hpp"

namespace tripodal::dds::detail {

msg::Gid gid_of(dds_entity_t entity) {
  dds_guid_t guid{};
  check(dds_get_guid(entity, &guid), "dds: dds_get_guid");
  msg::Gid g{};
  std::copy(std::begin(guid.v), std::end(guid.v), g.begin());
  return g;
}

NodeGraph::NodeGraph(dds_entity_t participant) : participant_(participant), gid_(gid_of(participant)) {}

void NodeGraph::declare(std::string ns, std::string name) {
  std::lock_guard lock(mutex_);
  if (participant_ == 0) return;
  if (writer_ == 0) {
    // As rmw writes it: reliable, transient local, the last sample only (a late tool gets it).
    topic_ = dds_create_topic(participant_, TypeSupport<msg::ParticipantEntitiesInfo>::descriptor(), "ros_discovery_info",
                              nullptr, nullptr);
    check(topic_, "dds: dds_create_topic of ros_discovery_info");
    const auto qos = to_dds_qos(Qos{Reliability::reliable, Durability::transient_local, 1, {}, Liveliness::automatic, {}});
    writer_ = dds_create_writer(participant_, topic_, qos.get(), nullptr);
    check(writer_, "dds: dds_create_writer of ros_discovery_info");
  }
  node_ = std::pair{std::move(ns), std::move(name)};
  publish_locked();
}

void NodeGraph::add(dds_entity_t endpoint, bool reader) {
  const msg::Gid g = gid_of(endpoint);
  std::lock_guard lock(mutex_);
  (reader ? readers_ : writers_)[endpoint] = g;
  if (node_) publish_locked();
}

void NodeGraph::remove(dds_entity_t endpoint) noexcept {
  std::lock_guard lock(mutex_);
  const bool erased = readers_.erase(endpoint) + writers_.erase(endpoint) > 0;
  if (erased && node_) {
    try {
      publish_locked();
    } catch (const tripodal::dds::DdsError&) {
      // the graph is told again at the next change; a destructor does not throw
    }
  }
}

void NodeGraph::close() noexcept {
  std::lock_guard lock(mutex_);
  participant_ = topic_ = writer_ = 0;  // deleted with the participant
}

msg::ParticipantEntitiesInfo NodeGraph::info() const {
  std::lock_guard lock(mutex_);
  return info_locked();
}

msg::ParticipantEntitiesInfo NodeGraph::info_locked() const {
  msg::ParticipantEntitiesInfo m;
  m.gid = gid_;
  if (node_) {
    msg::NodeEntitiesInfo n{node_->first, node_->second, {}, {}};
    for (const auto& [e, g] : readers_) n.reader_gid_seq.push_back(g);
    for (const auto& [e, g] : writers_) n.writer_gid_seq.push_back(g);
    m.node_entities_info_seq.push_back(std::move(n));
  }
  return m;
}

void NodeGraph::publish_locked() {
  if (writer_ == 0) return;
  const msg::ParticipantEntitiesInfo m = info_locked();
  TypeSupport<msg::ParticipantEntitiesInfo>::Scratch scratch;
  const auto sample = TypeSupport<msg::ParticipantEntitiesInfo>::to_c(m, scratch);
  check(dds_write(writer_, &sample), "dds: dds_write on ros_discovery_info");
}

}  // namespace tripodal::dds::detail
