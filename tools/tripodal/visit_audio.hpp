// Live audio on the guide demo (`tripodal run --visit/--monitor ... --audio DEVICE`): the robot
// hears the room through an ALSA microphone and answers on its speaker while the visit runs, with
// the HRI's LiveConversation (docs/hri.md "Live audio"). Application layer, part of the `tripodal`
// tool; visit.cpp steps it once a period.
#pragma once

#include <filesystem>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "tripodal/hri/audio_device.hpp"
#include "tripodal/hri/live_conversation.hpp"
#include "visit.hpp"

namespace tripodal::app {

class VisitAudio {
 public:
  /// Opens the ALSA PCM `device` (defined by the configuration file `config_file`, or the
  /// system's when empty) for capture and playback at the recognizer's rate. Throws
  /// std::runtime_error naming the device when it cannot (ALSA's reason, or a build without ALSA).
  VisitAudio(const std::string& device, const std::filesystem::path& config_file, HriModule& hri, SpeechRecognizer& ears,
             SpeechSynthesizer& voice);

  /// Listens and speaks for `period_s` more of the stream (blocking on a real device: it paces the
  /// run to real time); what was heard and answered is said as dialogue lines and added to
  /// `exchanges` (kind "live"). Nothing once the microphone stream has ended.
  void step(double period_s, const std::function<void(const std::string&)>& say, std::vector<VisitExchange>& exchanges,
            double now_s);
  [[nodiscard]] bool ended() const noexcept { return ended_; }

 private:
  std::unique_ptr<AudioInput> microphone_;
  std::unique_ptr<AudioOutput> speaker_;
  LiveConversation live_;
  double until_s_ = 0.0;
  std::size_t reported_ = 0;
  bool ended_ = false;
};

/// The live audio of a visit (VisitOptions::audio_device, audio_config), or none when no device is
/// named. Throws std::runtime_error when one is but the run has no voice (`ears` or `voice` null:
/// a build without espeak-ng and pocketsphinx, or --no-voice) or it cannot be opened.
[[nodiscard]] std::unique_ptr<VisitAudio> open_visit_audio(const VisitOptions& options, HriModule& hri, SpeechRecognizer* ears,
                                                           SpeechSynthesizer* voice);

}  // namespace tripodal::app
