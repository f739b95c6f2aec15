#include "tripodal/processes/module.hpp"

namespace tripodal {

void CModule::configure(const ParameterValues& params, const SourceLocation& where) {
  where_ = where;
  on_configure(ParameterSet::resolve(manifest(), params, where));
  configured_ = true;
}

ParameterSet BehaviorActivation::resolved() const {
  if (manifest == nullptr) throw ConfigError(SourceLocation{}, "behavior '" + std::string(behavior) + "' has no manifest");
  return ParameterSet::resolve(*manifest, params);
}

}  // namespace tripodal
