// Typed DDS publishers and subscribers of tripodal's messages, with their status (a silent peer,
// a missed deadline) reported as callbacks (tripodal::dds area; docs/distribution.md).
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/dds/messages.hpp"
#include "tripodal/dds/participant.hpp"
#include "tripodal/dds/qos.hpp"

namespace tripodal::dds {

// The DDS topic name of a ROS 2 topic: "rt/" + namespace + name ("cmd_vel", "robot1" ->
// "rt/robot1/cmd_vel"). A leading '/' of either is dropped; an empty namespace is none.
std::string ros_topic(std::string_view name, std::string_view ns = {});

// A change of an endpoint's status that a robot may turn into an event or a fault.
enum class StatusKind {
  liveliness_lost,       // subscriber: a matched publisher went silent beyond its lease (or left)
  liveliness_regained,   // subscriber: a publisher is alive (again)
  deadline_missed,       // subscriber: no sample within the deadline; publisher: none written
  publication_matched,   // subscriber: a publisher appeared or left (see current_count)
  subscription_matched,  // publisher: a subscriber appeared or left
  own_liveliness_lost,   // publisher of manual liveliness: it did not assert within its lease
};
std::string_view to_string(StatusKind kind);

struct StatusEvent {
  StatusKind kind;
  std::string topic;
  std::int32_t total_count = 0;    // how often this status changed since the endpoint was created
  std::int32_t current_count = 0;  // alive publishers, matched peers (0 for deadlines)
  std::chrono::steady_clock::time_point at;
};

// Called on a Cyclone DDS thread: keep it short and thread-safe (post to the robot's queue).
using StatusCallback = std::function<void(const StatusEvent&)>;

struct EndpointOptions {
  TopicKind kind = TopicKind::state;
  std::optional<Qos> qos;  // unset: qos_for(kind, role)
  StatusCallback on_status;
};

namespace detail {
struct EndpointCore;  // the Cyclone entities, listener and type support of one endpoint
}

template <Message T>
class Publisher {
 public:
  Publisher(Participant& participant, const std::string& topic, const EndpointOptions& options = {});
  ~Publisher();
  Publisher(Publisher&&) noexcept;
  Publisher& operator=(Publisher&&) noexcept;

  void publish(const T& message);
  // For manual_by_topic liveliness: "alive" without data.
  void assert_liveliness();
  // Waits until every matched reliable subscriber acknowledged what was published (before a
  // process exits, say); false on timeout.
  bool wait_for_acknowledgments(std::chrono::milliseconds timeout);
  std::size_t matched_subscribers() const;
  // Waits until at least `count` subscribers matched; false on timeout.
  bool wait_for_subscribers(std::size_t count, std::chrono::milliseconds timeout) const;
  const std::string& topic() const noexcept;
  const Qos& qos() const noexcept;
  // The writer's GUID (ROS 2's gid: what ros_discovery_info lists for its node).
  msg::Gid gid() const;

 private:
  std::unique_ptr<detail::EndpointCore> core_;
};

template <Message T>
class Subscriber {
 public:
  // With on_data, every sample is handed to it on a Cyclone DDS thread as it arrives, and take()
  // finds nothing; without, samples wait in the reader's history (qos depth) for take().
  using DataCallback = std::function<void(const T&)>;
  Subscriber(Participant& participant, const std::string& topic, const EndpointOptions& options = {},
             DataCallback on_data = {});
  ~Subscriber();
  Subscriber(Subscriber&&) noexcept;
  Subscriber& operator=(Subscriber&&) noexcept;

  std::vector<T> take(std::size_t max = 64);
  // The next sample, waiting up to timeout for one.
  std::optional<T> take_one(std::chrono::milliseconds timeout);
  // The samples as they travelled: CDR with its 4-byte encapsulation header (00 01 00 00 for
  // XCDR1 little-endian), for recording and for checking the wire format.
  std::vector<std::vector<std::uint8_t>> take_serialized(std::size_t max = 64);
  std::size_t matched_publishers() const;
  bool wait_for_publishers(std::size_t count, std::chrono::milliseconds timeout) const;
  const std::string& topic() const noexcept;
  const Qos& qos() const noexcept;
  // The reader's GUID (ROS 2's gid).
  msg::Gid gid() const;

 private:
  std::unique_ptr<detail::EndpointCore> core_;
};

#define TRIPODAL_DDS_EXTERN(Type)                  \
  extern template class Publisher<msg::Type>;  \
  extern template class Subscriber<msg::Type>
TRIPODAL_DDS_EXTERN(String);
TRIPODAL_DDS_EXTERN(Twist);
TRIPODAL_DDS_EXTERN(PoseWithCovarianceStamped);
TRIPODAL_DDS_EXTERN(Odometry);
TRIPODAL_DDS_EXTERN(OccupancyGrid);
TRIPODAL_DDS_EXTERN(LaserScan);
TRIPODAL_DDS_EXTERN(JointState);
TRIPODAL_DDS_EXTERN(Clock);
TRIPODAL_DDS_EXTERN(TFMessage);
TRIPODAL_DDS_EXTERN(Imu);
TRIPODAL_DDS_EXTERN(ParticipantEntitiesInfo);
TRIPODAL_DDS_EXTERN(Event);
TRIPODAL_DDS_EXTERN(TaskCommand);
TRIPODAL_DDS_EXTERN(SimStep);
TRIPODAL_DDS_EXTERN(SimState);
#undef TRIPODAL_DDS_EXTERN

}  // namespace tripodal::dds
