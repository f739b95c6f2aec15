// CNaviModules, the base class of the navigation modules (the paper's class; sequencing layer):
// maps, localizers, the path planner, the section splitter, map builders. Each module declares a
// static manifest (core/manifest.hpp), is configured once from parameters, and is updated every
// period of the sequencing layer, posting named events (e.g. localizer.lost) that the process
// supervisor routes to the running nets.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/manifest.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal::navi {

/// An event a navigation module posts: the name a net's transition waits for, and why.
struct NaviEvent {
  Time stamp{0};
  std::string name;     ///< e.g. "localizer.lost"
  std::string message;  ///< for logs and fault messages
  friend bool operator==(const NaviEvent&, const NaviEvent&) = default;
};

class CNaviModules {
 public:
  virtual ~CNaviModules() = default;
  CNaviModules() = default;
  CNaviModules(const CNaviModules&) = delete;
  CNaviModules& operator=(const CNaviModules&) = delete;

  /// The static manifest of the module type (layer sequencing, kind navigation).
  [[nodiscard]] const ModuleManifest& manifest() const noexcept { return do_manifest(); }
  [[nodiscard]] std::string_view name() const noexcept { return manifest().name; }

  /// Resolves params against the manifest (ConfigError listing every problem, located at where),
  /// then calls on_configure(). May be called again to reconfigure.
  void configure(const ParameterValues& params = {}, const SourceLocation& where = {});
  [[nodiscard]] bool configured() const noexcept { return configured_; }

  /// One period of the sequencing layer at time now: appends the events the module posts to
  /// out. Does nothing before configure(). Never throws: a module's failure is an event.
  void update(Time now, std::vector<NaviEvent>& out) noexcept;

 protected:
  [[nodiscard]] virtual const ModuleManifest& do_manifest() const noexcept = 0;
  virtual void on_configure(const ParameterSet& params) = 0;
  virtual void on_update(Time now, std::vector<NaviEvent>& out) noexcept;

 private:
  bool configured_ = false;
};

/// A manifest for a navigation module: layer sequencing, kind navigation.
[[nodiscard]] ModuleManifest navi_manifest(std::string name, std::string description, std::vector<std::string> inputs,
                                           std::vector<std::string> outputs, std::vector<ParameterSpec> parameters);

/// Navigation module types by name.
class NaviModuleRegistry {
 public:
  using Factory = std::function<std::unique_ptr<CNaviModules>()>;
  /// Registers a type; throws std::invalid_argument when the name is taken.
  void add(const ModuleManifest& manifest, Factory factory);
  /// A new, unconfigured module; nullptr for an unknown name.
  [[nodiscard]] std::unique_ptr<CNaviModules> create(std::string_view name) const;
  [[nodiscard]] const ModuleManifest* manifest(std::string_view name) const;
  [[nodiscard]] std::vector<std::string> names() const;
  /// A registry holding the built-in modules (CSectionSplitter, CLocalizer).
  [[nodiscard]] static NaviModuleRegistry with_builtins();

 private:
  struct Entry {
    const ModuleManifest* manifest;
    Factory factory;
  };
  std::map<std::string, Entry, std::less<>> entries_;
};

}  // namespace tripodal::navi
