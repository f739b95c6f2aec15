// Loading configuration nets from files: tripodal's native XML format (docs/net-format.md) and
// PNML (ISO/IEC 15909-2 and the older JARP dialect). Every error of a file is collected and
// reported gcc-style; a net that loads is structurally valid and ready for the engine.
#pragma once

#include <filesystem>
#include <functional>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/diagnostic.hpp"
#include "tripodal/core/petri_net.hpp"

namespace tripodal {

enum class NetFormat { automatic, native_xml, pnml };

struct LoadOptions {
  NetFormat format = NetFormat::automatic;  ///< automatic: by extension (.pnml) then by root element
  /// When set, a place binding a behavior (or referring to a process) whose name the predicate
  /// rejects is an error: "unknown behavior 'BhClening'".
  std::function<bool(std::string_view)> is_known_behavior;
  std::function<bool(std::string_view)> is_known_process;
  /// The names "did you mean" picks from when is_known_behavior / is_known_process rejects one.
  std::vector<std::string> behavior_names;
  std::vector<std::string> process_names;
  bool structural_warnings = true;  ///< places no transition can mark, transitions never enabled
};

/// Loads a net, appending every problem (errors and warnings) to `diagnostics`. Returns the net
/// when there were no errors, nullopt otherwise.
std::optional<PetriNet> load_net(const std::filesystem::path& file, Diagnostics& diagnostics,
                                 const LoadOptions& options = {});

/// As load_net but from text in memory; `name` is used as the file name in diagnostics.
std::optional<PetriNet> load_net_from_string(std::string_view text, std::string_view name,
                                             Diagnostics& diagnostics, const LoadOptions& options = {});

/// Loads a net or throws ConfigError listing every error.
PetriNet load_net_or_throw(const std::filesystem::path& file, const LoadOptions& options = {});

/// Writes a net in the format the extension names (.pnml -> PNML, else native XML). Throws
/// ConfigError when the net cannot be represented in the target format.
void save_net(const PetriNet& net, const std::filesystem::path& file);

/// The text save_net writes: NetFormat::pnml gives PNML (ISO 2009 P/T net), anything else the
/// native XML format. Throws ConfigError when the net cannot be represented.
[[nodiscard]] std::string net_to_string(const PetriNet& net, NetFormat format);

/// Places some firing sequence might mark, by a fixpoint that ignores guards, inhibitors,
/// capacities and events (a transition fires once every place it consumes from or reads is
/// markable): false is certain, true is not a proof. Indexed by PlaceIndex.
[[nodiscard]] std::vector<bool> structurally_markable(const PetriNet& net);

/// The structural warnings load_net adds (when LoadOptions::structural_warnings): places that no
/// transition can ever mark and transitions that can never be enabled, ignoring guards,
/// inhibitors and capacities (so a warning is certain, silence is not a proof).
void structural_warnings(const PetriNet& net, Diagnostics& diagnostics);

}  // namespace tripodal
