// The decoder allocates nothing per frame (nor ever): counted with a replaced operator new.
#include <array>
#include <catch2/catch.hpp>
#include <vector>

#include "../support/counting_new.hpp"
#include "tripodal/board/commands.hpp"
#include "tripodal/board/frame.hpp"
#include "tripodal/board/rplidar_a1.hpp"
#include "tripodal/board/serial_line.hpp"
#include "tripodal/sim/rplidar_emulator.hpp"

using namespace tripodal::board;

TEST_CASE("decoding and encoding frames allocates nothing", "[board][alloc]") {
  std::vector<std::uint8_t> stream;
  std::array<std::uint8_t, kMaxFrameBytes> out{};
  for (int i = 0; i < 1000; ++i) {
    std::array<std::uint8_t, 4> p{static_cast<std::uint8_t>(i), 0, static_cast<std::uint8_t>(i >> 8), 0};
    const std::size_t n = encode_request(0x12, p, out);
    stream.insert(stream.end(), out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n));
    if (i % 10 == 0) stream.push_back(0x77);  // garbage
  }
  FrameDecoder decoder;
  const std::size_t before = tripodal::test::allocations();
  std::size_t frames = 0;
  for (std::size_t i = 0; i < stream.size(); i += 13) {
    frames += decoder.feed(std::span<const std::uint8_t>(stream).subspan(i, std::min<std::size_t>(13, stream.size() - i)));
  }
  std::array<std::uint8_t, 4> p{1, 2, 3, 4};
  const std::size_t n = encode_request(0x12, p, out);
  const std::size_t after = tripodal::test::allocations();
  CHECK(n == 9);
  CHECK(frames == 1000);
  CHECK(decoder.stats().garbage_runs == 100);
  CHECK(after == before);
}

TEST_CASE("the RPLIDAR driver's scanning cycle allocates nothing, garbage included", "[board][alloc][rplidar]") {
  // The A1 emulator on the in-process line's far end, the driver on the near one, one clock.
  struct Flat final : tripodal::sim::LidarScene {
    double range_m(double, tripodal::Time) const noexcept override { return 3.0; }
  } scene;
  tripodal::SimClock clock{tripodal::Time{std::chrono::seconds(1)}};
  SerialLine line(clock);
  tripodal::sim::RplidarEmulator emulator(line.board(), scene, {}, clock.now());
  RplidarA1 lidar("laser", line.host(), RplidarConfig{});
  const auto run_for = [&](std::chrono::milliseconds d) {
    for (std::chrono::milliseconds t{0}; t < d; ++t) {
      clock.advance(std::chrono::milliseconds(1));
      emulator.run_until(clock.now());
      lidar.poll(clock.now());
    }
  };
  run_for(std::chrono::milliseconds(1000));
  REQUIRE(lidar.state() == RplidarA1::State::scanning);
  REQUIRE(lidar.stats().scans >= 2);  // the scan's storage exists
  const std::size_t before = tripodal::test::allocations();
  const std::array<std::uint8_t, 7> garbage{0xFF, 0x00, 0xFF, 0xFC, 0xFF, 0x13, 0x00};
  emulator.inject(garbage);
  run_for(std::chrono::milliseconds(2000));
  const std::size_t after = tripodal::test::allocations();
  CHECK(lidar.stats().scans >= 12);
  CHECK(lidar.stats().decoder_errors >= 1);
  CHECK(after == before);
}
