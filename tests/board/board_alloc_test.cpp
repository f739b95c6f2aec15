// The decoder allocates nothing per frame (nor ever): counted with a replaced operator new.
#include <catch2/catch.hpp>

#include <array>
#include <vector>

#include "../support/counting_new.hpp"
#include "tripodal/board/commands.hpp"
#include "tripodal/board/frame.hpp"

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
