#include "tripodal/hri/listener.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

#include "spoken_jinny.hpp"
#include "tripodal/hri/hri_module.hpp"

using namespace tripodal;

namespace {

constexpr int kRate = 16000;

// A recording built piece by piece: room noise, voiced bursts (a 150 Hz buzz with harmonics, like
// a vowel), silence. Times in seconds.
struct Recording {
  AudioClip clip{kRate, {}};
  std::mt19937 noise{7};
  double noise_amplitude = 30.0;  // about -61 dBFS

  double now() const { return static_cast<double>(clip.samples.size()) / kRate; }
  void room(double seconds) { add(seconds, 0.0); }
  void voice(double seconds, double amplitude = 6000.0) { add(seconds, amplitude); }
  void add(double seconds, double amplitude) {
    std::uniform_real_distribution<double> n(-noise_amplitude, noise_amplitude);
    const auto count = static_cast<std::size_t>(std::lround(seconds * kRate));
    for (std::size_t i = 0; i < count; ++i) {
      const double t = static_cast<double>(clip.samples.size()) / kRate;
      double v = n(noise);
      for (int h = 1; h <= 4; ++h) v += amplitude / h * std::sin(2.0 * std::numbers::pi * 150.0 * h * t);
      clip.samples.push_back(static_cast<std::int16_t>(std::clamp(v, -32768.0, 32767.0)));
    }
  }
};

std::vector<SegmentedUtterance> segment(const AudioClip& clip, std::size_t chunk, VadOptions options = {}) {
  UtteranceSegmenter s(clip.sample_rate_hz, options);
  std::vector<SegmentedUtterance> out;
  for (std::size_t at = 0; at < clip.samples.size(); at += chunk) {
    const std::size_t n = std::min(chunk, clip.samples.size() - at);
    for (auto& u : s.feed(std::span<const std::int16_t>(clip.samples).subspan(at, n))) out.push_back(std::move(u));
  }
  for (auto& u : s.finish()) out.push_back(std::move(u));
  return out;
}

}  // namespace

TEST_CASE("utterances are found in a stream: starts and ends, a pause inside kept, a click ignored") {
  Recording r;
  r.room(1.0);
  const double first_start = r.now();
  r.voice(0.8);
  const double first_end = r.now();
  r.room(1.0);
  const double second_start = r.now();
  r.voice(0.5);
  r.room(0.2);  // a pause between words: shorter than end_silence_s
  r.voice(0.6);
  const double second_end = r.now();
  r.room(1.0);
  r.voice(0.03);  // a click
  r.room(1.0);

  const std::vector<SegmentedUtterance> found = segment(r.clip, 160);
  REQUIRE(found.size() == 2);
  CHECK(found[0].start_s == Approx(first_start).margin(0.02));
  CHECK(found[0].end_s == Approx(first_end).margin(0.02));
  CHECK(found[1].start_s == Approx(second_start).margin(0.02));
  CHECK(found[1].end_s == Approx(second_end).margin(0.02));
  for (const auto& u : found) {
    CHECK_FALSE(u.truncated);
    CHECK(u.clip.sample_rate_hz == kRate);
    // The speech and a quarter second of room before and after it, for the recognizer.
    CHECK(u.clip.duration_s() == Approx(u.end_s - u.start_s + 0.5).margin(0.02));
  }
  // The clip is the stream's own samples from the pre-roll on.
  const auto from = static_cast<std::size_t>(std::lround((found[1].start_s - 0.25) * kRate));
  CHECK(std::equal(found[1].clip.samples.begin(), found[1].clip.samples.end(), r.clip.samples.begin() + static_cast<std::ptrdiff_t>(from)));
}

TEST_CASE("the segmentation does not depend on how the stream is chunked") {
  Recording r;
  r.room(0.5);
  r.voice(0.7);
  r.room(0.6);
  r.voice(0.4);
  r.room(0.3);
  const std::vector<SegmentedUtterance> reference = segment(r.clip, r.clip.samples.size());
  REQUIRE(reference.size() == 2);
  for (const std::size_t chunk : {std::size_t{1}, std::size_t{7}, std::size_t{160}, std::size_t{4096}}) {
    const std::vector<SegmentedUtterance> found = segment(r.clip, chunk);
    REQUIRE(found.size() == reference.size());
    for (std::size_t i = 0; i < found.size(); ++i) {
      CHECK(found[i].start_s == reference[i].start_s);
      CHECK(found[i].end_s == reference[i].end_s);
      CHECK(found[i].clip.samples == reference[i].clip.samples);
    }
  }
}

TEST_CASE("an utterance longer than max_utterance_s is cut and the rest goes on, and the end of the stream completes one") {
  Recording r;
  r.room(0.5);
  r.voice(2.5);
  r.room(1.0);
  r.voice(0.5);  // the stream ends while this one is being said
  VadOptions o;
  o.max_utterance_s = 1.0;
  const std::vector<SegmentedUtterance> found = segment(r.clip, 320, o);
  REQUIRE(found.size() == 4);
  CHECK(found[0].truncated);
  CHECK(found[1].truncated);
  CHECK(found[0].start_s == Approx(0.5).margin(0.02));
  CHECK(found[0].end_s - found[0].start_s == Approx(1.0).margin(0.02));
  CHECK(found[0].clip.duration_s() == Approx(1.25).margin(0.02));  // with the pre-roll
  CHECK(found[1].start_s == Approx(found[0].end_s));
  CHECK(found[1].clip.duration_s() == Approx(1.0).margin(0.02));
  CHECK_FALSE(found[2].truncated);
  CHECK(found[2].end_s == Approx(3.0).margin(0.02));
  CHECK_FALSE(found[3].truncated);
  CHECK(found[3].start_s == Approx(4.0).margin(0.02));
  CHECK(found[3].end_s == Approx(4.5).margin(0.02));

  // Fed on after finish(), the timeline goes on from the last sample, the partial frame included.
  UtteranceSegmenter s(kRate);
  const std::vector<std::int16_t> odd(4159, 0);  // 25 frames of 160 and 159 samples
  CHECK(s.feed(odd).empty());
  CHECK(s.finish().empty());
  Recording more;
  more.voice(0.5);
  more.room(0.6);
  const std::vector<SegmentedUtterance> later = s.feed(more.clip.samples);
  REQUIRE(later.size() == 1);
  CHECK(later[0].start_s == Approx(4159.0 / kRate).margin(0.001));
}

TEST_CASE("the noise floor follows a room getting louder, and a voice above it is still found") {
  Recording r;
  r.room(0.5);
  // The room grows from -61 to about -31 dBFS over 4 s (a fan starting): no utterance.
  for (int step = 0; step < 40; ++step) {
    r.noise_amplitude = 30.0 * std::pow(10.0, step / 40.0 * 1.5);
    r.room(0.1);
  }
  UtteranceSegmenter s(kRate);
  CHECK(s.feed(r.clip.samples).empty());
  CHECK_FALSE(s.in_speech());
  CHECK(s.noise_floor_dbfs() > -40.0);
  const double floor = s.noise_floor_dbfs();
  Recording voice;
  voice.noise_amplitude = r.noise_amplitude;
  voice.voice(0.6);
  voice.room(0.6);
  const std::vector<SegmentedUtterance> found = s.feed(voice.clip.samples);
  REQUIRE(found.size() == 1);
  CHECK(found[0].end_s - found[0].start_s == Approx(0.6).margin(0.03));
  CHECK(s.noise_floor_dbfs() == Approx(floor).margin(3.0));
}

TEST_CASE("digital silence and an empty stream give no utterance, and bad options are refused") {
  UtteranceSegmenter s(kRate);
  CHECK(s.feed(std::vector<std::int16_t>(kRate, 0)).empty());
  CHECK(s.finish().empty());
  CHECK(UtteranceSegmenter(kRate).finish().empty());
  CHECK_THROWS_AS(UtteranceSegmenter(0), std::invalid_argument);
  VadOptions bad;
  bad.frame_s = 0.0;
  CHECK_THROWS_AS(UtteranceSegmenter(kRate, bad), std::invalid_argument);
  bad.frame_s = 1e-6;  // shorter than a sample
  CHECK_THROWS_AS(UtteranceSegmenter(kRate, bad), std::invalid_argument);
  VadOptions rise;
  rise.floor_rise = 1.5;
  CHECK_THROWS_AS(UtteranceSegmenter(kRate, rise), std::invalid_argument);
}

namespace {

// A recognizer double: reports each clip's length, so the test sees what it was given.
class ClipLengths final : public SpeechRecognizer {
 public:
  int sample_rate_hz() const noexcept override { return kRate; }
  Result recognize(const AudioClip& audio) override {
    clips.push_back(audio.duration_s());
    return {"clip " + std::to_string(clips.size()), 0.5, {}};
  }
  std::vector<double> clips;
};

}  // namespace

TEST_CASE("the listener hands each utterance to the recognizer with where it was in the stream") {
  Recording r;
  r.room(0.4);
  r.voice(0.5);
  r.room(0.8);
  r.voice(0.7);
  r.room(0.8);
  ClipLengths recognizer;
  const std::vector<HeardUtterance> heard = listen_to(recognizer, r.clip);
  REQUIRE(heard.size() == 2);
  CHECK(heard[0].result.words == "clip 1");
  CHECK(heard[1].result.words == "clip 2");
  CHECK(heard[0].start_s == Approx(0.4).margin(0.02));
  CHECK(heard[1].start_s == Approx(1.7).margin(0.02));
  REQUIRE(recognizer.clips.size() == 2);
  CHECK(recognizer.clips[1] == Approx(0.7 + 0.5).margin(0.03));
}

TEST_CASE("a stream of spoken questions: each one is recognised and answered", "[voice]") {
  if (!voice_available()) {
    WARN("built without espeak-ng and pocketsphinx (TRIPODAL_VOICE=OFF): nothing to test");
    return;
  }
  testing::SpokenJinny jinny;
  const auto recognizer = jinny.recognizer();
  const auto voice = testing::SpokenJinny::visitor();

  // One recording: room noise, three requests with pauses of various lengths between them.
  Recording r;
  r.room(0.6);
  std::vector<double> starts;
  for (const char* text : {"What time is it?", "Introduce yourself.", "Guide me to node 1."}) {
    starts.push_back(r.now());
    const AudioClip said = resample(voice->synthesize(text), kRate);
    std::uniform_real_distribution<double> n(-r.noise_amplitude, r.noise_amplitude);
    for (const std::int16_t s : said.samples) r.clip.samples.push_back(static_cast<std::int16_t>(std::clamp(s + n(r.noise), -32768.0, 32767.0)));
    r.room(0.8 + 0.3 * static_cast<double>(starts.size()));
  }

  SpeechListener listener(*recognizer, kRate);
  std::vector<HeardUtterance> heard;
  // Fed as a microphone would: 20 ms at a time.
  for (std::size_t at = 0; at < r.clip.samples.size(); at += 320) {
    const std::size_t n = std::min<std::size_t>(320, r.clip.samples.size() - at);
    for (auto& h : listener.feed(std::span<const std::int16_t>(r.clip.samples).subspan(at, n))) heard.push_back(std::move(h));
  }
  for (auto& h : listener.finish()) heard.push_back(std::move(h));

  REQUIRE(heard.size() == 3);
  for (std::size_t i = 0; i < heard.size(); ++i) CHECK(heard[i].start_s == Approx(starts[i]).margin(0.1));
  CHECK(jinny.hri.handle_heard(heard[0].result).entry_id == "time");
  CHECK(jinny.hri.handle_heard(heard[1].result).entry_id == "introduce");
  // The guide starts at once when heard surely (posterior >= 0.5), else after the visitor's yes.
  const HriReply guide = jinny.hri.handle_heard(heard[2].result);
  INFO("heard \"" << heard[2].result.words << "\" at " << heard[2].result.confidence);
  if (guide.kind == HriReply::Kind::confirm_task) {
    CHECK(guide.task == "guide");
    CHECK(jinny.hri.handle("yes").kind == HriReply::Kind::task_started);
  } else {
    CHECK(guide.kind == HriReply::Kind::task_started);
  }
  CHECK(jinny.started == std::vector<std::string>{"guide"});
}
