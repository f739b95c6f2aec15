// The HRI's live voice loop (deliberate layer, around HriModule): a microphone stream is segmented
// into utterances, each is recognised and handled, and the reply is spoken on the speaker — in one
// loop, chunk by chunk, so the robot keeps listening while it speaks. While it speaks (and a short
// hangover after) the microphone is not listened to, so the robot does not hear itself; a visitor
// who speaks over it clearly louder than its own echo stops the speech (barge-in) and is heard.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "tripodal/hri/audio_device.hpp"
#include "tripodal/hri/hri_module.hpp"
#include "tripodal/hri/listener.hpp"
#include "tripodal/hri/speech.hpp"

namespace tripodal {

struct LiveOptions {
  /// The loop's step: one chunk read from the microphone, one written to the speaker.
  double chunk_s = 0.02;
  /// Utterance detection on the microphone stream.
  VadOptions vad;
  /// After the robot stops speaking, the microphone stays closed this long (the room's echo).
  double echo_hangover_s = 0.3;
  /// How loud the robot's own voice comes back into the microphone, relative to what it plays
  /// (dB; a robot's microphone a few tens of centimetres from its speaker: about -10 dB or less).
  double echo_coupling_db = -10.0;
  /// Barge-in: the microphone this much above the expected echo, and above barge_in_min_dbfs,
  /// for barge_in_s in a row stops the speech.
  double barge_in_margin_db = 10.0;
  double barge_in_min_dbfs = -40.0;
  double barge_in_s = 0.15;
};

/// What happened in the conversation, in stream time (seconds from the first sample read).
struct LiveEvent {
  enum class Kind {
    heard,     ///< an utterance recognised and handled: `text` what was heard, `reply` the answer
    spoke,     ///< the robot started speaking `text`
    finished,  ///< the robot finished speaking
    barge_in,  ///< the visitor spoke over the robot: the speech was stopped
  };
  Kind kind = Kind::heard;
  double at_s = 0.0;
  std::string text;
  HriReply reply;
};

/// Not thread-safe: one thread steps it (run() may be stopped from another through its flag).
/// The devices, the engines and the HRI must outlive it.
class LiveConversation {
 public:
  /// Throws std::invalid_argument for a chunk that holds no sample or devices at different rates.
  LiveConversation(AudioInput& microphone, AudioOutput& speaker, SpeechRecognizer& recognizer, SpeechSynthesizer& synthesizer,
                   HriModule& hri, LiveOptions options = {});

  /// One chunk: read from the microphone, play the next part of the speech, listen. False when
  /// the microphone stream has ended.
  bool step();
  /// Steps until the stream ends, `stop` is set, or `max_s` of stream has passed (0: no limit).
  void run(const std::atomic<bool>* stop = nullptr, double max_s = 0.0);

  [[nodiscard]] const std::vector<LiveEvent>& events() const noexcept { return events_; }
  [[nodiscard]] bool speaking() const noexcept { return speech_pos_ < speech_.size(); }
  /// Samples of speech written to the speaker so far.
  [[nodiscard]] std::size_t samples_spoken() const noexcept { return spoken_; }
  /// Seconds of stream read so far.
  [[nodiscard]] double stream_s() const noexcept;

 private:
  void listen(std::span<const std::int16_t> chunk);
  void speak(const std::string& text);
  void play_chunk(std::size_t n, double& played_dbfs);
  void note(LiveEvent::Kind kind, std::string text, HriReply reply = {});

  AudioInput& microphone_;
  AudioOutput& speaker_;
  SpeechRecognizer& recognizer_;
  SpeechSynthesizer& synthesizer_;
  HriModule& hri_;
  LiveOptions options_;
  UtteranceSegmenter segmenter_;
  std::size_t chunk_len_;
  std::vector<std::int16_t> chunk_;
  std::vector<std::int16_t> speech_;  // the reply being spoken, at the speaker's rate
  std::size_t speech_pos_ = 0;
  std::size_t spoken_ = 0;
  std::size_t read_ = 0;        // samples read from the microphone
  std::size_t gate_until_ = 0;  // the microphone is closed until this stream sample
  std::size_t loud_run_ = 0;    // chunks in a row loud enough for a barge-in
  std::vector<LiveEvent> events_;
};

}  // namespace tripodal
