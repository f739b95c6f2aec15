#include "tripodal/navi/map_io.hpp"

#include <fmt/format.h>

#include <cctype>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>
#include <tuple>

#include "tripodal_common_internal/yaml_reader.hpp"

namespace tripodal::navi {

namespace {

// ---------------------------------------------------------------- PGM

class PgmParser {
 public:
  PgmParser(std::string_view bytes, const std::string& name) : b_(bytes), name_(name) {}

  GrayImage parse() {
    if (b_.size() < 2 || b_[0] != 'P' || (b_[1] != '5' && b_[1] != '2')) {
      fail(0, "not a PGM image: expected the magic number P5 (binary) or P2 (ASCII)");
    }
    const bool ascii = b_[1] == '2';
    pos_ = 2;
    if (pos_ >= b_.size() || (std::isspace(static_cast<unsigned char>(b_[pos_])) == 0 && b_[pos_] != '#')) {
      fail(pos_, "expected whitespace after the magic number");
    }
    GrayImage img;
    skip_space();
    const std::size_t size_at = pos_;
    img.width = header_int("width", 1, 1 << 20);
    img.height = header_int("height", 1, 1 << 20);
    const std::size_t n = static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height);
    // The header's numbers are checked against the documented maximum and against the bytes the
    // file holds before anything is allocated, so a 20-byte file cannot ask for a terabyte.
    if (n > kMaxPgmPixels) {
      fail(size_at, "image of " + std::to_string(img.width) + " x " + std::to_string(img.height) + " = " +
                        std::to_string(n) + " pixels exceeds the maximum of " + std::to_string(kMaxPgmPixels) +
                        " pixels");
    }
    img.maxval = header_int("maxval", 1, 65535);
    if (ascii) {
      // Each ASCII sample takes at least one digit.
      if (b_.size() - pos_ < n) {
        fail(b_.size(), "raster truncated: " + std::to_string(img.width) + " x " + std::to_string(img.height) +
                            " ASCII samples need at least " + std::to_string(n) + " bytes, found " +
                            std::to_string(b_.size() - pos_));
      }
      img.pixels.resize(n);
      for (std::size_t i = 0; i < n; ++i) {
        img.pixels[i] = static_cast<std::uint16_t>(
            header_int("sample " + std::to_string(i) + " of " + std::to_string(n), 0, img.maxval));
      }
      return img;
    }
    // Exactly one whitespace byte separates maxval from the raster.
    if (pos_ >= b_.size() || std::isspace(static_cast<unsigned char>(b_[pos_])) == 0) {
      fail(pos_, "expected one whitespace byte after maxval, before the raster");
    }
    ++pos_;
    const std::size_t bytes_per = img.maxval > 255 ? 2 : 1;
    const std::size_t need = n * bytes_per;
    if (b_.size() - pos_ < need) {
      fail(b_.size(), "raster truncated: expected " + std::to_string(need) + " bytes for " +
                          std::to_string(img.width) + " x " + std::to_string(img.height) + " samples, found " +
                          std::to_string(b_.size() - pos_));
    }
    img.pixels.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t at = pos_ + i * bytes_per;
      unsigned v = static_cast<unsigned char>(b_[at]);
      if (bytes_per == 2) v = (v << 8U) | static_cast<unsigned char>(b_[at + 1]);
      if (v > static_cast<unsigned>(img.maxval)) {
        fail(at, "sample " + std::to_string(v) + " exceeds maxval " + std::to_string(img.maxval));
      }
      img.pixels[i] = static_cast<std::uint16_t>(v);
    }
    return img;
  }

 private:
  [[noreturn]] void fail(std::size_t at, const std::string& what) const {
    throw ConfigError(SourceLocation{name_, 0, 0}, "at byte " + std::to_string(at) + ": " + what);
  }

  // Skips whitespace and '#' comments (which run to the end of the line).
  void skip_space() {
    while (pos_ < b_.size()) {
      const char c = b_[pos_];
      if (c == '#') {
        while (pos_ < b_.size() && b_[pos_] != '\n' && b_[pos_] != '\r') ++pos_;
      } else if (std::isspace(static_cast<unsigned char>(c)) != 0) {
        ++pos_;
      } else {
        break;
      }
    }
  }

  int header_int(const std::string& what, int lo, int hi) {
    skip_space();
    const std::size_t start = pos_;
    long long v = 0;
    while (pos_ < b_.size() && std::isdigit(static_cast<unsigned char>(b_[pos_])) != 0) {
      v = v * 10 + (b_[pos_] - '0');
      if (v > std::numeric_limits<int>::max()) fail(start, what + " is too large");
      ++pos_;
    }
    if (pos_ == start) {
      if (pos_ >= b_.size()) fail(pos_, "unexpected end of file: expected " + what);
      fail(pos_, "expected " + what + " (a decimal number), found '" + std::string(1, b_[pos_]) + "'");
    }
    if (v < lo || v > hi) {
      fail(start, what + " " + std::to_string(v) + " out of range: expected " + std::to_string(lo) + ".." +
                      std::to_string(hi));
    }
    return static_cast<int>(v);
  }

  std::string_view b_;
  const std::string& name_;
  std::size_t pos_ = 0;
};

// ---------------------------------------------------------------- YAML

const char* mode_name(MapMode m) {
  switch (m) {
    case MapMode::trinary: return "trinary";
    case MapMode::scale: return "scale";
    case MapMode::raw: return "raw";
  }
  return "trinary";
}

}  // namespace

GrayImage parse_pgm(std::string_view bytes, const std::string& name) { return PgmParser(bytes, name).parse(); }

GrayImage read_pgm(const std::filesystem::path& file) {
  const std::string bytes = yaml::read_file(file);
  return parse_pgm(bytes, file.string());
}

void write_pgm(const std::filesystem::path& file, const GrayImage& image) {
  std::ofstream out(file, std::ios::binary);
  if (!out) throw std::runtime_error("cannot write " + file.string());
  out << "P5\n" << image.width << ' ' << image.height << '\n' << image.maxval << '\n';
  std::string raster;
  const bool wide = image.maxval > 255;
  raster.reserve(image.pixels.size() * (wide ? 2 : 1));
  for (const std::uint16_t v : image.pixels) {
    if (wide) raster.push_back(static_cast<char>(v >> 8U));
    raster.push_back(static_cast<char>(v & 0xFFU));
  }
  out.write(raster.data(), static_cast<std::streamsize>(raster.size()));
  if (!out) throw std::runtime_error("cannot write " + file.string());
}

namespace {

MapMetadata walk_map_yaml(std::string_view text, const std::filesystem::path& file) {
  const std::string name = file.string();
  const YAML::Node root = yaml::parse(text, name);
  Diagnostics d;
  yaml::Reader r(name, d);
  MapMetadata m;
  if (!r.expect_keys(root, {"image", "resolution", "origin", "occupied_thresh", "free_thresh", "negate", "mode"},
                     "a map_server map description")) {
    throw ConfigError(d);
  }
  const YAML::Node image = r.require(root, "image", "the map description", "the PGM file, relative to this file");
  const YAML::Node res = r.require(root, "resolution", "the map description", "metres per cell");
  const YAML::Node origin = r.require(root, "origin", "the map description", "[x, y, yaw] of the lower-left pixel");
  const YAML::Node occ_node = r.require(root, "occupied_thresh", "the map description", "e.g. 0.65");
  const YAML::Node free_node = r.require(root, "free_thresh", "the map description", "e.g. 0.196");
  if (image) {
    if (auto file_name = r.text(image, "'image' (a file name)", true)) {
      m.image = *file_name;
      m.image_path = m.image.is_absolute() ? m.image : file.parent_path() / m.image;
    }
  }
  if (res) {
    if (auto v = r.positive(res, "'resolution' (metres per cell)")) m.resolution_m = *v;
  }
  if (origin) {
    if (auto v = r.numbers(origin, "'origin'", 3, 3, "[x, y, yaw]")) m.origin = Pose2D{(*v)[0], (*v)[1], (*v)[2]};
  }
  for (const auto& [node, key, out] : {std::tuple{occ_node, "occupied_thresh", &m.occupied_thresh},
                                       std::tuple{free_node, "free_thresh", &m.free_thresh}}) {
    if (!node) continue;
    if (auto t = r.number(node, fmt::format("'{}'", key))) {
      if (*t < 0.0 || *t > 1.0) r.error(node, fmt::format("'{}': expected a probability in [0, 1], got {}", key, node.Scalar()));
      else *out = *t;
    }
  }
  if (const YAML::Node negate = root["negate"]) {
    if (auto v = r.boolean(negate, "'negate'")) m.negate = *v;
  }
  if (const YAML::Node mode = root["mode"]) {
    if (auto v = r.choice(mode, "'mode'", {"trinary", "scale", "raw"})) {
      m.mode = *v == "scale" ? MapMode::scale : *v == "raw" ? MapMode::raw : MapMode::trinary;
    }
  }
  if (occ_node && free_node && !d.has_errors() && !(m.free_thresh < m.occupied_thresh)) {
    r.error(free_node, "'free_thresh' (" + free_node.Scalar() + ") must be below 'occupied_thresh' (" + occ_node.Scalar() + ")");
  }
  if (d.has_errors()) throw ConfigError(d);
  return m;
}

}  // namespace

MapMetadata parse_map_yaml(std::string_view text, const std::filesystem::path& file) {
  return yaml::guarded(file.string(), [&] { return walk_map_yaml(text, file); });
}

MapMetadata load_map_yaml(const std::filesystem::path& file) {
  return parse_map_yaml(yaml::read_file(file), file);
}

OccupancyGrid grid_from_image(const GrayImage& image, const MapMetadata& meta) {
  OccupancyGrid grid(image.width, image.height, meta.resolution_m, meta.origin, Occupancy::unknown);
  const double span = meta.occupied_thresh - meta.free_thresh;
  for (int row = 0; row < image.height; ++row) {
    for (int col = 0; col < image.width; ++col) {
      const unsigned raw = image.at(col, row);
      double v = image.maxval == 255 ? raw : std::round(raw * 255.0 / image.maxval);
      if (meta.negate) v = 255.0 - v;
      std::int8_t value = kUnknownValue;
      if (meta.mode == MapMode::raw) {
        value = v <= 100.0 ? static_cast<std::int8_t>(v) : kUnknownValue;
      } else {
        const double p = (255.0 - v) / 255.0;
        if (p > meta.occupied_thresh) value = kOccupiedValue;
        else if (p < meta.free_thresh) value = kFreeValue;
        else if (meta.mode == MapMode::scale) value = static_cast<std::int8_t>(1.0 + 98.0 * (p - meta.free_thresh) / span);
      }
      grid.set_value({col, image.height - 1 - row}, value);
    }
  }
  return grid;
}

MapFile load_map(const std::filesystem::path& yaml_file) {
  MapFile out;
  out.meta = load_map_yaml(yaml_file);
  const GrayImage img = read_pgm(out.meta.image_path);
  out.grid = grid_from_image(img, out.meta);
  return out;
}

GrayImage image_from_grid(const OccupancyGrid& grid) {
  GrayImage img;
  img.width = grid.width();
  img.height = grid.height();
  img.maxval = 255;
  img.pixels.resize(grid.size());
  for (int y = 0; y < grid.height(); ++y) {
    for (int x = 0; x < grid.width(); ++x) {
      const std::int8_t v = grid.value({x, y});
      std::uint16_t px = 205;
      if (v == kFreeValue) px = 254;
      else if (v == kOccupiedValue) px = 0;
      else if (v > 0) px = static_cast<std::uint16_t>(std::lround(255.0 * (1.0 - v / 100.0)));
      img.pixels[static_cast<std::size_t>(grid.height() - 1 - y) * static_cast<std::size_t>(img.width) +
                 static_cast<std::size_t>(x)] = px;
    }
  }
  return img;
}

void save_map(const OccupancyGrid& grid, const std::filesystem::path& yaml_file) {
  std::filesystem::path pgm = yaml_file;
  pgm.replace_extension(".pgm");
  write_pgm(pgm, image_from_grid(grid));
  std::ofstream out(yaml_file);
  if (!out) throw std::runtime_error("cannot write " + yaml_file.string());
  out.precision(17);
  out << "image: " << pgm.filename().string() << '\n'
      << "resolution: " << grid.resolution_m() << '\n'
      << "origin: [" << grid.origin().x_m << ", " << grid.origin().y_m << ", " << grid.origin().theta_rad << "]\n"
      << "negate: 0\n"
      << "occupied_thresh: 0.65\n"
      << "free_thresh: 0.196\n"
      << "mode: " << mode_name(MapMode::trinary) << '\n';
  if (!out) throw std::runtime_error("cannot write " + yaml_file.string());
}

}  // namespace tripodal::navi
