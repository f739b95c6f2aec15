// Voice on an audio stream for the HRI module (paper, Table 3: voice recognition): a microphone
// gives a continuous stream, not one clip per question. UtteranceSegmenter finds where each
// utterance starts and ends (energy against a tracked noise floor), and SpeechListener hands each
// one to a SpeechRecognizer, so the HRI gets one recognised sentence per thing a visitor said.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <span>
#include <vector>

#include "tripodal/hri/speech.hpp"

namespace tripodal {

struct VadOptions {
  /// The analysis frame; energies are compared frame by frame.
  double frame_s = 0.010;
  /// A frame is speech when it is this far above the noise floor (dB) and above min_level_dbfs.
  double threshold_db = 12.0;
  /// Below this level (dB full scale) a frame is silence whatever the floor: digital silence
  /// and a quiet room do not make the floor so low that breathing becomes speech.
  double min_level_dbfs = -55.0;
  /// This much speech in a row starts an utterance (a click or a cough shorter than it does not).
  double start_speech_s = 0.08;
  /// This much silence in a row ends it (pauses between words are shorter).
  double end_silence_s = 0.45;
  /// Audio kept before the first speech frame (the onset of a soft consonant is under the
  /// threshold) and after the last one: the recognizer's silence model needs some.
  double pre_roll_s = 0.25;
  double post_roll_s = 0.25;
  /// An utterance speaking this long is cut and handed on as it is (truncated); the next one
  /// starts at once.
  double max_utterance_s = 10.0;
  /// How fast the noise floor follows the level of non-speech frames (per frame, 0..1): the floor
  /// falls at once to a quieter frame and rises slowly with a louder room.
  double floor_rise = 0.02;
};

/// The mean power of `samples` in dB relative to a full-scale square wave (-120 for none).
[[nodiscard]] double level_dbfs(std::span<const std::int16_t> samples) noexcept;

/// One utterance found in the stream: its audio (with the pre- and post-roll) and where it lies
/// in the stream, in seconds from the first sample fed.
struct SegmentedUtterance {
  AudioClip clip;
  double start_s = 0.0;  ///< the first speech frame
  double end_s = 0.0;    ///< the end of the last speech frame
  bool truncated = false;  ///< cut at max_utterance_s
};

/// Energy-based voice activity detection with hangover over a stream fed in chunks of any size;
/// independent of any recognizer. Not thread-safe (one stream, one thread).
class UtteranceSegmenter {
 public:
  /// Throws std::invalid_argument for a rate <= 0 or options that make no frame.
  explicit UtteranceSegmenter(int sample_rate_hz, VadOptions options = {});

  /// Consumes `samples`; returns the utterances they complete, in order.
  std::vector<SegmentedUtterance> feed(std::span<const std::int16_t> samples);
  /// The end of the stream: an utterance in progress is completed (its post-roll is what there is).
  std::vector<SegmentedUtterance> finish();

  [[nodiscard]] bool in_speech() const noexcept { return in_speech_; }
  /// The current noise floor estimate (dB full scale).
  [[nodiscard]] double noise_floor_dbfs() const noexcept { return floor_db_; }
  [[nodiscard]] int sample_rate_hz() const noexcept { return rate_hz_; }

 private:
  void frame_done(std::vector<SegmentedUtterance>& out);
  void close_utterance(std::vector<SegmentedUtterance>& out, bool truncated);
  void trim_history();

  int rate_hz_;
  VadOptions options_;
  std::size_t frame_len_;
  std::size_t start_frames_;
  std::size_t end_frames_;
  std::size_t pre_roll_len_;
  std::size_t post_roll_len_;
  std::size_t max_len_;

  std::vector<std::int16_t> frame_;       // the frame being filled
  std::deque<std::int16_t> history_;      // the samples before an utterance (pre-roll and the start run)
  std::vector<std::int16_t> utterance_;   // the utterance's audio so far, while in speech
  std::size_t samples_seen_ = 0;          // samples of complete frames so far
  bool floor_known_ = false;
  double floor_db_ = -90.0;
  bool in_speech_ = false;
  std::size_t speech_run_ = 0;            // consecutive speech frames (before a start)
  std::size_t silence_run_ = 0;           // consecutive silence frames (in speech)
  std::size_t utterance_start_ = 0;       // stream sample index of the first speech frame
  std::size_t last_speech_end_ = 0;       // stream sample index just after the last speech frame
  std::size_t utterance_first_sample_ = 0;  // stream sample index of utterance_[0]
};

/// A recognised utterance of the stream.
struct HeardUtterance {
  double start_s = 0.0;
  double end_s = 0.0;
  bool truncated = false;
  SpeechRecognizer::Result result;
};

/// A stream in, recognised utterances out: UtteranceSegmenter and a SpeechRecognizer (which must
/// outlive the listener). Each utterance is recognised in the feeding thread when it ends.
class SpeechListener {
 public:
  SpeechListener(SpeechRecognizer& recognizer, int sample_rate_hz, VadOptions options = {});
  std::vector<HeardUtterance> feed(std::span<const std::int16_t> samples);
  std::vector<HeardUtterance> finish();
  [[nodiscard]] const UtteranceSegmenter& segmenter() const noexcept { return segmenter_; }

 private:
  std::vector<HeardUtterance> recognise(const std::vector<SegmentedUtterance>& utterances);

  SpeechRecognizer& recognizer_;
  UtteranceSegmenter segmenter_;
};

/// Every utterance of a recording (a WAV file read with read_wav, say), as a stream would give them.
[[nodiscard]] std::vector<HeardUtterance> listen_to(SpeechRecognizer& recognizer, const AudioClip& recording,
                                                    VadOptions options = {});

}  // namespace tripodal
