#include "visit_audio.hpp"

#include <stdexcept>

namespace tripodal::app {

VisitAudio::VisitAudio(const std::string& device, const std::filesystem::path& config_file, HriModule& hri,
                       SpeechRecognizer& ears, SpeechSynthesizer& voice)
    : microphone_(open_alsa_input({device, config_file.string(), ears.sample_rate_hz(), 0.1})),
      speaker_(open_alsa_output({device, config_file.string(), ears.sample_rate_hz(), 0.1})),
      live_(*microphone_, *speaker_, ears, voice, hri) {}

void VisitAudio::step(double period_s, const std::function<void(const std::string&)>& say, std::vector<VisitExchange>& exchanges,
                      double now_s) {
  until_s_ += period_s;
  while (!ended_ && live_.stream_s() < until_s_) ended_ = !live_.step();
  for (; reported_ < live_.events().size(); ++reported_) {
    const LiveEvent& e = live_.events()[reported_];
    switch (e.kind) {
      case LiveEvent::Kind::heard: {
        VisitExchange x;
        x.step = exchanges.size();
        x.time_s = now_s;
        x.kind = "live";
        x.request = e.text;
        x.heard = e.text;
        x.reply_kind = std::string(to_string(e.reply.kind));
        x.entry = e.reply.entry_id;
        x.task = e.reply.task;
        x.reply = e.reply.text;
        say("visitor (microphone): \"" + e.text + "\" -> Jinny [" + x.reply_kind + (x.entry.empty() ? "" : " " + x.entry) +
            (x.task.empty() ? "" : ", task " + x.task) + "]: " + x.reply);
        exchanges.push_back(std::move(x));
        break;
      }
      case LiveEvent::Kind::barge_in:
        say("the visitor spoke over Jinny: its speech stopped");
        break;
      case LiveEvent::Kind::spoke:
      case LiveEvent::Kind::finished:
        break;
    }
  }
}

std::unique_ptr<VisitAudio> open_visit_audio(const VisitOptions& options, HriModule& hri, SpeechRecognizer* ears,
                                             SpeechSynthesizer* voice) {
  if (options.audio_device.empty()) return nullptr;
  if (ears == nullptr || voice == nullptr) {
    throw std::runtime_error("--audio " + options.audio_device +
                             ": live audio needs the voice (espeak-ng and pocketsphinx, TRIPODAL_VOICE; not --no-voice)");
  }
  return std::make_unique<VisitAudio>(options.audio_device, options.audio_config, hri, *ears, *voice);
}

}  // namespace tripodal::app
