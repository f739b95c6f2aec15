// Control-board decoder throughput (issue 17's target: at least 100 MB/s, no allocation): a stream
// of DRIVE responses (the control cycle's frame, 23 bytes) fed in 4 KiB reads, and the same with
// 1 % garbage bytes between frames.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <vector>

#include "instructions.hpp"
#include "tripodal/board/commands.hpp"
#include "tripodal/board/frame.hpp"

using namespace tripodal::board;

namespace {

std::vector<std::uint8_t> drive_stream(std::size_t frames, bool garbage) {
  std::vector<std::uint8_t> stream;
  std::array<std::uint8_t, kMaxFrameBytes> out{};
  std::array<std::uint8_t, 32> payload{};
  for (std::size_t i = 0; i < frames; ++i) {
    ByteWriter w(payload);
    pack(w, DriveState{{static_cast<std::int32_t>(i), -static_cast<std::int32_t>(i), 200, 210}, 0, 0, kStatusSynchronised});
    const std::size_t n = encode_response(static_cast<std::uint8_t>(Command::drive), w.written(), out);
    stream.insert(stream.end(), out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n));
    if (garbage && i % 4 == 0) stream.push_back(0x77);  // ~1 % of the bytes
  }
  return stream;
}

void decode(benchmark::State& state, bool garbage) {
  const std::vector<std::uint8_t> stream = drive_stream(10000, garbage);
  FrameDecoder decoder;
  std::size_t frames = 0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < stream.size(); i += 4096) {
      frames += decoder.feed(std::span<const std::uint8_t>(stream).subspan(i, std::min<std::size_t>(4096, stream.size() - i)));
    }
  }
  benchmark::DoNotOptimize(frames);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * stream.size()));
  state.counters["frames/s"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}

void BM_DecodeDriveResponses(benchmark::State& state) { decode(state, false); }
void BM_DecodeDriveResponsesWithGarbage(benchmark::State& state) { decode(state, true); }

}  // namespace

BENCHMARK(BM_DecodeDriveResponses);
BENCHMARK(BM_DecodeDriveResponsesWithGarbage);
// The instruction-count guard's twins (bench/instructions.yaml).
[[maybe_unused]] static const bool kDecodeTwins[] = {
    tripodal::bench::register_instruction_twin("BM_DecodeDriveResponses", BM_DecodeDriveResponses),
    tripodal::bench::register_instruction_twin("BM_DecodeDriveResponsesWithGarbage", BM_DecodeDriveResponsesWithGarbage),
};
BENCHMARK_MAIN();
