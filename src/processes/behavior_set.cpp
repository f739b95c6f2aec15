#include "tripodal/processes/behavior_set.hpp"

#include <stdexcept>

namespace tripodal {

CBehavior& BehaviorSet::add(std::unique_ptr<CBehavior> behavior) {
  if (!behavior) throw std::invalid_argument("BehaviorSet::add: null behavior");
  std::string name(behavior->name());
  auto [it, inserted] = entries_.try_emplace(name);
  if (!inserted) throw std::invalid_argument("behavior '" + name + "' is already in the set");
  it->second.behavior = std::move(behavior);
  return *it->second.behavior;
}

CBehavior& BehaviorSet::add(const BehaviorRegistry& registry, std::string_view type) { return add(registry.create(type)); }

CBehavior* BehaviorSet::find(std::string_view name) noexcept {
  auto it = entries_.find(name);
  return it == entries_.end() ? nullptr : it->second.behavior.get();
}

std::vector<std::string> BehaviorSet::names() const {
  std::vector<std::string> out;
  for (const auto& [k, v] : entries_) out.push_back(k);
  return out;
}

void BehaviorSet::step_active(const BehaviorContext& context,
                              const std::function<void(std::string_view, const std::optional<Twist2D>&)>& sink) {
  for (auto& [name, e] : entries_) {
    if (!e.behavior->running()) continue;
    const std::optional<Twist2D> cmd = e.behavior->step(context);
    if (sink) sink(name, cmd);
  }
}

bool BehaviorSet::has(std::string_view behavior) const { return entries_.find(behavior) != entries_.end(); }

void BehaviorSet::activate(std::string_view behavior, const ParameterValues& params, Time now) {
  auto it = entries_.find(behavior);
  if (it == entries_.end()) throw std::out_of_range("no behavior '" + std::string(behavior) + "'");
  CBehavior& b = *it->second.behavior;
  ParameterValues typed;
  for (const auto& [name, value] : params) {
    const ParameterSpec* spec = b.manifest().find_parameter(name);
    if (spec != nullptr && spec->type != ValueType::string && std::holds_alternative<std::string>(value)) {
      if (auto v = parse_value(spec->type, std::get<std::string>(value))) {
        typed[name] = *v;
        continue;
      }
    }
    typed[name] = value;
  }
  BehaviorContext ctx = context_ ? *context_ : BehaviorContext{};
  ctx.now = now;
  b.activate(typed, ctx);  // throws ConfigError for bad parameters: the supervisor makes it a failure
  it->second.seen_steps = b.steps();
  it->second.last_step = now;
}

void BehaviorSet::deactivate(std::string_view behavior, Time /*now*/) {
  auto it = entries_.find(behavior);
  if (it != entries_.end()) it->second.behavior->deactivate();
}

BehaviorReport BehaviorSet::report(std::string_view behavior) const {
  auto it = entries_.find(behavior);
  if (it == entries_.end()) throw std::out_of_range("no behavior '" + std::string(behavior) + "'");
  const Entry& e = it->second;
  BehaviorReport r;
  r.state = e.behavior->status();
  r.reason = std::string(e.behavior->failure_reason());
  if (e.behavior->steps() != e.seen_steps) {
    e.seen_steps = e.behavior->steps();
    e.last_step = clock_.now();
  }
  r.last_step = e.last_step;
  return r;
}

}  // namespace tripodal
