#include "tripodal/board/actuator_behaviors.hpp"

namespace tripodal::board {

namespace {

ModuleManifest actuator_manifest(std::string name, std::string description, std::string output) {
  return ManifestBuilder(std::move(name), ModuleKind::behavior).description(std::move(description)).output(std::move(output)).build();
}

}  // namespace

const ModuleManifest& BhUvLamp::static_manifest() {
  static const ModuleManifest m = actuator_manifest("BhUvLamp", "the UV lamp on while active (the board's command 0x31)", "uv_lamp");
  return m;
}

const ModuleManifest& BhAtomize::static_manifest() {
  static const ModuleManifest m = [] {
    ModuleManifest r = actuator_manifest("BhAtomize", "dry fog while active: the atomizer and its fan (the board's command 0x30)", "atomizer");
    r.parameters.push_back(ParameterSpec{"fan", ValueType::boolean, Value{true}, "", "run the fan that carries the fog", {}, {}});
    return r;
  }();
  return m;
}

const ModuleManifest& BhVoicePrompt::static_manifest() {
  static const ModuleManifest m = [] {
    ModuleManifest r = actuator_manifest("BhVoicePrompt", "plays a voice prompt once (the board's command 0x32)", "voice");
    r.parameters.push_back(ParameterSpec{"track", ValueType::number, Value{kTrackAddDisinfectant}, "", "WT2003S track index", 0.0, 255.0});
    return r;
  }();
  return m;
}

void register_board_behaviors(BehaviorRegistry& registry) {
  registry.add<BhUvLamp>();
  registry.add<BhAtomize>();
  registry.add<BhVoicePrompt>();
}

}  // namespace tripodal::board
