// The one plugin model of the framework: a Registry of the types of one plugin family (behaviors,
// processes, controllers, resources, navigation modules, hardware), each registered by name with
// its static manifest and a factory. Every family finds, describes and creates its types the same
// way and reports an unknown name with the same message, listing the known names.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"

namespace tripodal {

/// "unknown behavior type 'BhClean'; known: BhAutoMove, BhCleaning, ...; did you mean 'BhCleaning'?"
/// `kind` names the family ("behavior type"); `known` is listed in the given order (or "none");
/// the suggestion is closest_name(name, known) and is left out when no name is close.
[[nodiscard]] std::string unknown_name_message(std::string_view kind, std::string_view name,
                                               const std::vector<std::string>& known);

/// The name of `known` closest to `name` by edit distance, letters compared case-insensitively;
/// nullopt when none is close: within max(2, size / 3) edits, size being the longer of the two
/// names. Ties go to the first in `known`.
[[nodiscard]] std::optional<std::string> closest_name(std::string_view name, const std::vector<std::string>& known);

/// The types of one plugin family, by name: each a manifest (kept by value) and a factory that
/// builds an instance from Args... (nothing for a behavior, a ProcessDefinition for a process,
/// the configuration and hardware for a controller). Registration is not thread-safe; once it is
/// over, lookups and creations may run concurrently.
template <class Base, class... Args>
class Registry {
 public:
  using Factory = std::function<std::unique_ptr<Base>(Args...)>;

  /// `kind` names the family in messages: "behavior type", "controller type", ...
  explicit Registry(std::string kind) : kind_(std::move(kind)) {}

  /// Registers a type under manifest.name. Throws std::invalid_argument for an empty name, an
  /// empty factory or a name already registered.
  void add(ModuleManifest manifest, Factory factory) {
    if (manifest.name.empty()) throw std::invalid_argument("a " + kind_ + " needs a name");
    if (!factory) throw std::invalid_argument(kind_ + " '" + manifest.name + "' has no factory");
    if (entries_.find(manifest.name) != entries_.end()) {
      throw std::invalid_argument(kind_ + " '" + manifest.name + "' is already registered");
    }
    std::string name = manifest.name;
    entries_.emplace(std::move(name), Entry{std::move(manifest), std::move(factory)});
  }

  /// Registers `T`, which provides `static const ModuleManifest& static_manifest()` (or one
  /// returned by value) and a constructor T(Args...).
  template <class T>
  void add() {
    add(T::static_manifest(),
        [](Args... args) { return std::unique_ptr<Base>(std::make_unique<T>(std::forward<Args>(args)...)); });
  }

  [[nodiscard]] bool contains(std::string_view name) const noexcept { return entries_.find(name) != entries_.end(); }

  /// The manifest of `name`; nullptr when it is not registered.
  [[nodiscard]] const ModuleManifest* find(std::string_view name) const noexcept {
    auto it = entries_.find(name);
    return it == entries_.end() ? nullptr : &it->second.manifest;
  }

  /// The manifest of `name`. Throws ConfigError at `where` with unknown_name_message when it is
  /// not registered.
  [[nodiscard]] const ModuleManifest& manifest(std::string_view name, const SourceLocation& where = {}) const {
    return entry(name, where).manifest;
  }

  /// A new instance of type `name`. Throws ConfigError (without location) for an unknown name,
  /// std::logic_error when the factory returns nothing, and whatever the factory throws.
  [[nodiscard]] std::unique_ptr<Base> create(std::string_view name, Args... args) const {
    return create_at(SourceLocation{}, name, std::forward<Args>(args)...);
  }
  /// As create(), with the unknown-name error located at `where` (the configuration entry).
  [[nodiscard]] std::unique_ptr<Base> create_at(const SourceLocation& where, std::string_view name,
                                                Args... args) const {
    std::unique_ptr<Base> made = entry(name, where).factory(std::forward<Args>(args)...);
    if (!made) throw std::logic_error("the factory of " + kind_ + " '" + std::string(name) + "' returned nothing");
    return made;
  }

  /// Removes type `name`; false when it is not registered.
  bool erase(std::string_view name) noexcept {
    const auto it = entries_.find(name);
    if (it == entries_.end()) return false;
    entries_.erase(it);
    return true;
  }

  /// The names registered both here and in `other`, in alphabetical order.
  [[nodiscard]] std::vector<std::string> common_names(const Registry& other) const {
    std::vector<std::string> out;
    for (const auto& [name, e] : other.entries_) {
      if (contains(name)) out.push_back(name);
    }
    return out;
  }

  /// Moves every type of `other` into this registry (a set registered apart, as a shared-library
  /// plugin's is). Throws std::invalid_argument naming the names both have, and then moves none.
  void merge(Registry&& other) {
    const std::vector<std::string> both = common_names(other);
    if (!both.empty()) {
      std::string list;
      for (const std::string& n : both) list += (list.empty() ? "'" : ", '") + n + "'";
      throw std::invalid_argument(kind_ + (both.size() == 1 ? " " : "s ") + list + " already registered");
    }
    entries_.merge(other.entries_);
  }

  /// Registered names in alphabetical order.
  [[nodiscard]] std::vector<std::string> names() const {
    std::vector<std::string> out;
    out.reserve(entries_.size());
    for (const auto& [name, e] : entries_) out.push_back(name);
    return out;
  }
  [[nodiscard]] std::size_t size() const noexcept { return entries_.size(); }
  [[nodiscard]] const std::string& kind() const noexcept { return kind_; }

 private:
  struct Entry {
    ModuleManifest manifest;
    Factory factory;
  };

  const Entry& entry(std::string_view name, const SourceLocation& where) const {
    auto it = entries_.find(name);
    if (it == entries_.end()) throw ConfigError(where, unknown_name_message(kind_, name, names()));
    return it->second;
  }

  std::string kind_;
  // std::map: names() comes out sorted and a manifest's address stays valid as types are added.
  std::map<std::string, Entry, std::less<>> entries_;
};

}  // namespace tripodal
