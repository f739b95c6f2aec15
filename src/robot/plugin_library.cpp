#include "tripodal/robot/plugin_library.hpp"

#include <dlfcn.h>

#include <cstring>
#include <stdexcept>
#include <utility>

namespace tripodal {

namespace {

using AbiVersionFn = std::uint32_t (*)();
using RegisterFn = int (*)(tripodal_plugin_host*);

// dlsym returns an object pointer; POSIX guarantees it converts to a function pointer.
template <class Fn>
Fn symbol(void* library, const char* name) {
  void* const p = dlsym(library, name);
  Fn fn = nullptr;
  static_assert(sizeof fn == sizeof p);
  std::memcpy(&fn, &p, sizeof fn);
  return fn;
}

template <class R>
void add_names(std::vector<std::string>& out, const R& registry) {
  for (const std::string& n : registry.names()) out.push_back(registry.kind() + " '" + n + "'");
}

template <class R>
void add_common(std::vector<std::string>& out, const R& into, const R& from) {
  for (const std::string& n : into.common_names(from)) out.push_back(into.kind() + " '" + n + "'");
}

}  // namespace

void merge_plugins(RobotPlugins& into, RobotPlugins&& from) {
  // Every process type registry is born with "net": not the plugin's to add.
  for (const std::string& n : ProcessTypeRegistry{}.names()) from.processes.erase(n);
  std::vector<std::string> both;
  add_common(both, into.behaviors, from.behaviors);
  add_common(both, into.controllers, from.controllers);
  add_common(both, into.modules, from.modules);
  add_common(both, into.resources, from.resources);
  add_common(both, into.hardware, from.hardware);
  add_common(both, into.processes, from.processes);
  if (!both.empty()) {
    std::string list;
    for (const std::string& n : both) list += (list.empty() ? "" : ", ") + n;
    throw std::invalid_argument(list + (both.size() == 1 ? " is" : " are") + " already registered");
  }
  into.behaviors.merge(std::move(from.behaviors));
  into.controllers.merge(std::move(from.controllers));
  into.modules.merge(std::move(from.modules));
  into.resources.merge(std::move(from.resources));
  into.hardware.merge(std::move(from.hardware));
  into.processes.merge(std::move(from.processes));
}

PluginLibraryInfo load_plugin_library(const std::filesystem::path& path, RobotPlugins& plugins, const SourceLocation& where) {
  const std::string name = path.string();
  const SourceLocation at = where.file.empty() ? SourceLocation{name, 0, 0} : where;
  const auto refuse = [&](const std::string& why) { return ConfigError(at, "plugin '" + name + "' " + why); };
  std::error_code ec;
  if (!std::filesystem::is_regular_file(path, ec)) throw refuse("is not a file that can be read");
  // A path without '/' would be looked up in the library search path, not where it was named.
  const std::string open_name = path.has_parent_path() ? name : "./" + name;
  void* const library = dlopen(open_name.c_str(), RTLD_NOW | RTLD_LOCAL);
  if (library == nullptr) {
    const char* e = dlerror();
    throw refuse("cannot be loaded as a shared library: " + std::string(e != nullptr ? e : "unknown error"));
  }
  // The library is never closed: the factories registered, and the objects they build, run its
  // code. Refused libraries stay loaded too (a library's own destructors may not be safe to run
  // half-registered); loading is a start-up step, so this costs one mapping per refused file.
  const auto version = symbol<AbiVersionFn>(library, kPluginAbiSymbol);
  const auto register_fn = symbol<RegisterFn>(library, kPluginRegisterSymbol);
  if (version == nullptr || register_fn == nullptr) {
    throw refuse(std::string("is not a tripodal plugin: it exports no ") +
                 (version == nullptr ? kPluginAbiSymbol : kPluginRegisterSymbol) +
                 " (define its entry points with TRIPODAL_REGISTER_PLUGINS, tripodal/robot/plugin_library.hpp)");
  }
  const std::uint32_t theirs = version();
  if (theirs != kPluginAbiVersion) {
    throw refuse("was built against tripodal plugin ABI version " + std::to_string(theirs) + ", this program has version " +
                 std::to_string(kPluginAbiVersion) + ": rebuild the plugin against this tripodal");
  }
  RobotPlugins registered;
  tripodal_plugin_host host{kPluginAbiVersion, &registered, {}};
  if (register_fn(&host) != 0) {
    host.error[sizeof host.error - 1] = '\0';
    throw refuse("failed to register its types: " + std::string(host.error[0] != '\0' ? host.error : "no reason given"));
  }
  PluginLibraryInfo info{path, {}};
  add_names(info.types, registered.behaviors);
  add_names(info.types, registered.controllers);
  add_names(info.types, registered.modules);
  add_names(info.types, registered.resources);
  add_names(info.types, registered.hardware);
  for (const std::string& n : ProcessTypeRegistry{}.names()) registered.processes.erase(n);
  add_names(info.types, registered.processes);
  try {
    merge_plugins(plugins, std::move(registered));
  } catch (const std::invalid_argument& e) {
    throw refuse("registers a name this program already has: " + std::string(e.what()) +
                 " (built in, or by a plugin loaded before); rename the type");
  }
  return info;
}

std::vector<PluginLibraryInfo> load_profile_plugins(const RobotProfile& profile, RobotPlugins& plugins,
                                                    const std::vector<std::filesystem::path>& extra) {
  std::vector<PluginLibraryInfo> out;
  out.reserve(extra.size() + profile.plugins.size());
  for (const std::filesystem::path& p : extra) out.push_back(load_plugin_library(p, plugins, SourceLocation{"--plugin", 0, 0}));
  for (const PluginEntry& e : profile.plugins) out.push_back(load_plugin_library(e.path, plugins, e.where));
  return out;
}

}  // namespace tripodal
