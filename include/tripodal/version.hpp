// The framework's version, for robot applications that log what they run on.
#pragma once

namespace tripodal {

inline constexpr int kVersionMajor = 0;
inline constexpr int kVersionMinor = 1;
inline constexpr int kVersionPatch = 0;

/// "0.1.0"; kept equal to project(VERSION) in CMakeLists.txt (a test checks it).
[[nodiscard]] const char* version_string() noexcept;

}  // namespace tripodal
