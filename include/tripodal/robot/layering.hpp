// The layered functionality diagram of a configured robot (paper, section 3.2, Figs. 4-7): every
// module with its layer, kind, inputs and outputs, including the core components (planner, process
// supervisor, configurations, behavior coordinator); the start-up checks that every input has
// exactly one provider and that the layering rules hold (docs/processes.md, "Layering rules");
// and its text and Graphviz renderings (`tripodal describe`).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "tripodal/behaviors/behavior_registry.hpp"
#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/planner/task_library.hpp"
#include "tripodal/robot/plugins.hpp"
#include "tripodal/robot/robot_profile.hpp"

namespace tripodal {

/// One module of the diagram. An input ending in '*' accepts any number of providers (the
/// behavior coordinator fuses every behavior_command); every other input needs exactly one.
struct DescribedModule {
  std::string name;
  std::string type;
  ModuleKind kind = ModuleKind::other;
  Layer layer = Layer::reactive;
  bool core = false;  ///< planner, process supervisor, behavior coordinator
  std::string description;
  std::vector<std::string> inputs;
  std::vector<std::string> outputs;
  SourceLocation where;
  /// Inputs bound to one provider by name (the profile entry's `from:`), where several provide it.
  std::map<std::string, std::string, std::less<>> from;
  /// Behaviors: the command channels they write ("uv_lamp", "<joint>" for one their parameter
  /// names). Hardware: the command channels its type exports.
  std::vector<ChannelWrite> writes;
  std::vector<ChannelSpec> channels;
  bool hardware = false;  ///< the profile's hardware entry
};

struct RobotDescription {
  std::string name;
  std::string description;
  std::vector<DescribedModule> modules;  ///< core components first, then the profile's order
  std::vector<std::string> processes;    ///< the configurations the supervisor may run
};

/// Names of the core components, as they appear in the diagram.
struct CoreNames {
  static constexpr const char* kPlanner = "planner";
  static constexpr const char* kSupervisor = "process_supervisor";
  static constexpr const char* kCoordinator = "behavior_coordinator";
};

/// Builds the diagram of `profile`: resolves each entry's manifest (the registered type's own, or
/// for a type not registered, the layer/inputs/outputs declared in the profile; re-declaring a
/// registered type's manifest is an error), adds the core components (the planner's inputs
/// are the knowledge its task templates ask for, e.g. "sections"), then checks providers and the
/// layering rules. Every problem is appended to `diagnostics`, located at the entry.
[[nodiscard]] RobotDescription describe_robot(const RobotProfile& profile, const RobotPlugins& plugins,
                                              const std::vector<std::string>& planner_inputs, Diagnostics& diagnostics);

/// Only the checks, over an already resolved list of modules: exactly one provider per input
/// (R0), the layering rules R1-R5 (docs/processes.md) and R6: a command channel a behavior
/// writes by name is one the hardware exports, of the same type (when the hardware is described).
void check_layering(const std::vector<DescribedModule>& modules, Diagnostics& diagnostics);

/// The knowledge functions task templates ask for in their foreach lists ("sections"), sorted.
[[nodiscard]] std::vector<std::string> knowledge_inputs(const TaskLibrary& tasks);

/// Modules by layer with inputs and outputs, for people.
[[nodiscard]] std::string describe_text(const RobotDescription& description);
/// The layered functionality diagram in Graphviz DOT: a cluster per layer, an edge per
/// information from its provider to each consumer.
[[nodiscard]] std::string describe_dot(const RobotDescription& description);

}  // namespace tripodal
