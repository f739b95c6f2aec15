// PGM images (the raster half of a map_server map): an image that parses writes and reparses to
// the same samples; a rejected one is located "at byte N". The size limits (kMaxPgmPixels, the
// file's length) are what keep this target inside libFuzzer's malloc limit.
#include <filesystem>
#include <fstream>
#include <sstream>

#include <unistd.h>

#include "../fuzz_target.hpp"
#include "tripodal/navi/map_io.hpp"

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  navi::GrayImage image;
  try {
    image = navi::parse_pgm(fuzz::as_text(bytes), "fuzz.pgm");
  } catch (const ConfigError& e) {
    fuzz::require_located(e, "fuzz.pgm");
    return;
  }
  fuzz::require(image.pixels.size() == static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height),
                "a parsed image has width x height samples");
  // write_pgm writes a file: one per process, reused.
  static const std::filesystem::path file =
      std::filesystem::temp_directory_path() / ("tripodal-fuzz-" + std::to_string(::getpid()) + ".pgm");
  navi::write_pgm(file, image);
  const navi::GrayImage again = navi::read_pgm(file);
  fuzz::require(again.width == image.width && again.height == image.height && again.maxval == image.maxval &&
                    again.pixels == image.pixels,
                "a written image reads back with the same samples");
}
