// Command channels: the one way anything that is not the base's velocity is driven (as
// ros2_control's command interfaces). A hardware type exports named, typed channels (a joint's
// position, the UV lamp, the atomizer's level, the voice chip's track, the LCD's text); a behavior
// declares in its manifest the channels it writes; the behavior coordinator fuses each channel
// every reactive cycle and the hardware applies the result (docs/reactive.md, "Command channels").
// Values are fixed-size (text has a fixed capacity), so fusing and writing them allocates nothing.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/core/time.hpp"

namespace tripodal {

/// What a channel carries. Numeric channels (joint_position, analog) are averaged by weight in
/// the coordinator's weighted_sum mode; the others always go by priority (a lamp half on, or the
/// mean of two tracks, means nothing).
enum class ChannelType : std::uint8_t {
  joint_position,  ///< rad
  digital,         ///< on/off: 0 or 1
  analog,          ///< a level in the channel's [min, max] (an atomizer's 0..1)
  track,           ///< an index to play (a voice chip's track); 0 plays nothing
  text,            ///< a short text (an LCD line), at most kChannelTextCapacity characters
};
[[nodiscard]] std::string_view to_string(ChannelType type) noexcept;
/// "joint_position" | "digital" | "analog" | "track" | "text" -> ChannelType.
[[nodiscard]] std::optional<ChannelType> parse_channel_type(std::string_view text) noexcept;
[[nodiscard]] constexpr bool is_numeric(ChannelType type) noexcept {
  return type == ChannelType::joint_position || type == ChannelType::analog;
}

/// The capacity of a text channel: one line of the control board's LCD.
inline constexpr std::size_t kChannelTextCapacity = 32;

/// A channel's value: `number` for every type but text (digital: 0 or 1), `text` for text.
/// Trivially copyable; a longer text is cut at kChannelTextCapacity.
struct ChannelValue {
  double number = 0.0;
  std::array<char, kChannelTextCapacity> chars{};
  std::uint8_t size = 0;

  [[nodiscard]] static ChannelValue of(double value) noexcept {
    ChannelValue v;
    v.number = value;
    return v;
  }
  [[nodiscard]] static ChannelValue of(bool on) noexcept { return of(on ? 1.0 : 0.0); }
  [[nodiscard]] static ChannelValue of_text(std::string_view text) noexcept {
    ChannelValue v;
    v.size = static_cast<std::uint8_t>(std::min(text.size(), kChannelTextCapacity));
    std::copy_n(text.data(), v.size, v.chars.data());
    return v;
  }
  [[nodiscard]] bool on() const noexcept { return number != 0.0; }
  [[nodiscard]] std::string_view text() const noexcept { return {chars.data(), size}; }
  friend bool operator==(const ChannelValue& a, const ChannelValue& b) noexcept {
    return a.number == b.number && a.text() == b.text();
  }
};

/// A channel a hardware exports.
struct ChannelSpec {
  std::string name;  ///< unique in the hardware: "uv_lamp", "neck"
  ChannelType type = ChannelType::digital;
  /// What the channel falls to when no live input writes it (every writer withdrawn or timed
  /// out), and its value before the first write: the lamp off, the atomizer at 0.
  ChannelValue safe;
  /// Hold the last fused value instead of falling to `safe` (a position-controlled joint stays
  /// where it was sent; `safe` is then its initial value).
  bool hold = false;
  /// A write older than this no longer counts (0: as long as its writer is live).
  Duration timeout{0};
  double min = 0.0, max = 0.0;  ///< numeric types: the fused value is clamped into [min, max] when min < max
  std::string unit;
  std::string description;
};

/// A channel a behavior type writes, as its manifest declares it: by name, or named by one of its
/// string parameters (BhNeckGesture writes the joint its parameter `joint` names).
struct ChannelWrite {
  std::string name;       ///< the channel; empty when `parameter` names it
  std::string parameter;  ///< the string parameter whose value is the channel's name
  ChannelType type = ChannelType::digital;
  std::string description;
  /// "uv_lamp", or "<joint>" for a parameter-named channel: for messages and describe.
  [[nodiscard]] std::string label() const { return name.empty() ? "<" + parameter + ">" : name; }
};

/// The most channels one behavior writes (their writes are kept in a fixed array).
inline constexpr std::size_t kMaxBehaviorChannels = 4;

/// The channels a hardware exports and the values the reactive loop last wrote into them. Built
/// at construction (add() allocates); set() and value() are noexcept, on the reactive loop's
/// thread, where the hardware also reads them.
class CommandChannels {
 public:
  /// Adds a channel with value `spec.safe`; throws std::invalid_argument for a duplicate or
  /// empty name. Returns its index.
  std::size_t add(ChannelSpec spec);
  [[nodiscard]] std::optional<std::size_t> find(std::string_view name) const noexcept;
  [[nodiscard]] std::size_t size() const noexcept { return specs_.size(); }
  [[nodiscard]] bool empty() const noexcept { return specs_.empty(); }
  [[nodiscard]] const ChannelSpec& spec(std::size_t i) const noexcept { return specs_[i]; }
  [[nodiscard]] std::span<const ChannelSpec> specs() const noexcept { return specs_; }
  /// The value the loop wrote last (the safe value before the first write).
  [[nodiscard]] const ChannelValue& value(std::size_t i) const noexcept { return values_[i]; }
  /// Number of set() calls on channel i so far: a hardware that acts on changes compares it.
  [[nodiscard]] std::uint64_t writes(std::size_t i) const noexcept { return writes_[i]; }
  void set(std::size_t i, const ChannelValue& value) noexcept {
    values_[i] = value;
    ++writes_[i];
  }

 private:
  std::vector<ChannelSpec> specs_;
  std::vector<ChannelValue> values_;
  std::vector<std::uint64_t> writes_;
};

}  // namespace tripodal
