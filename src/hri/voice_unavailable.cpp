// Built instead of voice.cpp when CMake did not find espeak-ng and pocketsphinx (TRIPODAL_VOICE=OFF):
// the interfaces stay, the engines say why they are missing.
#include <stdexcept>

#include "tripodal/hri/speech.hpp"

namespace tripodal {

bool voice_available() noexcept { return false; }

std::optional<std::string> espeak_pronunciation(std::string_view) { return std::nullopt; }

std::unique_ptr<SpeechSynthesizer> make_espeak_synthesizer(const EspeakOptions&) {
  throw std::runtime_error("this build of tripodal has no espeak-ng (TRIPODAL_VOICE=OFF; install libespeak-ng-dev)");
}

std::unique_ptr<SpeechRecognizer> make_pocketsphinx_recognizer(const PocketsphinxOptions&) {
  throw std::runtime_error(
      "this build of tripodal has no pocketsphinx (TRIPODAL_VOICE=OFF; install libpocketsphinx-dev and pocketsphinx-en-us)");
}

}  // namespace tripodal
