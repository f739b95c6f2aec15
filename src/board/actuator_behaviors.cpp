#include "tripodal/board/actuator_behaviors.hpp"

namespace tripodal::board {

const ModuleManifest& BhUvLamp::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("BhUvLamp", ModuleKind::behavior)
                                      .description("the UV lamp on while active (channel uv_lamp: the board's command 0x31)")
                                      .writes("uv_lamp", ChannelType::digital, "on while active")
                                      .build();
  return m;
}

std::optional<Twist2D> BhUvLamp::on_step(const BehaviorContext& /*context*/) noexcept {
  write_channel(0, ChannelValue::of(true));
  return std::nullopt;
}

const ModuleManifest& BhAtomize::static_manifest() {
  static const ModuleManifest m =
      ManifestBuilder("BhAtomize", ModuleKind::behavior)
          .description(
              "dry fog while active: the atomizer and its fan (channels atomizer, atomizer_fan: the board's command 0x30)")
          .writes("atomizer", ChannelType::analog, "full fog while active")
          .writes("atomizer_fan", ChannelType::digital, "the fan, as parameter fan says")
          .flag("fan", true, "run the fan that carries the fog")
          .build();
  return m;
}

void BhAtomize::on_activate(const ParameterSet& params, const BehaviorContext& /*context*/) {
  fan_ = params.boolean("fan");
}

std::optional<Twist2D> BhAtomize::on_step(const BehaviorContext& /*context*/) noexcept {
  write_channel(0, ChannelValue::of(1.0));
  write_channel(1, ChannelValue::of(fan_));
  return std::nullopt;
}

const ModuleManifest& BhVoicePrompt::static_manifest() {
  static const ModuleManifest m = ManifestBuilder("BhVoicePrompt", ModuleKind::behavior)
                                      .description("plays a voice prompt once (channel voice: the board's command 0x32)")
                                      .writes("voice", ChannelType::track, "the track, for one period")
                                      .number("track", kTrackAddDisinfectant, "", "WT2003S track index", 0.0, 255.0)
                                      .build();
  return m;
}

void BhVoicePrompt::on_activate(const ParameterSet& params, const BehaviorContext& /*context*/) {
  track_ = params.number("track");
}

std::optional<Twist2D> BhVoicePrompt::on_step(const BehaviorContext& /*context*/) noexcept {
  if (steps() > 1) {
    succeed();  // the track went to the hardware with the previous period's channels
  } else {
    write_channel(0, ChannelValue::of(track_));
  }
  return std::nullopt;
}

const ModuleManifest& BhLcdText::static_manifest() {
  static const ModuleManifest m =
      ManifestBuilder("BhLcdText", ModuleKind::behavior)
          .description("a text on the LCD's first line while active (channel lcd: the board's command 0x33)")
          .writes("lcd", ChannelType::text, "the text")
          .text("text", std::nullopt, "at most 32 characters (longer is cut)")
          .build();
  return m;
}

void BhLcdText::on_activate(const ParameterSet& params, const BehaviorContext& /*context*/) {
  text_ = ChannelValue::of_text(params.string("text"));
}

std::optional<Twist2D> BhLcdText::on_step(const BehaviorContext& /*context*/) noexcept {
  write_channel(0, text_);
  return std::nullopt;
}

void register_board_behaviors(BehaviorRegistry& registry) {
  registry.add<BhUvLamp>();
  registry.add<BhAtomize>();
  registry.add<BhVoicePrompt>();
  registry.add<BhLcdText>();
}

}  // namespace tripodal::board
