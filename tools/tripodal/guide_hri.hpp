// The HRI as a module of the guide robot (profile section `hri:`, type "Hri"; docs/guide.md): it
// holds the robot's RKMS knowledge file and the LED buttons' requests, answers the planner's
// questions about the exhibit hall (node(1) -> node1, exhibit_here() -> the node the robot stands
// at) and turns the simulated buttons' presses into events for the nets ("button.hello"). The
// robot program builds the HriModule (hri/hri_module.hpp) on it. Application layer, not installed.
#pragma once

#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tripodal/hri/knowledge_base.hpp"
#include "tripodal/processes/module.hpp"

namespace tripodal::sim {
class Simulator;
}
namespace tripodal::navi {
class CGridMaps;
}

namespace tripodal::app {

/// Type "Hri". Parameters: knowledge (an RKMS XML file, relative to the profile), buttons
/// ("hello=Introduce yourself.; help=What can you do?"), exhibit_radius_m (how near a node the
/// robot must stand for exhibit_here). Outputs the planner's functions node and exhibit_here.
class CHri final : public CModule {
 public:
  static const ModuleManifest& static_manifest();

  [[nodiscard]] const KnowledgeBase& knowledge() const;
  /// Each button's request (HriOptions::buttons).
  [[nodiscard]] const std::map<std::string, std::string, std::less<>>& buttons() const noexcept { return buttons_; }
  /// The LED buttons pressed since the last call, in order.
  [[nodiscard]] std::vector<std::string> take_presses();
  /// The simulator the buttons are on (nullptr on other hardware).
  [[nodiscard]] sim::Simulator* simulator() const noexcept { return sim_; }

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
  std::unique_ptr<KnowledgeBase> base_;
  std::map<std::string, std::string, std::less<>> buttons_;
  std::vector<std::string> presses_;
  const navi::CGridMaps* maps_ = nullptr;
  sim::Simulator* sim_ = nullptr;
};

/// "hello=Introduce yourself.; help=What can you do?" as a map; ConfigError at `where` for an
/// entry without '=' or with an empty name or request, or a name given twice.
[[nodiscard]] std::map<std::string, std::string, std::less<>> parse_button_bindings(std::string_view text,
                                                                                    const SourceLocation& where);

/// Registers the module type "Hri".
void register_guide_modules(ModuleRegistry& registry);

}  // namespace tripodal::app
