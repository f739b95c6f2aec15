// Control-board decoder throughput (issue 17's target: at least 100 MB/s, no allocation): a stream
// of DRIVE responses (the control cycle's frame, 22 bytes) fed in 4 KiB reads, and the same with
// 1 % garbage bytes between frames; per protocol profile (issue 35): tripodal-v1, the thesis's
// (its host decoder also looks for the TYPE of a SYNC echo), and the thesis's with an 8-bit sum
// or XOR, plus the board's side decoding DRIVE requests.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <vector>

#include "instructions.hpp"
#include "tripodal/board/commands.hpp"
#include "tripodal/board/frame.hpp"
#include "tripodal/board/protocol_profile.hpp"

using namespace tripodal::board;

namespace {

std::vector<std::uint8_t> drive_stream(std::size_t frames, bool garbage, const FrameFormat& format = kTripodalV1Format) {
  std::vector<std::uint8_t> stream;
  std::array<std::uint8_t, kMaxFrameBytes> out{};
  std::array<std::uint8_t, 32> payload{};
  for (std::size_t i = 0; i < frames; ++i) {
    ByteWriter w(payload);
    pack(w, DriveState{{static_cast<std::int32_t>(i), -static_cast<std::int32_t>(i), 200, 210}, 0, 0, kStatusSynchronised});
    const std::size_t n = encode_response(static_cast<std::uint8_t>(Command::drive), w.written(), out, format);
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

FrameFormat thesis_with(ChecksumKind k) {
  FrameFormat f = thesis_profile().frame;
  f.checksum = k;
  return f;
}

// One profile's stream through its decoder of `side`.
void decode_profile(benchmark::State& state, const FrameFormat& format, FrameSide side) {
  std::vector<std::uint8_t> stream;
  if (side == FrameSide::responses) {
    stream = drive_stream(10000, false, format);
  } else {
    std::array<std::uint8_t, kMaxFrameBytes> out{};
    const std::array<std::uint8_t, 4> speeds{0xC8, 0x00, 0xFA, 0x00};
    for (std::size_t i = 0; i < 10000; ++i) {
      const std::size_t n = encode_request(0x12, speeds, out, format);
      stream.insert(stream.end(), out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n));
    }
  }
  FrameDecoder decoder(format, side);
  std::size_t frames = 0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < stream.size(); i += 4096) {
      frames += decoder.feed(std::span<const std::uint8_t>(stream).subspan(i, std::min<std::size_t>(4096, stream.size() - i)));
    }
  }
  benchmark::DoNotOptimize(frames);
  if (decoder.stats().errors() != 0) state.SkipWithError("decoder errors on a clean stream");
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * stream.size()));
  state.counters["frames/s"] = benchmark::Counter(static_cast<double>(frames), benchmark::Counter::kIsRate);
}

void BM_Profile_TripodalV1_Responses(benchmark::State& s) { decode_profile(s, kTripodalV1Format, FrameSide::responses); }
void BM_Profile_Thesis_Responses(benchmark::State& s) { decode_profile(s, thesis_profile().frame, FrameSide::responses); }
void BM_Profile_Thesis_Requests(benchmark::State& s) { decode_profile(s, thesis_profile().frame, FrameSide::requests); }
void BM_Profile_ThesisSum8_Responses(benchmark::State& s) { decode_profile(s, thesis_with(ChecksumKind::sum8), FrameSide::responses); }
void BM_Profile_ThesisXor8_Responses(benchmark::State& s) { decode_profile(s, thesis_with(ChecksumKind::xor8), FrameSide::responses); }

}  // namespace

BENCHMARK(BM_DecodeDriveResponses);
BENCHMARK(BM_DecodeDriveResponsesWithGarbage);
BENCHMARK(BM_Profile_TripodalV1_Responses);
BENCHMARK(BM_Profile_Thesis_Responses);
BENCHMARK(BM_Profile_Thesis_Requests);
BENCHMARK(BM_Profile_ThesisSum8_Responses);
BENCHMARK(BM_Profile_ThesisXor8_Responses);
// The instruction-count guard's twins (bench/instructions.yaml).
[[maybe_unused]] static const bool kDecodeTwins[] = {
    tripodal::bench::register_instruction_twin("BM_DecodeDriveResponses", BM_DecodeDriveResponses),
    tripodal::bench::register_instruction_twin("BM_DecodeDriveResponsesWithGarbage", BM_DecodeDriveResponsesWithGarbage),
};
BENCHMARK_MAIN();
