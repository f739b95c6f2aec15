// A minimal PNG encoder (8-bit RGB, zlib-compressed, no filtering) for the pictures `tripodal run`
// writes: the map with its sections, the path and the cleaned cells. Part of the application
// layer (tools); nothing in the robot depends on it.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace tripodal::app {

/// An 8-bit RGB raster, row 0 at the top.
struct RgbImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> rgb;  ///< row-major, 3 bytes per pixel
  RgbImage() = default;
  RgbImage(int w, int h, std::uint8_t r = 255, std::uint8_t g = 255, std::uint8_t b = 255);
  void set(int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b) noexcept;
  /// Blends the colour over the pixel with opacity alpha in [0, 1].
  void blend(int x, int y, std::uint8_t r, std::uint8_t g, std::uint8_t b, double alpha) noexcept;
  [[nodiscard]] bool contains(int x, int y) const noexcept { return x >= 0 && y >= 0 && x < width && y < height; }
};

/// The PNG file bytes of an image. Throws std::invalid_argument for an empty or inconsistent
/// image.
[[nodiscard]] std::string encode_png(const RgbImage& image);
/// Writes encode_png(image) to file; std::runtime_error naming the file when it cannot.
void write_png(const std::filesystem::path& file, const RgbImage& image);

/// CRC-32 (ISO 3309, as PNG chunks use) of bytes.
[[nodiscard]] std::uint32_t png_crc32(const std::string& bytes) noexcept;

}  // namespace tripodal::app
