// Shared-library plugins: types an application builds into a .so of its own, registered into the
// plugin set (robot/plugins.hpp) of any program that loads it — `tripodal run`, `describe`,
// `tripodal-net check`, the test harnesses — through one versioned C entry point. The plugin
// side is the macro TRIPODAL_REGISTER_PLUGINS; the host side is load_plugin_library.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <exception>
#include <filesystem>
#include <string>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/robot/plugins.hpp"
#include "tripodal/robot/robot_profile.hpp"

/// The version of the plugin interface: the entry points below and the layout of RobotPlugins and
/// of every family's base class, as this tripodal was built. A plugin records the version it was
/// compiled against; a host refuses a plugin of another version (the classes it derives from would
/// not match the host's). Changes with every minor release of the package (0.1 -> 1).
#define TRIPODAL_PLUGIN_ABI_VERSION 1u

/// What the host hands a plugin's tripodal_plugin_register: the set to register into and room
/// for the reason when registration fails. Plain C layout, so that the entry point is C.
extern "C" {
struct tripodal_plugin_host {
  std::uint32_t abi_version;        ///< the host's TRIPODAL_PLUGIN_ABI_VERSION
  tripodal::RobotPlugins* plugins;  ///< an empty set, merged into the application's afterwards
  char error[512];                  ///< filled by the plugin when it returns non-zero
};
}

namespace tripodal {

inline constexpr std::uint32_t kPluginAbiVersion = TRIPODAL_PLUGIN_ABI_VERSION;
/// The symbols a plugin exports (C linkage, found with dlsym).
inline constexpr const char* kPluginAbiSymbol = "tripodal_plugin_abi_version";
inline constexpr const char* kPluginRegisterSymbol = "tripodal_plugin_register";

namespace detail {
/// Runs a plugin's registration function on host->plugins; an exception becomes return value 1
/// and its message host->error, so that nothing is thrown across the C entry point.
inline int run_plugin_registration(tripodal_plugin_host* host, void (*register_types)(RobotPlugins&)) noexcept {
  const auto fail = [host](const char* what) {
    std::snprintf(host->error, sizeof host->error, "%s", what);
    return 1;
  };
  if (host == nullptr || host->plugins == nullptr) return 2;
  try {
    register_types(*host->plugins);
    return 0;
  } catch (const std::exception& e) {
    return fail(e.what());
  } catch (...) {
    return fail("an exception that is not a std::exception");
  }
}
}  // namespace detail

/// What load_plugin_library registered: the library and the names it added, per family.
struct PluginLibraryInfo {
  std::filesystem::path path;
  std::vector<std::string> types;  ///< "behavior type 'BhBeacon'", ... in family order
};

/// Loads the shared library at `path` (dlopen), checks that it is a tripodal plugin of this
/// ABI version, runs its registration into an empty set and moves the types into `plugins`.
/// Throws ConfigError at `where` (the `--plugin` option or the profile's `plugins:` entry; by
/// default the library's path), and
/// leaves `plugins` as it was, when the file cannot be loaded, exports no
/// tripodal_plugin_register, was built against another ABI version, throws from its registration
/// (or registers a name twice), or registers a name `plugins` already has (a built-in one, or
/// another plugin's). The library stays loaded until the process ends: the types' code is in it.
PluginLibraryInfo load_plugin_library(const std::filesystem::path& path, RobotPlugins& plugins, const SourceLocation& where = {});

/// Loads the libraries of `extra` (the command line's `--plugin`, refused at "--plugin"), then
/// those of `profile`'s `plugins:` list (each refused at its entry), into `plugins`. What the tools
/// and harnesses call before they assemble or check a profile.
std::vector<PluginLibraryInfo> load_profile_plugins(const RobotProfile& profile, RobotPlugins& plugins,
                                                    const std::vector<std::filesystem::path>& extra = {});

/// Moves every type of `from` into `into` (but the process type "net" every set is born with).
/// Throws std::invalid_argument naming every name both have (in every family), and then moves
/// none.
void merge_plugins(RobotPlugins& into, RobotPlugins&& from);

}  // namespace tripodal

#if defined(_WIN32)
#define TRIPODAL_PLUGIN_EXPORT __declspec(dllexport)
#else
#define TRIPODAL_PLUGIN_EXPORT __attribute__((visibility("default")))
#endif

/// Defines a shared library's plugin entry points; the body that follows registers its types:
///
///   TRIPODAL_REGISTER_PLUGINS(plugins) {
///     plugins.behaviors.add<BhBeacon>();
///     plugins.controllers.add<WinchController>();
///   }
///
/// `plugins` is a tripodal::RobotPlugins&. An exception from the body refuses the plugin with its
/// message. Use once per library.
#define TRIPODAL_REGISTER_PLUGINS(plugins)                                                                \
  static void tripodal_plugin_register_types(::tripodal::RobotPlugins& plugins);                          \
  extern "C" TRIPODAL_PLUGIN_EXPORT std::uint32_t tripodal_plugin_abi_version() noexcept {                \
    return TRIPODAL_PLUGIN_ABI_VERSION;                                                                   \
  }                                                                                                       \
  extern "C" TRIPODAL_PLUGIN_EXPORT int tripodal_plugin_register(::tripodal_plugin_host* host) noexcept { \
    return ::tripodal::detail::run_plugin_registration(host, &tripodal_plugin_register_types);            \
  }                                                                                                       \
  static void tripodal_plugin_register_types(::tripodal::RobotPlugins& plugins)
