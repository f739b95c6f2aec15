#include "tripodal/board/actuator_behaviors.hpp"

namespace tripodal::board {

const ModuleManifest& BhUvLamp::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("BhUvLamp", ModuleKind::behavior)
                                      .description("the UV lamp on while active (the board's command 0x31)")
                                      .output("uv_lamp")
                                      .build();
  return m;
}

const ModuleManifest& BhAtomize::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("BhAtomize", ModuleKind::behavior)
                                      .description("dry fog while active: the atomizer and its fan (the board's command 0x30)")
                                      .output("atomizer")
                                      .flag("fan", true, "run the fan that carries the fog")
                                      .build();
  return m;
}

const ModuleManifest& BhVoicePrompt::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("BhVoicePrompt", ModuleKind::behavior)
                                      .description("plays a voice prompt once (the board's command 0x32)")
                                      .output("voice")
                                      .number("track", kTrackAddDisinfectant, "", "WT2003S track index", 0.0, 255.0)
                                      .build();
  return m;
}

void register_board_behaviors(BehaviorRegistry& registry) {
  registry.add<BhUvLamp>();
  registry.add<BhAtomize>();
  registry.add<BhVoicePrompt>();
}

}  // namespace tripodal::board
