// The parameter sets `tripodal-net check` verifies a net with: `--param K=V`, a `--params FILE`
// of sets, and the process entries of robot profiles (`--profile ROBOT.yaml`), which bind a
// process's net (and its module net) to parameter values. Values stay text until a net's
// declarations type them.
#pragma once

#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/engine.hpp"
#include "tripodal/core/petri_net.hpp"

namespace tripodal::net_tool {

/// One parameter set as written: name -> value text, and where it comes from ("--param",
/// "params.yaml:3:5", "psr2.yaml: process PrCleaning").
struct ParameterSetText {
  std::map<std::string, std::string> values;
  std::string origin;
  SourceLocation where;
};

/// Reads a `--params` file: a map of parameter values (one set) or a list of such maps (one set
/// each). Throws ConfigError (located) for anything else.
[[nodiscard]] std::vector<ParameterSetText> load_parameter_sets(const std::filesystem::path& file);

/// A profile's nets with the parameter sets it binds them with: for each process entry, its net
/// and its module net (if any), each with the entry's parameters; `behaviors` (if given) gets
/// the names of the profile's behaviors, the ones its nets may bind. Throws ConfigError.
struct ProfileNet {
  std::filesystem::path file;
  ParameterSetText set;
  bool module = false;  ///< the process's module net (high-level): it takes the parameters it declares
};
[[nodiscard]] std::vector<ProfileNet> profile_nets(const std::filesystem::path& profile,
                                                 std::vector<std::string>* behaviors = nullptr);

/// Types a set by the net's declarations. `only_declared`: names the net does not declare are
/// skipped (a module net declares few of its process's parameters); else they are errors, with
/// "did you mean". Errors go to `diagnostics` at the set's location.
[[nodiscard]] ParameterValues typed_set(const PetriNet& net, const ParameterSetText& set, bool only_declared,
                                        Diagnostics& diagnostics);

}  // namespace tripodal::net_tool
