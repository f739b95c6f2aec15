// The HRI's live voice loop (LiveConversation) and its ALSA devices. The loop's logic is tested with
// a room double (the speaker's sound comes back into the microphone) and engines that speak and
// hear tones; the devices through ALSA's file plugin (a capture device reading a raw file, a
// playback device writing a WAV), with espeak-ng and pocketsphinx when the build has them.
#include <unistd.h>

#include <catch2/catch.hpp>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

#include "spoken_jinny.hpp"
#include "tripodal/hri/audio_device.hpp"
#include "tripodal/hri/live_conversation.hpp"

using namespace tripodal;

namespace {

namespace fs = std::filesystem;
constexpr int kRate = 16000;

void append_tone(std::vector<std::int16_t>& out, double freq_hz, double seconds, double amplitude = 8000.0) {
  const auto n = static_cast<std::size_t>(seconds * kRate);
  for (std::size_t i = 0; i < n; ++i) {
    out.push_back(
        static_cast<std::int16_t>(amplitude * std::sin(2.0 * std::numbers::pi * freq_hz * static_cast<double>(i) / kRate)));
  }
}

void append_silence(std::vector<std::int16_t>& out, double seconds) {
  out.resize(out.size() + static_cast<std::size_t>(seconds * kRate), 0);
}

// What the tone engines say and hear: each sentence is a tone of its own pitch.
const std::vector<std::pair<double, std::string>>& tone_sentences() {
  static const std::vector<std::pair<double, std::string>> list = {
      {300.0, "what time is it"}, {500.0, "introduce yourself"}, {700.0, "thank you"}, {1000.0, "guide me to node one"}};
  return list;
}

// Hears the pitch of the loudest part of a clip (zero crossings) as the sentence of that pitch;
// nothing for a pitch it does not know.
class ToneRecognizer final : public SpeechRecognizer {
 public:
  [[nodiscard]] int sample_rate_hz() const noexcept override { return kRate; }
  Result recognize(const AudioClip& audio) override {
    ++calls;
    std::size_t crossings = 0;
    std::size_t voiced = 0;
    for (std::size_t i = 1; i < audio.samples.size(); ++i) {
      if (std::abs(audio.samples[i]) < 500 && std::abs(audio.samples[i - 1]) < 500) continue;
      ++voiced;
      crossings += (audio.samples[i - 1] < 0) != (audio.samples[i] < 0) ? 1 : 0;
    }
    Result r;
    if (voiced == 0) return r;
    const double freq = static_cast<double>(crossings) / 2.0 / (static_cast<double>(voiced) / audio.sample_rate_hz);
    for (const auto& [f, words] : tone_sentences()) {
      if (std::abs(freq - f) < 0.1 * f) r.words = words;
    }
    r.confidence = 0.9;
    return r;
  }
  int calls = 0;
};

// Speaks every text as a 1 kHz tone, 60 ms a character: a robot hearing its own voice would
// take it for "guide me to node one".
class ToneSynthesizer final : public SpeechSynthesizer {
 public:
  AudioClip synthesize(std::string_view text) override {
    AudioClip c;
    c.sample_rate_hz = kRate;
    append_tone(c.samples, 1000.0, 0.06 * static_cast<double>(text.size()), 10000.0);
    return c;
  }
};

// A room: what the speaker plays comes back into the microphone `coupling` times as loud, one
// chunk later (a robot's microphone is centimetres from its speaker).
class Room final : public AudioInput, public AudioOutput {
 public:
  Room(std::vector<std::int16_t> visitor, double coupling) : visitor_(std::move(visitor)), coupling_(coupling) {}
  [[nodiscard]] int sample_rate_hz() const noexcept override { return kRate; }
  std::size_t read(std::span<std::int16_t> out) override {
    const std::size_t n = std::min(out.size(), visitor_.size() - pos_);
    for (std::size_t i = 0; i < n; ++i) {
      const double echo = i < last_played_.size() ? coupling_ * last_played_[i] : 0.0;
      out[i] = static_cast<std::int16_t>(std::clamp(visitor_[pos_ + i] + echo, -32768.0, 32767.0));
    }
    pos_ += n;
    last_played_.clear();
    return n;
  }
  void write(std::span<const std::int16_t> samples) override {
    last_played_.assign(samples.begin(), samples.end());
    played.insert(played.end(), samples.begin(), samples.end());
  }
  void drop() override { ++drops; }
  std::vector<std::int16_t> played;
  int drops = 0;

 private:
  std::vector<std::int16_t> visitor_;
  std::size_t pos_ = 0;
  double coupling_;
  std::vector<std::int16_t> last_played_;
};

std::vector<const LiveEvent*> events_of(const LiveConversation& c, LiveEvent::Kind kind) {
  std::vector<const LiveEvent*> out;
  for (const auto& e : c.events()) {
    if (e.kind == kind) out.push_back(&e);
  }
  return out;
}

fs::path temp_dir(const std::string& name) {
  const fs::path d = fs::temp_directory_path() / ("tripodal_live_" + std::to_string(::getpid()) + "_" + name);
  fs::create_directories(d);
  return d;
}

// An ALSA configuration with a microphone reading `raw` and a speaker writing `wav`.
fs::path file_plugin_config(const fs::path& dir, const fs::path& raw, const fs::path& wav) {
  const fs::path conf = dir / "asound.conf";
  std::ofstream(conf) << "pcm.tripodal_mic {\n  type file\n  slave.pcm { type null }\n  file \"/dev/null\"\n  infile \""
                      << raw.string() << "\"\n  format \"raw\"\n}\n"
                      << "pcm.tripodal_speaker {\n  type file\n  slave.pcm { type null }\n  file \"" << wav.string()
                      << "\"\n  format \"wav\"\n}\n";
  return conf;
}

void write_raw(const fs::path& file, const std::vector<std::int16_t>& samples) {
  std::ofstream out(file, std::ios::binary);
  out.write(reinterpret_cast<const char*>(samples.data()), static_cast<std::streamsize>(samples.size() * sizeof(std::int16_t)));
}

}  // namespace

TEST_CASE("live: each thing a visitor says is heard once and answered aloud, and the robot does not hear itself") {
  testing::SpokenJinny jinny;
  std::vector<std::int16_t> visitor;
  append_silence(visitor, 1.0);
  append_tone(visitor, 300.0, 1.0);  // "what time is it"
  append_silence(visitor, 6.0);      // the answer is spoken meanwhile
  append_tone(visitor, 700.0, 0.8);  // "thank you"
  append_silence(visitor, 6.0);
  // The robot's voice comes back at -6 dB: louder than the -10 dB the loop expects, so a missing
  // gate would hear it, as "guide me to node one".
  Room room(visitor, 0.5);
  ToneRecognizer recognizer;
  ToneSynthesizer synthesizer;
  LiveConversation live(room, room, recognizer, synthesizer, jinny.hri);
  live.run();

  const auto heard = events_of(live, LiveEvent::Kind::heard);
  REQUIRE(heard.size() == 2);
  CHECK(heard[0]->text == "what time is it");
  CHECK(heard[0]->reply.entry_id == "time");
  CHECK(heard[0]->at_s == Approx(2.0).margin(0.6));  // when the visitor stopped (plus the VAD's end silence)
  CHECK(heard[1]->text == "thank you");
  CHECK(heard[1]->reply.entry_id == "thanks");
  CHECK(events_of(live, LiveEvent::Kind::spoke).size() == 2);
  CHECK(events_of(live, LiveEvent::Kind::finished).size() == 2);
  CHECK(events_of(live, LiveEvent::Kind::barge_in).empty());
  CHECK(jinny.started.empty());
  // Both answers were played whole.
  const std::size_t answers =
      synthesizer.synthesize(heard[0]->reply.text).samples.size() + synthesizer.synthesize(heard[1]->reply.text).samples.size();
  CHECK(live.samples_spoken() == answers);
  CHECK(room.played.size() == answers);
}

TEST_CASE("live: a visitor speaking over the robot stops its speech and is heard") {
  testing::SpokenJinny jinny;
  std::vector<std::int16_t> visitor;
  append_silence(visitor, 0.5);
  append_tone(visitor, 500.0, 1.0);           // "introduce yourself": a long answer
  append_silence(visitor, 1.5);               // the robot is speaking by now
  append_tone(visitor, 300.0, 1.0, 16000.0);  // "what time is it", over the robot's voice
  append_silence(visitor, 8.0);
  Room room(visitor, 0.3);
  ToneRecognizer recognizer;
  ToneSynthesizer synthesizer;
  LiveConversation live(room, room, recognizer, synthesizer, jinny.hri);
  live.run();

  const auto barge = events_of(live, LiveEvent::Kind::barge_in);
  REQUIRE(barge.size() == 1);
  CHECK(barge[0]->at_s == Approx(3.0).margin(0.3));
  CHECK(room.drops == 1);
  const auto heard = events_of(live, LiveEvent::Kind::heard);
  REQUIRE(heard.size() == 2);
  CHECK(heard[0]->reply.entry_id == "introduce");
  CHECK(heard[1]->text == "what time is it");
  CHECK(heard[1]->reply.entry_id == "time");
  // The introduction was cut: less of it was played than it lasts.
  const std::size_t introduction = synthesizer.synthesize(heard[0]->reply.text).samples.size();
  CHECK(live.samples_spoken() < introduction);
}

TEST_CASE("live: minutes of silence, clipping and unknown sounds start nothing") {
  testing::SpokenJinny jinny;
  std::vector<std::int16_t> stream;
  append_silence(stream, 180.0);
  // A clipped burst of a pitch no sentence has (a door slamming, a shout into the microphone).
  append_tone(stream, 2000.0, 0.5, 60000.0);
  append_silence(stream, 2.0);
  Room room(stream, 0.5);
  ToneRecognizer recognizer;
  ToneSynthesizer synthesizer;
  LiveConversation live(room, room, recognizer, synthesizer, jinny.hri);
  live.run();
  CHECK(recognizer.calls == 1);  // the burst was an utterance, and heard as nothing
  CHECK(events_of(live, LiveEvent::Kind::heard).empty());
  CHECK(live.samples_spoken() == 0);
  CHECK(jinny.started.empty());
  CHECK(live.stream_s() == Approx(182.5).margin(0.05));
}

TEST_CASE("live: devices at different rates, and ALSA devices that do not exist, are refused by name") {
  testing::SpokenJinny jinny;
  struct Mic8k final : AudioInput {
    [[nodiscard]] int sample_rate_hz() const noexcept override { return 8000; }
    std::size_t read(std::span<std::int16_t>) override { return 0; }
  } mic;
  Room speaker({}, 0.0);
  ToneRecognizer recognizer;
  ToneSynthesizer synthesizer;
  CHECK_THROWS_WITH(LiveConversation(mic, speaker, recognizer, synthesizer, jinny.hri),
                    Catch::Contains("(8000 Hz)") && Catch::Contains("(16000 Hz)"));
  if (!alsa_available()) {
    CHECK_THROWS_WITH(open_alsa_input({"default", "", kRate, 0.1}), Catch::Contains("no ALSA"));
    return;
  }
  CHECK_THROWS_WITH(open_alsa_input({"tripodal_no_such_device", "", kRate, 0.1}), Catch::Contains("'tripodal_no_such_device'"));
  CHECK_THROWS_WITH(open_alsa_output({"default", "/nonexistent/asound.conf", kRate, 0.1}),
                    Catch::Contains("/nonexistent/asound.conf") && Catch::Contains("configuration file"));
}

TEST_CASE("live through ALSA's file plugin: a recording in, the robot's answers out in a WAV") {
  if (!alsa_available()) {
    WARN("built without ALSA (TRIPODAL_ALSA=OFF): nothing to test");
    return;
  }
  testing::SpokenJinny jinny;
  const fs::path dir = temp_dir("tones");
  std::vector<std::int16_t> visitor;
  append_silence(visitor, 0.5);
  append_tone(visitor, 300.0, 1.0);  // "what time is it"
  append_silence(visitor, 6.0);
  write_raw(dir / "mic.raw", visitor);
  const fs::path conf = file_plugin_config(dir, dir / "mic.raw", dir / "speaker.wav");
  ToneRecognizer recognizer;
  ToneSynthesizer synthesizer;
  std::size_t spoken = 0;
  {
    const auto mic = open_alsa_input({"tripodal_mic", conf.string(), kRate, 0.1});
    const auto speaker = open_alsa_output({"tripodal_speaker", conf.string(), kRate, 0.1});
    LiveConversation live(*mic, *speaker, recognizer, synthesizer, jinny.hri);
    // The file plugin's capture gives silence after the file: the stream is as long as we say.
    live.run(nullptr, 7.5);
    const auto heard = events_of(live, LiveEvent::Kind::heard);
    REQUIRE(heard.size() == 1);
    CHECK(heard[0]->reply.entry_id == "time");
    spoken = live.samples_spoken();
  }  // the speaker is drained and closed: the WAV is complete
  const AudioClip out = read_wav(dir / "speaker.wav");
  CHECK(out.sample_rate_hz == kRate);
  REQUIRE(spoken > 0);
  CHECK(out.samples.size() == spoken);
  CHECK(level_dbfs(out.samples) > -20.0);
  fs::remove_all(dir);
}

TEST_CASE("live through ALSA with espeak-ng and pocketsphinx: a spoken question answered aloud") {
  if (!alsa_available() || !voice_available()) {
    WARN("built without ALSA or the voice engines: nothing to test");
    return;
  }
  testing::SpokenJinny jinny;
  const fs::path dir = temp_dir("voice");
  AudioClip question = resample(testing::SpokenJinny::visitor()->synthesize("what time is it"), kRate);
  std::vector<std::int16_t> stream;
  append_silence(stream, 0.5);
  stream.insert(stream.end(), question.samples.begin(), question.samples.end());
  append_silence(stream, 1.0);
  write_raw(dir / "mic.raw", stream);
  const fs::path conf = file_plugin_config(dir, dir / "mic.raw", dir / "speaker.wav");
  const auto recognizer = jinny.recognizer();
  const auto voice = make_espeak_synthesizer();
  std::string answer;
  std::size_t spoken = 0;
  {
    const auto mic = open_alsa_input({"tripodal_mic", conf.string(), kRate, 0.1});
    const auto speaker = open_alsa_output({"tripodal_speaker", conf.string(), kRate, 0.1});
    LiveConversation live(*mic, *speaker, *recognizer, *voice, jinny.hri);
    live.run(nullptr, question.duration_s() + 6.0);
    const auto heard = events_of(live, LiveEvent::Kind::heard);
    REQUIRE(heard.size() == 1);
    CHECK(heard[0]->text == "what time is it");
    CHECK(heard[0]->reply.entry_id == "time");
    answer = heard[0]->reply.text;
    spoken = live.samples_spoken();
  }
  // The answer ("It is 14:00.") was played whole: the WAV holds its synthesis.
  const AudioClip out = read_wav(dir / "speaker.wav");
  const AudioClip expected = resample(voice->synthesize(answer), kRate);
  REQUIRE(out.samples.size() > static_cast<std::size_t>(kRate) / 2);
  // (espeak-ng's output for one text may differ by a few samples from one call to the next)
  CHECK(spoken + kRate / 100 >= expected.samples.size());
  CHECK(spoken <= expected.samples.size() + kRate / 100);
  // The file plugin writes whole periods: the last part of one may be missing from the file.
  CHECK(out.samples.size() <= spoken);
  CHECK(out.samples.size() + kRate / 100 >= spoken);
  CHECK(level_dbfs(out.samples) == Approx(level_dbfs(expected.samples)).margin(0.5));
  CHECK(jinny.started.empty());
  fs::remove_all(dir);
}
