// Internal (monitor area): the operator requests that reach the robot's HRI — the RKMS
// administration (rkms.list, rkms.get, rkms.add, rkms.edit, rkms.delete, rkms.history) and the
// touch screen (touch, ask). RobotMonitor hands them over on the robot's thread, read and checked
// already (operator_request.hpp); the store's rules are the hri area's (KnowledgeStore), this file
// only turns typed requests into calls and the results into JSON.
#pragma once

#include <functional>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "tripodal/hri/hri_service.hpp"
#include "operator_request.hpp"

namespace tripodal::monitor {

struct HriOpResult {
  int status = 200;
  nlohmann::json body;
};

/// Whether `command` is one of this file's.
[[nodiscard]] bool is_hri_op(const OperatorCommand& command) noexcept;

/// Handles an HRI request (`op` names it in errors); `hri` nullptr: 404 (the robot has no
/// HriService module). `note` receives a line for the life cycle for every change made.
[[nodiscard]] HriOpResult handle_hri_op(HriService* hri, std::string_view op, const OperatorCommand& command,
                                        const std::function<void(std::string)>& note);

}  // namespace tripodal::monitor
