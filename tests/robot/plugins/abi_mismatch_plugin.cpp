// A test plugin built against another version of the plugin interface: its entry points written
// out by hand with version 999. The host must refuse it before it calls tripodal_plugin_register.
#include <cstdint>
#include <exception>

struct tripodal_plugin_host;

extern "C" __attribute__((visibility("default"))) std::uint32_t tripodal_plugin_abi_version() noexcept {
  return 999;
}
extern "C" __attribute__((visibility("default"))) int tripodal_plugin_register(tripodal_plugin_host*) noexcept {
  std::terminate();  // never called: a host that calls it with another layout would corrupt itself
}
