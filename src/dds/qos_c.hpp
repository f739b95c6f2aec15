// Private to the dds area: a Qos as Cyclone DDS's dds_qos_t, and the return-code check of every call.
#pragma once

#include <dds/dds.h>

#include <memory>
#include <string_view>

#include "tripodal/dds/qos.hpp"

namespace tripodal::dds::detail {

struct QosDeleter {
  void operator()(dds_qos_t* q) const noexcept { dds_delete_qos(q); }
};
using QosPtr = std::unique_ptr<dds_qos_t, QosDeleter>;

// Also fixes the data representation to XCDR1, the one ROS 2 (rmw_cyclonedds) writes and reads.
QosPtr to_dds_qos(const Qos& qos);

// Throws DdsError "<what>: <Cyclone's error text> (<code>)" when rc is negative; returns rc.
dds_return_t check(dds_return_t rc, std::string_view what);

}  // namespace tripodal::dds::detail
