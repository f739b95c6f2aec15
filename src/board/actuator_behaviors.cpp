#include "tripodal/board/actuator_behaviors.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <string_view>

#include "tripodal/board/board_hardware.hpp"

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

const ModuleManifest& BhLcdStatus::static_manifest() {
  static const ModuleManifest m =
      ManifestBuilder("BhLcdStatus", ModuleKind::behavior)
          .description(
              "the state, the battery and the tank on the LCD's first line while active (channel lcd: the "
              "board's command 0x33)")
          .inputs({"battery", "tank"})
          .writes("lcd", ChannelType::text, "state, battery and tank")
          .text("state", std::string("READY"), "the state's word, at most 16 characters")
          .build();
  return m;
}

void BhLcdStatus::on_activate(const ParameterSet& params, const BehaviorContext& /*context*/) {
  state_ = params.string("state").substr(0, 16);
}

std::optional<Twist2D> BhLcdStatus::on_step(const BehaviorContext& context) noexcept {
  const BatteryResource* battery = context.resources != nullptr ? context.resources->find<BatteryReading>("battery") : nullptr;
  const auto* tank = context.resources != nullptr ? context.resources->find<TankReading>("tank") : nullptr;
  // Whole percent, as the board reports them; fixed buffers: the step must not allocate.
  const int b =
      battery != nullptr && battery->has_reading() ? static_cast<int>(std::lround(battery->latest().percentage * 100.0)) : -1;
  const int t = tank != nullptr && tank->has_reading() ? static_cast<int>(std::lround(tank->latest().percent)) : -1;
  std::array<char, 16> bs{}, ts{};
  if (b < 0)
    (void)std::snprintf(bs.data(), bs.size(), "--");
  else
    (void)std::snprintf(bs.data(), bs.size(), "%d%%", b);
  if (t < 0)
    (void)std::snprintf(ts.data(), ts.size(), "--");
  else
    (void)std::snprintf(ts.data(), ts.size(), "%d%%", t);
  std::array<char, 64> text{};  // cut to the channel's 32 characters
  (void)std::snprintf(text.data(), text.size(), "%s B %s T %s", state_.c_str(), bs.data(), ts.data());
  write_channel(0, ChannelValue::of_text(std::string_view(text.data())));
  return std::nullopt;
}

void register_board_behaviors(BehaviorRegistry& registry) {
  registry.add<BhUvLamp>();
  registry.add<BhAtomize>();
  registry.add<BhVoicePrompt>();
  registry.add<BhLcdText>();
  registry.add<BhLcdStatus>();
}

}  // namespace tripodal::board
