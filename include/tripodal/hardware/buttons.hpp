// The robot's push buttons as its hardware offers them (the guide robot's LED buttons on the
// simulator): an interface next to CHardware that the HRI module (hri/hri_robot_module.hpp) reads
// through the robot's hardware slot, so that the hri area depends on no particular hardware type.
#pragma once

#include <string>
#include <vector>

namespace tripodal {

/// Implemented by a hardware type that has buttons, beside CHardware. One thread: the robot's.
class ButtonPanel {
 public:
  virtual ~ButtonPanel() = default;
  /// The buttons pressed since the last call, oldest first, by the names the hardware gives them.
  [[nodiscard]] virtual std::vector<std::string> take_button_presses() = 0;

 protected:
  ButtonPanel() = default;
  ButtonPanel(const ButtonPanel&) = default;
  ButtonPanel& operator=(const ButtonPanel&) = default;
};

}  // namespace tripodal
