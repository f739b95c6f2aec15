#include "tripodal/hri/live_conversation.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tripodal {

namespace {

std::size_t samples_of(double seconds, int rate_hz) {
  return static_cast<std::size_t>(std::lround(std::max(0.0, seconds) * rate_hz));
}

}  // namespace

LiveConversation::LiveConversation(AudioInput& microphone, AudioOutput& speaker, SpeechRecognizer& recognizer,
                                   SpeechSynthesizer& synthesizer, HriModule& hri, LiveOptions options)
    : microphone_(microphone),
      speaker_(speaker),
      recognizer_(recognizer),
      synthesizer_(synthesizer),
      hri_(hri),
      options_(options),
      segmenter_(microphone.sample_rate_hz(), options.vad),
      chunk_len_(samples_of(options.chunk_s, microphone.sample_rate_hz())) {
  if (chunk_len_ == 0) throw std::invalid_argument("live conversation: chunk_s holds no sample at the microphone's rate");
  if (speaker.sample_rate_hz() != microphone.sample_rate_hz()) {
    // One chunk in, one chunk out: the loop's pace is the microphone's, the speaker must keep it.
    throw std::invalid_argument("live conversation: the microphone (" + std::to_string(microphone.sample_rate_hz()) +
                                " Hz) and the speaker (" + std::to_string(speaker.sample_rate_hz()) +
                                " Hz) must run at one rate");
  }
  chunk_.resize(chunk_len_);
}

double LiveConversation::stream_s() const noexcept {
  return static_cast<double>(read_) / static_cast<double>(microphone_.sample_rate_hz());
}

void LiveConversation::note(LiveEvent::Kind kind, std::string text, HriReply reply) {
  events_.push_back({kind, stream_s(), std::move(text), std::move(reply)});
}

bool LiveConversation::step() {
  const std::size_t got = microphone_.read(chunk_);
  if (got == 0) return false;
  const std::span<const std::int16_t> heard(chunk_.data(), got);
  read_ += got;

  if (speaking()) {
    double played_dbfs = -120.0;
    play_chunk(got, played_dbfs);
    // The robot's own voice comes back at about played + coupling; a visitor speaking over it is
    // clearly louder than that, for a while (a cough is not a barge-in).
    const double mic = level_dbfs(heard);
    const double needed =
        std::max(options_.barge_in_min_dbfs, played_dbfs + options_.echo_coupling_db + options_.barge_in_margin_db);
    loud_run_ = mic >= needed ? loud_run_ + 1 : 0;
    if (static_cast<double>(loud_run_) * options_.chunk_s >= options_.barge_in_s - 1e-9) {
      speaker_.drop();
      speech_.clear();
      speech_pos_ = 0;
      loud_run_ = 0;
      gate_until_ = 0;  // the visitor is speaking now: listen at once
      note(LiveEvent::Kind::barge_in, {});
      listen(heard);
      return true;
    }
    if (!speaking()) {
      gate_until_ = read_ + samples_of(options_.echo_hangover_s, microphone_.sample_rate_hz());
      note(LiveEvent::Kind::finished, {});
    }
    return true;
  }
  if (read_ <= gate_until_) return true;  // the room still rings with the robot's voice
  listen(heard);
  return true;
}

void LiveConversation::run(const std::atomic<bool>* stop, double max_s) {
  while (stop == nullptr || !stop->load(std::memory_order_relaxed)) {
    if (max_s > 0.0 && stream_s() >= max_s) return;
    if (!step()) return;
  }
}

void LiveConversation::listen(std::span<const std::int16_t> chunk) {
  for (const SegmentedUtterance& u : segmenter_.feed(chunk)) {
    const SpeechRecognizer::Result result = recognizer_.recognize(u.clip);
    if (result.words.empty()) continue;  // a noise the recognizer heard nothing in
    HriReply reply = hri_.handle_heard(result);
    const std::string answer = reply.text;
    note(LiveEvent::Kind::heard, result.words, std::move(reply));
    if (!answer.empty()) {
      speak(answer);
      return;  // the rest of this chunk is the robot's turn
    }
  }
}

void LiveConversation::speak(const std::string& text) {
  AudioClip clip = synthesizer_.synthesize(text);
  if (clip.sample_rate_hz != speaker_.sample_rate_hz()) clip = resample(clip, speaker_.sample_rate_hz());
  speech_ = std::move(clip.samples);
  speech_pos_ = 0;
  loud_run_ = 0;
  // The segmenter is kept as it is (between utterances, its noise floor known): it is fed again
  // when the robot has spoken, or at once on a barge-in, where the visitor is already speaking and
  // a fresh segmenter would take their voice for the room's floor.
  note(LiveEvent::Kind::spoke, text);
}

void LiveConversation::play_chunk(std::size_t n, double& played_dbfs) {
  const std::size_t len = std::min(n, speech_.size() - speech_pos_);
  const std::span<const std::int16_t> part(speech_.data() + speech_pos_, len);
  speaker_.write(part);
  played_dbfs = level_dbfs(part);
  speech_pos_ += len;
  spoken_ += len;
}

}  // namespace tripodal
