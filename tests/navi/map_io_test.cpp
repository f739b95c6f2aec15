#include "tripodal/navi/map_io.hpp"

#include <sys/stat.h>

#include <catch2/catch.hpp>

#include <string>

#include "navi_test_util.hpp"
#include "tripodal/core/diagnostic.hpp"

using namespace tripodal;
using namespace tripodal::navi;
using tripodal::navi::test::TempDir;
using tripodal::navi::test::write_file;

namespace {

std::string p5(int w, int h, const std::vector<unsigned char>& px, int maxval = 255) {
  std::string s = "P5\n# made by a test\n" + std::to_string(w) + " " + std::to_string(h) + "\n" +
                  std::to_string(maxval) + "\n";
  for (const unsigned char c : px) s.push_back(static_cast<char>(c));
  return s;
}

const char* kYaml =
    "image: m.pgm\n"
    "resolution: 0.5\n"
    "origin: [-1.0, 2.0, 0.0]\n"
    "negate: 0\n"
    "occupied_thresh: 0.65\n"
    "free_thresh: 0.196\n";

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "(no exception)";
}

}  // namespace

TEST_CASE("map_io: a P5 map loads with map_server's thresholds and the top row at the highest y", "[navi][map]") {
  TempDir dir("p5");
  // 3 x 2 picture: top row black (occupied), white (free), 205 (unknown); bottom row 254, 100, 180
  write_file(dir / "m.pgm", p5(3, 2, {0, 255, 205, 254, 100, 180}));
  write_file(dir / "m.yaml", kYaml);
  const MapFile m = load_map(dir / "m.yaml");
  const OccupancyGrid& g = m.grid;
  REQUIRE(g.width() == 3);
  REQUIRE(g.height() == 2);
  CHECK(g.resolution_m() == 0.5);
  CHECK(g.origin() == Pose2D{-1.0, 2.0, 0.0});
  CHECK(g.state({0, 1}) == Occupancy::occupied);
  CHECK(g.state({1, 1}) == Occupancy::free);
  CHECK(g.state({2, 1}) == Occupancy::unknown);  // p = 50/255 = 0.196078 > 0.196
  CHECK(g.state({0, 0}) == Occupancy::free);
  CHECK(g.state({1, 0}) == Occupancy::unknown);  // p = 155/255 = 0.608 < 0.65
  CHECK(g.state({2, 0}) == Occupancy::unknown);  // p = 0.294
  CHECK(m.meta.image_path == dir / "m.pgm");
  CHECK(m.meta.mode == MapMode::trinary);
  // map frame: the top-left pixel covers x in [-1, -0.5), y in [2.5, 3)
  CHECK(g.world_to_cell({-0.9, 2.9}) == CellIndex{0, 1});
}

TEST_CASE("map_io: P2 ASCII, 16-bit samples, negate, scale and raw modes", "[navi][map]") {
  TempDir dir("modes");
  SECTION("P2 with comments") {
    write_file(dir / "m.pgm", "P2\n# comment\n3 1\n# another\n255\n0 255\n 120\n");
    write_file(dir / "m.yaml", kYaml);
    const OccupancyGrid g = load_map(dir / "m.yaml").grid;
    CHECK(g.state({0, 0}) == Occupancy::occupied);
    CHECK(g.state({1, 0}) == Occupancy::free);
    CHECK(g.state({2, 0}) == Occupancy::unknown);
  }
  SECTION("16-bit P5 samples scale to 8 bits") {
    // 65535 -> 255 free, 0 -> occupied, 52685 (~205.0) -> unknown
    write_file(dir / "m.pgm", p5(3, 1, {0xFF, 0xFF, 0x00, 0x00, 0xCD, 0xCD}, 65535));
    write_file(dir / "m.yaml", kYaml);
    const OccupancyGrid g = load_map(dir / "m.yaml").grid;
    CHECK(g.state({0, 0}) == Occupancy::free);
    CHECK(g.state({1, 0}) == Occupancy::occupied);
    CHECK(g.state({2, 0}) == Occupancy::unknown);
  }
  SECTION("maxval below 255 scales too") {
    write_file(dir / "m.pgm", "P2 2 1 15 15 0");
    write_file(dir / "m.yaml", kYaml);
    const OccupancyGrid g = load_map(dir / "m.yaml").grid;
    CHECK(g.state({0, 0}) == Occupancy::free);
    CHECK(g.state({1, 0}) == Occupancy::occupied);
  }
  SECTION("negate: black is free") {
    write_file(dir / "m.pgm", p5(2, 1, {0, 255}));
    std::string y = kYaml;
    y.replace(y.find("negate: 0"), 9, "negate: 1");
    write_file(dir / "m.yaml", y);
    const OccupancyGrid g = load_map(dir / "m.yaml").grid;
    CHECK(g.state({0, 0}) == Occupancy::free);
    CHECK(g.state({1, 0}) == Occupancy::occupied);
  }
  SECTION("scale: in-between probabilities are kept") {
    write_file(dir / "m.pgm", p5(3, 1, {0, 255, 128}));
    write_file(dir / "m.yaml", std::string(kYaml) + "mode: scale\n");
    const OccupancyGrid g = load_map(dir / "m.yaml").grid;
    CHECK(g.value({0, 0}) == 100);
    CHECK(g.value({1, 0}) == 0);
    // p = 127/255 = 0.498; 1 + 98 * (0.498 - 0.196) / (0.65 - 0.196) = 66.2
    CHECK(g.value({2, 0}) == 66);
    CHECK(g.state({2, 0}) == Occupancy::unknown);
  }
  SECTION("raw: the pixel is the value") {
    write_file(dir / "m.pgm", p5(4, 1, {0, 100, 37, 255}));
    write_file(dir / "m.yaml", std::string(kYaml) + "mode: raw\n");
    const OccupancyGrid g = load_map(dir / "m.yaml").grid;
    CHECK(g.value({0, 0}) == 0);
    CHECK(g.value({1, 0}) == 100);
    CHECK(g.value({2, 0}) == 37);
    CHECK(g.value({3, 0}) == -1);
  }
}

TEST_CASE("map_io: save_map and load_map round-trip", "[navi][map]") {
  TempDir dir("roundtrip");
  OccupancyGrid g(7, 5, 0.05, Pose2D{-3.25, 1.5, 0.25}, Occupancy::free);
  g.set_state({0, 0}, Occupancy::occupied);
  g.set_state({6, 4}, Occupancy::unknown);
  g.set_state({3, 2}, Occupancy::occupied);
  save_map(g, dir / "saved.yaml");
  CHECK(std::filesystem::exists(dir / "saved.pgm"));
  const MapFile back = load_map(dir / "saved.yaml");
  CHECK(back.grid == g);
  CHECK(back.meta.image == "saved.pgm");
  const GrayImage img = read_pgm(dir / "saved.pgm");
  CHECK(img.at(0, 4) == 0);    // cell (0,0) is the bottom-left pixel
  CHECK(img.at(6, 0) == 205);  // cell (6,4) is the top-right pixel
  CHECK(img.at(1, 1) == 254);
}

TEST_CASE("map_io: 16-bit PGM write/read round-trip", "[navi][map]") {
  TempDir dir("pgm16");
  GrayImage img{3, 2, 1000, {0, 1, 999, 1000, 500, 256}};
  write_pgm(dir / "w.pgm", img);
  const GrayImage back = read_pgm(dir / "w.pgm");
  CHECK(back.maxval == 1000);
  CHECK(back.pixels == img.pixels);
}

TEST_CASE("map_io: YAML errors are located and collected", "[navi][map][errors]") {
  const std::string bad =
      "image: m.pgm\n"
      "resolution: -0.05\n"
      "origin: [1, 2]\n"
      "occupied_thresh: 1.5\n"
      "free_thresh: 0.196\n"
      "negate: maybe\n"
      "mode: fancy\n"
      "colour: red\n";
  const std::string what = message_of([&] { (void)parse_map_yaml(bad, "dir/bad.yaml"); });
  CHECK_THAT(what, Catch::Contains("dir/bad.yaml:2:13: error: 'resolution' (metres per cell): expected a number > 0"));
  CHECK_THAT(what, Catch::Contains("dir/bad.yaml:3:9: error: 'origin': expected [x, y, yaw], got a list of 2 items"));
  CHECK_THAT(what, Catch::Contains("dir/bad.yaml:4:18: error: 'occupied_thresh': expected a probability in [0, 1], got 1.5"));
  CHECK_THAT(what, Catch::Contains("dir/bad.yaml:6:9: error: 'negate': expected true or false"));
  CHECK_THAT(what, Catch::Contains("dir/bad.yaml:7:7: error: 'mode': expected one of trinary, scale, raw; got 'fancy'"));
  CHECK_THAT(what, Catch::Contains("dir/bad.yaml:8:1: error: unknown key 'colour' in a map_server map description; expected one of: image, resolution,"));

  CHECK_THROWS_WITH(parse_map_yaml("image: m.pgm\nresolution: 0.05\n", "m.yaml"),
                    Catch::Contains("m.yaml:1:1: error: the map description: missing 'origin'") && Catch::Contains("missing 'free_thresh'"));
  CHECK_THROWS_WITH(parse_map_yaml("image: m.pgm\nresolution: abc\norigin: [0,0,0]\noccupied_thresh: 0.6\nfree_thresh: 0.2\n", "m.yaml"),
                    Catch::Contains("m.yaml:2:13: error: 'resolution' (metres per cell): expected a number > 0, got 'abc'"));
  CHECK_THROWS_WITH(parse_map_yaml("image: m.pgm\nresolution: 0.1\norigin: [0,0,0]\noccupied_thresh: 0.3\nfree_thresh: 0.4\n", "m.yaml"),
                    Catch::Contains("m.yaml:5:14: error: 'free_thresh' (0.4) must be below 'occupied_thresh' (0.3)"));
  CHECK_THROWS_WITH(parse_map_yaml("image: [a, b\n", "m.yaml"), Catch::Contains("m.yaml:"));
  CHECK_THROWS_WITH(parse_map_yaml("- 1\n- 2\n", "m.yaml"), Catch::Contains("m.yaml:1:1: error: a map_server map description: expected a map, got a list"));
}

TEST_CASE("map_io: PGM errors name the file and the byte", "[navi][map][errors]") {
  CHECK_THROWS_WITH(parse_pgm("P6\n1 1\n255\n\x01", "a.pgm"),
                    Catch::Contains("a.pgm: error: at byte 0: not a PGM image: expected the magic number P5"));
  CHECK_THROWS_WITH(parse_pgm("P5\n3 2\n255\nab", "t.pgm"),
                    Catch::Contains("t.pgm: error: at byte 13: raster truncated: expected 6 bytes for 3 x 2 samples, found 2"));
  CHECK_THROWS_WITH(parse_pgm("P5\n3 x\n255\n", "h.pgm"),
                    Catch::Contains("h.pgm: error: at byte 5: expected height (a decimal number), found 'x'"));
  CHECK_THROWS_WITH(parse_pgm("P5\n3 2\n70000\n", "m.pgm"),
                    Catch::Contains("at byte 7: maxval 70000 out of range: expected 1..65535"));
  CHECK_THROWS_WITH(parse_pgm("P2\n2 1\n10\n3 11\n", "s.pgm"),
                    Catch::Contains("at byte 12: sample 1 of 2 11 out of range: expected 0..10"));
  CHECK_THROWS_WITH(parse_pgm("P2\n2 1\n10\n3\n", "e.pgm"),
                    Catch::Contains("at byte 12: unexpected end of file: expected sample 1 of 2"));
  CHECK_THROWS_WITH(parse_pgm("P5\n1 1\n255", "n.pgm"),
                    Catch::Contains("at byte 10: expected one whitespace byte after maxval"));
  CHECK_THROWS_WITH(parse_pgm(std::string("P5\n1 1\n100\n\xC8", 12), "v.pgm"),
                    Catch::Contains("at byte 11: sample 200 exceeds maxval 100"));
  CHECK_THROWS_WITH(read_pgm("/nonexistent/x.pgm"), Catch::Contains("/nonexistent/x.pgm: error: cannot read the file"));
}

TEST_CASE("map_io: a missing image is reported with the resolved path", "[navi][map][errors]") {
  TempDir dir("missing");
  write_file(dir / "m.yaml", kYaml);
  CHECK_THROWS_WITH(load_map(dir / "m.yaml"), Catch::Contains((dir / "m.pgm").string() + ": error: cannot read the file"));
}

TEST_CASE("map_io: a PGM header larger than the file or the maximum is refused before allocation",
          "[navi][map][errors][limits]") {
  // Found by hand (issue 23): a 20-byte file declaring 10^12 pixels ended `tripodal run` with
  // std::bad_alloc, the raster being allocated before the file was checked to hold it.
  TempDir dir("huge");
  write_file(dir / "m.yaml", kYaml);
  const std::string huge = "P5 1000000 1000000 1";
  REQUIRE(huge.size() == 20);
  write_file(dir / "m.pgm", huge);
  CHECK_THROWS_WITH(load_map(dir / "m.yaml"),
                    Catch::Contains((dir / "m.pgm").string() + ": error: at byte 3: image of 1000000 x 1000000 = "
                                    "1000000000000 pixels exceeds the maximum of 67108864 pixels"));
  // Within the maximum but longer than the file: refused from the sizes alone, binary and ASCII.
  CHECK_THROWS_WITH(parse_pgm("P5\n8000 8000\n255\n", "b.pgm"),
                    Catch::Contains("b.pgm: error: at byte 17: raster truncated: expected 64000000 bytes for 8000 x "
                                    "8000 samples, found 0"));
  CHECK_THROWS_WITH(parse_pgm("P5\n8000 8000\n65535\n", "w.pgm"),
                    Catch::Contains("w.pgm: error: at byte 19: raster truncated: expected 128000000 bytes"));
  CHECK_THROWS_WITH(parse_pgm("P2\n8000 8000\n255\n1 2 3\n", "a.pgm"),
                    Catch::Contains("a.pgm: error: at byte 23: raster truncated: 8000 x 8000 ASCII samples need at "
                                    "least 64000000 bytes, found 7"));
  // The largest side alone is fine when the other is small.
  const GrayImage strip = parse_pgm("P5\n1048576 1\n255\n" + std::string(1 << 20, '\x10'), "s.pgm");
  CHECK(strip.pixels.size() == std::size_t{1} << 20);
}

TEST_CASE("map_io: a map file beyond the configuration file limit is refused unread", "[navi][map][errors][limits]") {
  TempDir dir("big");
  write_file(dir / "m.yaml", kYaml);
  {
    std::ofstream f(dir / "m.pgm", std::ios::binary);
    f << "P5\n1 1\n255\n";
  }
  // A sparse file: the size is what counts, nothing is read.
  std::filesystem::resize_file(dir / "m.pgm", kMaxConfigFileBytes + 1);
  CHECK_THROWS_WITH(load_map(dir / "m.yaml"),
                    Catch::Contains((dir / "m.pgm").string() + ": error: the file has 268435457 bytes, more than the "
                                    "268435456 a configuration file may have"));
}

TEST_CASE("map_io: only a regular file is read as a map image or description", "[navi][map][errors][limits]") {
  // Before, /dev/zero was read until memory ran out and a FIFO blocked the load for ever.
  TempDir dir("special");
  const auto with_image = [&](const std::string& image) {
    std::string y = kYaml;
    y.replace(y.find("m.pgm"), 5, image);
    write_file(dir / "m.yaml", y);
  };
  with_image("/dev/zero");
  CHECK_THROWS_WITH(load_map(dir / "m.yaml"),
                    Catch::Contains("/dev/zero: error: cannot read a character device: a configuration file must be a regular file"));
  std::filesystem::create_directories(dir / "d.pgm");
  with_image("d.pgm");
  CHECK_THROWS_WITH(load_map(dir / "m.yaml"), Catch::Contains((dir / "d.pgm").string() + ": error: cannot read a directory"));
  REQUIRE(::mkfifo((dir / "f.pgm").c_str(), 0600) == 0);
  with_image("f.pgm");
  CHECK_THROWS_WITH(load_map(dir / "m.yaml"), Catch::Contains((dir / "f.pgm").string() + ": error: cannot read a FIFO"));
  // The description itself too.
  CHECK_THROWS_WITH(load_map("/dev/zero"), Catch::Contains("/dev/zero: error: cannot read a character device"));
}
