// Helpers the tripodal-net commands share: argument scanning and loading with diagnostics.
#pragma once

#include <filesystem>
#include <optional>
#include <ostream>
#include <string>
#include <vector>

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

/// The value of `--name VALUE` at args[i] (advancing i), or nullopt after reporting a missing value.
inline std::optional<std::string> option_value(const std::vector<std::string>& args, std::size_t& i, std::ostream& err) {
  if (i + 1 >= args.size()) {
    err << "option " << args[i] << " needs a value\n";
    return std::nullopt;
  }
  return args[++i];
}

}  // namespace tripodal::net_tool
