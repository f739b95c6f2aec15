// A build without ALSA (TRIPODAL_ALSA=OFF): the live-audio devices refuse to open.
#include <stdexcept>

#include "tripodal/hri/audio_device.hpp"

namespace tripodal {

bool alsa_available() noexcept {
  return false;
}

std::unique_ptr<AudioInput> open_alsa_input(const AlsaOptions& options) {
  throw std::runtime_error("audio device '" + options.device + "': this build has no ALSA (install libasound2-dev and rebuild)");
}

std::unique_ptr<AudioOutput> open_alsa_output(const AlsaOptions& options) {
  throw std::runtime_error("audio device '" + options.device + "': this build has no ALSA (install libasound2-dev and rebuild)");
}

}  // namespace tripodal
