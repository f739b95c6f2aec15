// Occupancy grid maps in the ROS map_server format (a PGM image plus a YAML description), so maps
// made by ROS tools load as they are and maps written here open in ROS. Part of the navigation
// modules (sequencing layer); the simulator loads its world through it too.
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/navi/occupancy_grid.hpp"

namespace tripodal::navi {

/// How pixel values become cell values (map_server's `mode`).
enum class MapMode { trinary, scale, raw };

/// The YAML half of a map_server map, as typed values.
struct MapMetadata {
  std::filesystem::path image;   ///< as written in the YAML file
  std::filesystem::path image_path;  ///< resolved: relative paths against the YAML file's folder
  double resolution_m = 0.05;    ///< side of a cell
  Pose2D origin;                 ///< map_from_grid: lower-left corner of the lower-left pixel
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  bool negate = false;
  MapMode mode = MapMode::trinary;
};

/// A greyscale raster as read from a PGM file: row 0 is the TOP row of the picture.
struct GrayImage {
  int width = 0;
  int height = 0;
  int maxval = 255;  ///< 1..65535; samples are 0..maxval
  std::vector<std::uint16_t> pixels;  ///< row-major, width * height
  [[nodiscard]] std::uint16_t at(int column, int row) const noexcept {
    return pixels[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) + static_cast<std::size_t>(column)];
  }
};

/// The largest image parse_pgm accepts: 2^26 pixels (8192 x 8192, a 409 m square at 5 cm per
/// cell). Larger headers are refused before anything is allocated.
inline constexpr std::size_t kMaxPgmPixels = std::size_t{1} << 26;

/// Parses a PGM image (P5 binary or P2 ASCII, maxval up to 65535; 16-bit samples big-endian as
/// the format says). name is used in errors. Throws ConfigError "NAME: at byte N: what, expected
/// ..." for a malformed header, a bad sample or a truncated raster; the header's size is checked
/// against kMaxPgmPixels and against the length of `bytes` before the raster is allocated.
[[nodiscard]] GrayImage parse_pgm(std::string_view bytes, const std::string& name);
/// Reads and parses a PGM file; ConfigError when it cannot be read or is malformed.
[[nodiscard]] GrayImage read_pgm(const std::filesystem::path& file);
/// Writes a binary (P5) PGM; 8-bit samples when maxval <= 255, else 16-bit big-endian.
/// Throws std::runtime_error when the file cannot be written.
void write_pgm(const std::filesystem::path& file, const GrayImage& image);

/// Parses a map_server YAML description. Required keys: image, resolution, origin [x, y, yaw],
/// occupied_thresh, free_thresh; optional: negate (0/1 or bool, default 0), mode (trinary, scale,
/// raw; default trinary). Every problem is collected and thrown as one ConfigError with
/// file:line:col per problem. The image file is not read here; image_path is resolved against
/// the folder of `file`.
[[nodiscard]] MapMetadata parse_map_yaml(std::string_view text, const std::filesystem::path& file);
[[nodiscard]] MapMetadata load_map_yaml(const std::filesystem::path& file);

/// The grid a map_server would publish for this image and metadata. Samples are first scaled to
/// 0..255 (v * 255 / maxval, rounded), then, exactly as map_server: if negate, v = 255 - v;
/// raw mode stores v itself (0..100 kept, anything else unknown); otherwise p = (255 - v) / 255,
/// occupied (100) when p > occupied_thresh, free (0) when p < free_thresh, else unknown (-1) in
/// trinary mode or 1 + 98 * (p - free) / (occupied - free) in scale mode. Image row 0 (the top)
/// becomes grid row height-1 (the highest y).
[[nodiscard]] OccupancyGrid grid_from_image(const GrayImage& image, const MapMetadata& meta);

/// A loaded map: the grid with the metadata it came from.
struct MapFile {
  OccupancyGrid grid;
  MapMetadata meta;
};

/// Loads a map_server map from its YAML file (the image is found relative to it).
/// Throws ConfigError with the location of every problem.
[[nodiscard]] MapFile load_map(const std::filesystem::path& yaml_file);

/// The picture map_saver would write for a grid: free 254, occupied 0, unknown 205, and scale
/// values as 255 * (1 - value / 100) rounded. Row 0 is the top (the highest y).
[[nodiscard]] GrayImage image_from_grid(const OccupancyGrid& grid);

/// Writes grid as yaml_file plus a PGM beside it (same stem, ".pgm"), trinary, thresholds 0.65
/// and 0.196 as map_saver does, so load_map(yaml_file) gives back an equal grid for grids of
/// states. Throws std::runtime_error when a file cannot be written.
void save_map(const OccupancyGrid& grid, const std::filesystem::path& yaml_file);

}  // namespace tripodal::navi
