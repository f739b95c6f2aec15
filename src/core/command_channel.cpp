#include "tripodal/core/command_channel.hpp"

#include <stdexcept>

namespace tripodal {

std::string_view to_string(ChannelType type) noexcept {
  switch (type) {
    case ChannelType::joint_position:
      return "joint_position";
    case ChannelType::digital:
      return "digital";
    case ChannelType::analog:
      return "analog";
    case ChannelType::track:
      return "track";
    case ChannelType::text:
      return "text";
  }
  return "?";
}

std::optional<ChannelType> parse_channel_type(std::string_view text) noexcept {
  for (ChannelType t :
       {ChannelType::joint_position, ChannelType::digital, ChannelType::analog, ChannelType::track, ChannelType::text}) {
    if (to_string(t) == text) return t;
  }
  return std::nullopt;
}

std::size_t CommandChannels::add(ChannelSpec spec) {
  if (spec.name.empty()) throw std::invalid_argument("a command channel needs a name");
  if (find(spec.name)) throw std::invalid_argument("command channel '" + spec.name + "' already exists");
  values_.push_back(spec.safe);
  writes_.push_back(0);
  specs_.push_back(std::move(spec));
  return specs_.size() - 1;
}

std::optional<std::size_t> CommandChannels::find(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < specs_.size(); ++i) {
    if (specs_[i].name == name) return i;
  }
  return std::nullopt;
}

}  // namespace tripodal
