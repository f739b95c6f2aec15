// Helpers the tripodal-net commands share: loading a net with its diagnostics printed.
#pragma once

#include <filesystem>
#include <optional>
#include <ostream>

#include "tripodal/core/net_loader.hpp"

namespace tripodal::net_tool {

/// Loads a net, printing every diagnostic gcc-style to `err`; nullopt after errors.
inline std::optional<PetriNet> load_reporting(const std::filesystem::path& file, std::ostream& err,
                                              const LoadOptions& options = {}) {
  Diagnostics d;
  auto net = load_net(file, d, options);
  err << d.str();
  return net;
}

}  // namespace tripodal::net_tool
