// QoS per kind of topic, and its translation to Cyclone DDS.
#include <string>

#include "qos_c.hpp"
#include "tripodal/dds/participant.hpp"

namespace tripodal::dds {

Qos qos_for(TopicKind kind, Role role) {
  Qos q;
  switch (kind) {
    case TopicKind::command:
      q.reliability = Reliability::reliable;
      // A late reader of ours gets the last command from a writer of ours; a reader asks for
      // volatile only, so that it matches the volatile publishers of ROS 2 tools too.
      q.durability = role == Role::publisher ? Durability::transient_local : Durability::volatile_;
      q.depth = 1;
      break;
    case TopicKind::event:
      q.reliability = Reliability::reliable;
      q.durability = Durability::transient_local;
      q.depth = 100;
      break;
    case TopicKind::map:
      q.reliability = Reliability::reliable;
      q.durability = Durability::transient_local;
      q.depth = 1;
      break;
    case TopicKind::state:
      q.reliability = Reliability::reliable;
      q.durability = Durability::volatile_;
      q.depth = 10;
      break;
    case TopicKind::scan:
      q.reliability = Reliability::best_effort;
      q.durability = Durability::volatile_;
      q.depth = 5;
      break;
  }
  return q;
}

std::string_view to_string(TopicKind kind) {
  switch (kind) {
    case TopicKind::command: return "command";
    case TopicKind::event: return "event";
    case TopicKind::map: return "map";
    case TopicKind::state: return "state";
    case TopicKind::scan: return "scan";
  }
  return "?";
}

namespace detail {

QosPtr to_dds_qos(const Qos& qos) {
  QosPtr q(dds_create_qos());
  if (!q) throw DdsError("dds: dds_create_qos failed (out of memory)");
  // A reliable writer blocks at most this long on a full history of a slow reader.
  dds_qset_reliability(q.get(),
                       qos.reliability == Reliability::reliable ? DDS_RELIABILITY_RELIABLE
                                                                : DDS_RELIABILITY_BEST_EFFORT,
                       DDS_MSECS(100));
  dds_qset_durability(q.get(), qos.durability == Durability::transient_local ? DDS_DURABILITY_TRANSIENT_LOCAL
                                                                              : DDS_DURABILITY_VOLATILE);
  dds_qset_history(q.get(), DDS_HISTORY_KEEP_LAST, qos.depth);
  if (qos.deadline) dds_qset_deadline(q.get(), qos.deadline->count());
  dds_qset_liveliness(q.get(),
                      qos.liveliness == Liveliness::automatic ? DDS_LIVELINESS_AUTOMATIC
                                                              : DDS_LIVELINESS_MANUAL_BY_TOPIC,
                      qos.lease ? qos.lease->count() : DDS_INFINITY);
  const dds_data_representation_id_t xcdr1 = DDS_DATA_REPRESENTATION_XCDR1;
  dds_qset_data_representation(q.get(), 1, &xcdr1);
  return q;
}

dds_return_t check(dds_return_t rc, std::string_view what) {
  if (rc < 0) {
    throw DdsError(std::string(what) + ": " + dds_strretcode(rc) + " (" + std::to_string(rc) + ")");
  }
  return rc;
}

}  // namespace detail
}  // namespace tripodal::dds
