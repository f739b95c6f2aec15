// A resource that detects faults of its own beyond staleness (a DDS peer declared silent, a link
// lost) and the queue a driver keeps them in (resources area). The robot takes them each period of
// its sequencing loop and reports each as the resource's fault: CProcessSupervisor::
// report_module_fault(resource, reason), the event "<resource>.fault" (docs/processes.md).
#pragma once

#include <mutex>
#include <string>
#include <utility>
#include <vector>

namespace tripodal {

/// Implemented beside CResource by a driver whose faults come from another thread or protocol.
class ResourceFaultSource {
 public:
  virtual ~ResourceFaultSource() = default;
  ResourceFaultSource() = default;
  ResourceFaultSource(const ResourceFaultSource&) = delete;
  ResourceFaultSource& operator=(const ResourceFaultSource&) = delete;
  /// The faults detected since the last call, oldest first. Thread-safe.
  [[nodiscard]] virtual std::vector<std::string> take_faults() = 0;
};

/// Faults reported on a driver's thread (a middleware's callback), taken on the robot's.
class ResourceFaultQueue {
 public:
  void report(std::string reason) {
    std::lock_guard lock(mutex_);
    faults_.push_back(std::move(reason));
  }
  [[nodiscard]] std::vector<std::string> take() {
    std::lock_guard lock(mutex_);
    return std::exchange(faults_, {});
  }

 private:
  std::mutex mutex_;
  std::vector<std::string> faults_;
};

}  // namespace tripodal
