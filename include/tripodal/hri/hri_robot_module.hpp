// The HRI as a module of a robot (profile section `hri:`, type "Hri"; docs/guide.md): it holds the
// robot's RKMS knowledge store and the push buttons' requests, answers the planner's questions about
// the map's nodes (node(1) -> node1, exhibit_here() -> the node the robot stands at) and turns the
// hardware's button presses (hardware/buttons.hpp) into events for the nets ("button.hello").
// Registered by register_hri_modules, so that an application gets it with the built-in types.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/hri/knowledge_store.hpp"
#include "tripodal/processes/module.hpp"

namespace tripodal {

namespace navi {
class CGridMaps;
}
class ButtonPanel;

/// Type "Hri". Parameters: knowledge (an RKMS XML file, relative to the profile), buttons
/// ("hello=Introduce yourself.; help=What can you do?"), exhibit_radius_m (how near a node the
/// robot must stand for exhibit_here). Outputs the planner's functions node and exhibit_here.
/// Needs a GridMaps module (the map's nodes); reads buttons when the hardware is a ButtonPanel.
class CHri final : public CModule {
 public:
  static const ModuleManifest& static_manifest();

  /// The RKMS knowledge file, administered while the robot runs (the monitor's /rkms page edits
  /// it; every change saved atomically). Loaded at start; std::logic_error before.
  [[nodiscard]] KnowledgeStore& knowledge_store() const;
  /// Each button's request (the parameter buttons).
  [[nodiscard]] const std::map<std::string, std::string, std::less<>>& buttons() const noexcept { return buttons_; }
  /// The buttons pressed since the last call, in order.
  [[nodiscard]] std::vector<std::string> take_presses();

 protected:
  [[nodiscard]] const ModuleManifest& do_manifest() const noexcept override { return static_manifest(); }
  void on_configure(const ParameterSet& params) override;
  void on_start(ModuleContext& context) override;
  void on_update(ModuleContext& context) override;
  [[nodiscard]] std::optional<KnowledgeAnswer> on_answer(std::string_view function, std::string_view argument,
                                                         const NavigationData& navigation) const override;

 private:
  std::string knowledge_file_;
  double exhibit_radius_m_ = 1.0;
  std::unique_ptr<KnowledgeStore> store_;
  std::map<std::string, std::string, std::less<>> buttons_;
  std::vector<std::string> presses_;
  const navi::CGridMaps* maps_ = nullptr;
  ButtonPanel* panel_ = nullptr;
};

/// "hello=Introduce yourself.; help=What can you do?" as a map; ConfigError at `where` for an
/// entry without '=' or with an empty name or request, or a name given twice.
[[nodiscard]] std::map<std::string, std::string, std::less<>> parse_button_bindings(std::string_view text,
                                                                                    const SourceLocation& where);

/// The hri area's module types: "Hri". An application's plugin set gets them from register_all
/// (builtin/register_all.hpp).
void register_hri_modules(ModuleRegistry& registry);

}  // namespace tripodal
