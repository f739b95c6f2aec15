// Sound in and out for the HRI's live voice (paper, Table 3: voice recognition and synthesis): a
// microphone read in chunks and a speaker written in chunks, so one loop can listen while the
// robot speaks (LiveConversation). ALSA implements both; the tests use ALSA's file plugin, a
// capture device that reads a raw file and a playback device that writes a WAV, so no sound card
// is needed.
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>

namespace tripodal {

/// Mono 16-bit samples from a microphone (or a file standing for one).
class AudioInput {
 public:
  virtual ~AudioInput() = default;
  [[nodiscard]] virtual int sample_rate_hz() const noexcept = 0;
  /// Fills `out`, blocking until it is full; fewer samples only at the end of the stream (0: it
  /// has ended). Throws std::runtime_error when the device fails beyond recovery.
  virtual std::size_t read(std::span<std::int16_t> out) = 0;
};

/// Mono 16-bit samples to a speaker.
class AudioOutput {
 public:
  virtual ~AudioOutput() = default;
  [[nodiscard]] virtual int sample_rate_hz() const noexcept = 0;
  /// Queues `samples` for playing (blocks while the device's buffer is full).
  virtual void write(std::span<const std::int16_t> samples) = 0;
  /// Drops what is queued and not played yet: the visitor spoke over the robot (barge-in).
  virtual void drop() = 0;
};

struct AlsaOptions {
  /// An ALSA PCM name: "default", "plughw:1,0", or one that `config_file` defines.
  std::string device = "default";
  /// An ALSA configuration file read in addition to the system's (asoundrc syntax), for devices
  /// defined for the robot (or, in tests, file-plugin devices); empty: the system's only.
  std::string config_file;
  int sample_rate_hz = 16000;
  /// The device buffer's length: the delay from a write to the sound, and what drop() discards.
  double latency_s = 0.1;
};

/// True when the build has ALSA (TRIPODAL_ALSA; Debian's libasound2-dev).
[[nodiscard]] bool alsa_available() noexcept;

/// Open `options.device` for capture / playback, S16_LE mono at the rate given (converted by
/// ALSA's plug layer where the device needs it). Throws std::runtime_error naming the device and
/// ALSA's reason ("audio device 'mic': No such file or directory") when it cannot, and when the
/// build has no ALSA.
[[nodiscard]] std::unique_ptr<AudioInput> open_alsa_input(const AlsaOptions& options);
[[nodiscard]] std::unique_ptr<AudioOutput> open_alsa_output(const AlsaOptions& options);

}  // namespace tripodal
