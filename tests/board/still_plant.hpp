// The board tests' world: a robot standing still in front of fixed ranges (what `view` holds).
#pragma once

#include "tripodal/board/board_firmware.hpp"

namespace tripodal::board::test {

struct StillPlant final : BoardPlant {
  PlantSensors view = [] {
    PlantSensors s;
    s.ultrasonic_m = {0.8F, 1.0F, 1.2F};
    return s;
  }();
  void drive(Time, double, double) noexcept override {}
  void sense(Time, PlantSensors& out) noexcept override { out = view; }
};

}  // namespace tripodal::board::test
