// ALSA's PCM interface behind AudioInput and AudioOutput (include/tripodal/hri/audio_device.hpp).
#include <alsa/asoundlib.h>

#include <cerrno>
#include <cmath>
#include <stdexcept>
#include <string>

#include "tripodal/hri/audio_device.hpp"

namespace tripodal {

namespace {

[[noreturn]] void fail(const AlsaOptions& o, const std::string& what, int err) {
  throw std::runtime_error("audio device '" + o.device + "'" + (o.config_file.empty() ? "" : " (" + o.config_file + ")") + ": " +
                           what + ": " + snd_strerror(err));
}

// The PCM, opened with the system's configuration or with it and `config_file`.
snd_pcm_t* open_pcm(const AlsaOptions& o, snd_pcm_stream_t stream) {
  snd_pcm_t* pcm = nullptr;
  int err = 0;
  if (o.config_file.empty()) {
    err = snd_pcm_open(&pcm, o.device.c_str(), stream, 0);
  } else {
    // The system's configuration (for "null", "plug" and the cards) with the file's on top.
    if ((err = snd_config_update()) < 0) fail(o, "reading ALSA's configuration", err);
    snd_config_t* top = nullptr;
    if ((err = snd_config_copy(&top, snd_config)) < 0) fail(o, "copying ALSA's configuration", err);
    snd_input_t* in = nullptr;
    if ((err = snd_input_stdio_open(&in, o.config_file.c_str(), "r")) < 0) {
      snd_config_delete(top);
      fail(o, "opening the configuration file", err);
    }
    err = snd_config_load(top, in);
    snd_input_close(in);
    if (err < 0) {
      snd_config_delete(top);
      fail(o, "reading the configuration file", err);
    }
    err = snd_pcm_open_lconf(&pcm, o.device.c_str(), stream, 0, top);
    snd_config_delete(top);
  }
  if (err < 0) fail(o, stream == SND_PCM_STREAM_CAPTURE ? "opening for capture" : "opening for playback", err);
  const auto latency_us = static_cast<unsigned>(std::lround(o.latency_s * 1e6));
  if ((err = snd_pcm_set_params(pcm, SND_PCM_FORMAT_S16_LE, SND_PCM_ACCESS_RW_INTERLEAVED, 1,
                                static_cast<unsigned>(o.sample_rate_hz), 1, latency_us)) < 0) {
    snd_pcm_close(pcm);
    fail(o, "setting 16-bit mono at " + std::to_string(o.sample_rate_hz) + " Hz", err);
  }
  return pcm;
}

class AlsaInput final : public AudioInput {
 public:
  explicit AlsaInput(const AlsaOptions& o) : options_(o), pcm_(open_pcm(o, SND_PCM_STREAM_CAPTURE)) {}
  ~AlsaInput() override { snd_pcm_close(pcm_); }
  AlsaInput(const AlsaInput&) = delete;
  AlsaInput& operator=(const AlsaInput&) = delete;

  [[nodiscard]] int sample_rate_hz() const noexcept override { return options_.sample_rate_hz; }

  std::size_t read(std::span<std::int16_t> out) override {
    std::size_t got = 0;
    int recoveries = 0;
    while (got < out.size()) {
      const snd_pcm_sframes_t n = snd_pcm_readi(pcm_, out.data() + got, out.size() - got);
      if (n > 0) {
        got += static_cast<std::size_t>(n);
        continue;
      }
      if (n == 0 || n == -ENODATA) break;  // the end of a stream that has one
      // An overrun (the loop fell behind) or a suspend: recovered, the lost audio is lost. A
      // device that keeps failing is given up.
      if (++recoveries > 8 || snd_pcm_recover(pcm_, static_cast<int>(n), 1) < 0) fail(options_, "capture", static_cast<int>(n));
    }
    return got;
  }

 private:
  AlsaOptions options_;
  snd_pcm_t* pcm_;
};

class AlsaOutput final : public AudioOutput {
 public:
  explicit AlsaOutput(const AlsaOptions& o) : options_(o), pcm_(open_pcm(o, SND_PCM_STREAM_PLAYBACK)) {}
  ~AlsaOutput() override {
    snd_pcm_drain(pcm_);
    snd_pcm_close(pcm_);
  }
  AlsaOutput(const AlsaOutput&) = delete;
  AlsaOutput& operator=(const AlsaOutput&) = delete;

  [[nodiscard]] int sample_rate_hz() const noexcept override { return options_.sample_rate_hz; }

  void write(std::span<const std::int16_t> samples) override {
    std::size_t done = 0;
    int recoveries = 0;
    while (done < samples.size()) {
      const snd_pcm_sframes_t n = snd_pcm_writei(pcm_, samples.data() + done, samples.size() - done);
      if (n >= 0) {
        done += static_cast<std::size_t>(n);
        continue;
      }
      // An underrun (nothing to play for a while, as between answers) is normal: recovered.
      if (++recoveries > 8 || snd_pcm_recover(pcm_, static_cast<int>(n), 1) < 0) fail(options_, "playback", static_cast<int>(n));
    }
  }

  void drop() override {
    snd_pcm_drop(pcm_);
    snd_pcm_prepare(pcm_);
  }

 private:
  AlsaOptions options_;
  snd_pcm_t* pcm_;
};

}  // namespace

bool alsa_available() noexcept {
  return true;
}

std::unique_ptr<AudioInput> open_alsa_input(const AlsaOptions& options) {
  return std::make_unique<AlsaInput>(options);
}

std::unique_ptr<AudioOutput> open_alsa_output(const AlsaOptions& options) {
  return std::make_unique<AlsaOutput>(options);
}

}  // namespace tripodal
