// Quality of service of tripodal's DDS topics, chosen per kind of data (tripodal::dds area;
// docs/distribution.md has the table and why each kind gets what it gets).
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string_view>

namespace tripodal::dds {

// What a topic carries decides how it is delivered.
enum class TopicKind {
  command,  // cmd_vel, task commands: reliable, the last one kept for a late reader
  event,    // faults, life cycle: reliable, a history kept for a late reader
  map,      // occupancy grids: reliable, the last one kept (as ROS 2's map_server latches)
  state,    // odometry, poses: reliable, volatile (ROS 2's default profile)
  scan,     // laser scans: best effort, volatile (ROS 2's sensor-data profile): late is useless
};

enum class Reliability { best_effort, reliable };
enum class Durability { volatile_, transient_local };
// automatic: the peer's participant proves it alive; manual_by_topic: only a write or
// Publisher::assert_liveliness does, so a stuck loop that no longer publishes is seen as silent.
enum class Liveliness { automatic, manual_by_topic };

struct Qos {
  Reliability reliability = Reliability::reliable;
  Durability durability = Durability::volatile_;
  std::int32_t depth = 10;  // keep-last history depth
  // Unset: infinite. A reader's deadline is the longest it accepts between two samples; a
  // writer's what it promises. A reader matches only writers that promise at least as often.
  std::optional<std::chrono::nanoseconds> deadline;
  Liveliness liveliness = Liveliness::automatic;
  // Unset: infinite. A reader's lease is the longest silence it accepts; a writer's, its promise.
  std::optional<std::chrono::nanoseconds> lease;
};

enum class Role { publisher, subscriber };

// The QoS of a kind for a role. Readers of command topics ask for volatile durability so that they
// also match ROS 2 publishers (teleop, Nav2), which offer volatile; everything else is symmetric.
Qos qos_for(TopicKind kind, Role role);

std::string_view to_string(TopicKind kind);

}  // namespace tripodal::dds
