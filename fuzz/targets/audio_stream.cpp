// The listener's segmentation of a microphone stream (hri/listener.hpp, docs/hri.md "Listening to
// a stream"): any samples, any options within their ranges, any chunking. The utterances come in
// order without overlapping, each clip is the stream's own samples around its speech, and feeding
// the same stream in other chunks gives the same utterances.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>

#include "../fuzz_target.hpp"
#include "tripodal/hri/listener.hpp"

namespace {

using tripodal::SegmentedUtterance;
using tripodal::UtteranceSegmenter;
using tripodal::VadOptions;

std::vector<SegmentedUtterance> segment(const std::vector<std::int16_t>& stream, int rate, const VadOptions& o,
                                        const std::vector<std::size_t>& chunks) {
  UtteranceSegmenter s(rate, o);
  std::vector<SegmentedUtterance> out;
  std::size_t at = 0;
  std::size_t i = 0;
  while (at < stream.size()) {
    const std::size_t n = std::min(stream.size() - at, chunks.empty() ? stream.size() : chunks[i++ % chunks.size()]);
    for (auto& u : s.feed(std::span<const std::int16_t>(stream).subspan(at, n))) out.push_back(std::move(u));
    at += n;
  }
  for (auto& u : s.finish()) out.push_back(std::move(u));
  return out;
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  if (bytes.size() < 8) return;
  // A small rate keeps the frames short, so that a short input holds many of them.
  const int rate = 100 + bytes[0] * 8;
  VadOptions o;
  o.frame_s = 0.005 + bytes[1] % 8 * 0.005;
  o.threshold_db = bytes[2] % 30;
  o.start_speech_s = bytes[3] % 10 * 0.01;
  o.end_silence_s = bytes[4] % 20 * 0.02;
  o.pre_roll_s = bytes[5] % 8 * 0.05;
  o.post_roll_s = bytes[6] % 8 * 0.05;
  o.max_utterance_s = 0.05 + bytes[7] % 16 * 0.1;
  o.min_level_dbfs = -80.0;
  std::vector<std::int16_t> stream((bytes.size() - 8) / 2);
  if (!stream.empty()) std::memcpy(stream.data(), bytes.data() + 8, stream.size() * 2);
  std::vector<std::size_t> chunks;
  for (std::size_t i = 8; i < std::min<std::size_t>(bytes.size(), 24); ++i) chunks.push_back(1 + bytes[i] % 64);

  std::vector<SegmentedUtterance> whole;
  try {
    whole = segment(stream, rate, o, {});
  } catch (const std::invalid_argument&) {
    return;  // options that make no frame (a frame shorter than a sample): refused, as documented
  }
  const std::vector<SegmentedUtterance> chunked = segment(stream, rate, o, chunks);
  fuzz::require(whole.size() == chunked.size(), "the chunking changed how many utterances were found");
  double previous_end = 0.0;
  for (std::size_t i = 0; i < whole.size(); ++i) {
    const SegmentedUtterance& u = whole[i];
    fuzz::require(u.start_s == chunked[i].start_s && u.end_s == chunked[i].end_s && u.clip.samples == chunked[i].clip.samples,
                  "the chunking changed an utterance");
    fuzz::require(u.start_s < u.end_s, "an utterance ends before it starts");
    fuzz::require(u.start_s >= previous_end - 1e-9, "utterances overlap or come out of order");
    previous_end = u.end_s;
    fuzz::require(!u.clip.samples.empty() && u.clip.sample_rate_hz == rate, "an utterance has no audio");
    // The clip is the stream's samples, from at most the pre-roll before the speech to at least
    // the end of the speech (a cut one: exactly to the cut).
    const auto start = static_cast<std::size_t>(std::lround(u.start_s * rate));
    const auto end = static_cast<std::size_t>(std::lround(u.end_s * rate));
    const std::size_t len = u.clip.samples.size();
    bool found = false;
    const auto pre_roll = static_cast<std::size_t>(std::lround(o.pre_roll_s * rate));
    for (std::size_t first = start - std::min(start, pre_roll); first <= start && !found; ++first) {
      found = first + len <= stream.size() && first + len >= end &&
              std::equal(u.clip.samples.begin(), u.clip.samples.end(), stream.begin() + static_cast<std::ptrdiff_t>(first));
    }
    fuzz::require(found, "an utterance's clip is not the stream's samples around its speech");
  }
}
