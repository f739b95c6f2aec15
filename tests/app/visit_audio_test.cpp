// The guide demo's live audio (`tripodal run ... --audio DEVICE`, tools/tripodal/visit_audio.hpp),
// through ALSA's file plugin (no sound card): a question said in the room is heard and answered on
// the speaker while Jinny runs on the simulator; a device that does not exist is refused by name.
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <filesystem>
#include <fstream>
#include <string>

#include "tripodal/hri/audio_device.hpp"
#include "tripodal/hri/speech.hpp"
#include "visit.hpp"

using namespace tripodal;
using namespace tripodal::app;

namespace {

namespace fs = std::filesystem;

const fs::path kConfigs = TRIPODAL_SOURCE_DIR "/configs";

// One ALSA device, "tripodal_room": capture reads `mic` (raw 16 kHz), playback writes `speaker` (WAV).
fs::path room_config(const fs::path& dir, const fs::path& mic, const fs::path& speaker) {
  const fs::path conf = dir / "asound.conf";
  std::ofstream(conf)
      << "pcm.tripodal_room_mic {\n  type file\n  slave.pcm { type null }\n  file \"/dev/null\"\n  infile \"" << mic.string()
      << "\"\n  format \"raw\"\n}\n"
      << "pcm.tripodal_room_speaker {\n  type file\n  slave.pcm { type null }\n  file \"" << speaker.string()
      << "\"\n  format \"wav\"\n}\n"
      << "pcm.tripodal_room {\n  type asym\n  capture.pcm \"tripodal_room_mic\"\n  playback.pcm \"tripodal_room_speaker\"\n}\n";
  return conf;
}

VisitOptions live_options(const fs::path& conf, const std::string& device) {
  spdlog::set_level(spdlog::level::warn);
  VisitOptions o;
  o.robot = kConfigs / "robots/jinny.yaml";
  o.world = kConfigs / "worlds/exhibit_hall.yaml";
  o.seed = 1;
  o.audio_device = device;
  o.audio_config = conf;
  o.max_duration_s = 8.0;  // no visit file: the run listens this long
  return o;
}

}  // namespace

TEST_CASE("guide demo with --audio through ALSA's file plugin: a question said in the room is answered aloud",
          "[app][visit][audio]") {
  if (!alsa_available() || !voice_available()) {
    WARN("built without ALSA or the voice engines: nothing to test");
    return;
  }
  const fs::path dir = fs::temp_directory_path() / ("tripodal_visit_audio_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  const AudioClip question = resample(make_espeak_synthesizer({"en-us+klatt", 170})->synthesize("what time is it"), 16000);
  std::vector<std::int16_t> stream(8000, 0);
  stream.insert(stream.end(), question.samples.begin(), question.samples.end());
  stream.resize(stream.size() + 16000, 0);
  {
    std::ofstream mic(dir / "mic.raw", std::ios::binary);
    mic.write(reinterpret_cast<const char*>(stream.data()), static_cast<std::streamsize>(stream.size() * sizeof(std::int16_t)));
  }
  const fs::path conf = room_config(dir, dir / "mic.raw", dir / "speaker.wav");
  const VisitResult r = run_visit(live_options(conf, "tripodal_room"));
  INFO(r.json());
  REQUIRE(r.exchanges.size() == 1);
  CHECK(r.exchanges[0].kind == "live");
  CHECK(r.exchanges[0].heard == "what time is it");
  CHECK(r.exchanges[0].entry == "time");
  CHECK(r.exchanges[0].task.empty());
  CHECK(r.collisions == 0);
  // The answer was played: the speaker's WAV holds about a second of speech.
  const AudioClip out = read_wav(dir / "speaker.wav");
  CHECK(out.duration_s() > 0.8);
  fs::remove_all(dir);
}

TEST_CASE("guide demo with --audio: a device that does not exist is refused by name", "[app][visit][audio]") {
  if (!alsa_available() || !voice_available()) {
    WARN("built without ALSA or the voice engines: nothing to test");
    return;
  }
  CHECK_THROWS_WITH(run_visit(live_options({}, "tripodal_no_such_device")), Catch::Contains("tripodal_no_such_device"));
  VisitOptions no_voice = live_options({}, "default");
  no_voice.voice = false;
  CHECK_THROWS_WITH(run_visit(no_voice), Catch::Contains("live audio needs the voice"));
}
