#include "tripodal/hri/listener.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace tripodal {

namespace {

std::size_t samples_of(double seconds, int rate_hz) {
  return static_cast<std::size_t>(std::lround(std::max(0.0, seconds) * rate_hz));
}

std::size_t frames_of(double seconds, double frame_s) {
  return std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(seconds / frame_s - 1e-9)));
}

}  // namespace

double level_dbfs(std::span<const std::int16_t> samples) noexcept {
  if (samples.empty()) return -120.0;
  double sum = 0.0;
  for (const std::int16_t s : samples) sum += static_cast<double>(s) * static_cast<double>(s);
  const double mean = sum / static_cast<double>(samples.size()) / (32768.0 * 32768.0);
  return 10.0 * std::log10(mean + 1e-12);
}

UtteranceSegmenter::UtteranceSegmenter(int sample_rate_hz, VadOptions options)
    : rate_hz_(sample_rate_hz), options_(options) {
  if (rate_hz_ <= 0) throw std::invalid_argument("UtteranceSegmenter: the sample rate must be positive");
  if (!(options_.frame_s > 0.0) || !std::isfinite(options_.frame_s)) {
    throw std::invalid_argument("UtteranceSegmenter: frame_s must be positive");
  }
  frame_len_ = samples_of(options_.frame_s, rate_hz_);
  if (frame_len_ == 0) throw std::invalid_argument("UtteranceSegmenter: frame_s is shorter than one sample");
  if (!(options_.floor_rise >= 0.0 && options_.floor_rise <= 1.0)) {
    throw std::invalid_argument("UtteranceSegmenter: floor_rise must be within 0..1");
  }
  start_frames_ = frames_of(options_.start_speech_s, options_.frame_s);
  end_frames_ = frames_of(options_.end_silence_s, options_.frame_s);
  pre_roll_len_ = samples_of(options_.pre_roll_s, rate_hz_);
  post_roll_len_ = samples_of(options_.post_roll_s, rate_hz_);
  max_len_ = std::max(samples_of(options_.max_utterance_s, rate_hz_), frame_len_);
  frame_.reserve(frame_len_);
}

std::vector<SegmentedUtterance> UtteranceSegmenter::feed(std::span<const std::int16_t> samples) {
  std::vector<SegmentedUtterance> out;
  for (const std::int16_t s : samples) {
    frame_.push_back(s);
    if (frame_.size() == frame_len_) frame_done(out);
  }
  return out;
}

std::vector<SegmentedUtterance> UtteranceSegmenter::finish() {
  std::vector<SegmentedUtterance> out;
  if (in_speech_) {
    // The partial frame is the end of the stream: part of the post-roll, not analysed.
    utterance_.insert(utterance_.end(), frame_.begin(), frame_.end());
    close_utterance(out, false);
  }
  // The partial frame still counts in the timeline, should the stream be fed on after this.
  samples_seen_ += frame_.size();
  frame_.clear();
  history_.clear();
  in_speech_ = false;
  speech_run_ = 0;
  return out;
}

void UtteranceSegmenter::frame_done(std::vector<SegmentedUtterance>& out) {
  const std::size_t frame_end = samples_seen_ + frame_len_;
  const double level = level_dbfs(frame_);
  if (!floor_known_) {
    floor_db_ = level;
    floor_known_ = true;
  }
  const bool speech = level >= std::max(floor_db_ + options_.threshold_db, options_.min_level_dbfs);

  if (!in_speech_) {
    history_.insert(history_.end(), frame_.begin(), frame_.end());
    trim_history();
    if (speech) {
      ++speech_run_;
    } else {
      speech_run_ = 0;
      // The floor follows the room: down at once, up slowly (a louder room, not a voice).
      floor_db_ = level < floor_db_ ? level : floor_db_ + options_.floor_rise * (level - floor_db_);
    }
    if (speech_run_ >= start_frames_) {
      in_speech_ = true;
      utterance_start_ = frame_end - speech_run_ * frame_len_;
      const std::size_t history_first = frame_end - history_.size();
      utterance_first_sample_ = std::max(history_first, utterance_start_ - std::min(utterance_start_, pre_roll_len_));
      utterance_.assign(history_.begin() + static_cast<std::ptrdiff_t>(utterance_first_sample_ - history_first), history_.end());
      history_.clear();
      speech_run_ = 0;
      silence_run_ = 0;
      last_speech_end_ = frame_end;
    }
  } else {
    utterance_.insert(utterance_.end(), frame_.begin(), frame_.end());
    if (speech) {
      silence_run_ = 0;
      last_speech_end_ = frame_end;
    } else {
      ++silence_run_;
    }
    if (silence_run_ >= end_frames_) {
      close_utterance(out, false);
    } else if (silence_run_ == 0 && frame_end - utterance_start_ >= max_len_) {
      close_utterance(out, true);
    }
  }
  samples_seen_ = frame_end;
  frame_.clear();
}

void UtteranceSegmenter::trim_history() {
  // The pre-roll and a start run of speech frames are all a start can reach back to.
  const std::size_t keep = pre_roll_len_ + start_frames_ * frame_len_;
  if (history_.size() > keep) history_.erase(history_.begin(), history_.end() - static_cast<std::ptrdiff_t>(keep));
}

void UtteranceSegmenter::close_utterance(std::vector<SegmentedUtterance>& out, bool truncated) {
  SegmentedUtterance u;
  u.clip.sample_rate_hz = rate_hz_;
  u.start_s = static_cast<double>(utterance_start_) / rate_hz_;
  u.truncated = truncated;
  const std::size_t have_end = utterance_first_sample_ + utterance_.size();
  if (truncated) {
    u.end_s = static_cast<double>(have_end) / rate_hz_;
    u.clip.samples = std::move(utterance_);
    // The voice goes on: the next utterance starts where this one was cut.
    utterance_.clear();
    utterance_start_ = have_end;
    utterance_first_sample_ = have_end;
    last_speech_end_ = have_end;
    silence_run_ = 0;
  } else {
    if (last_speech_end_ <= utterance_start_) {
      // Only silence after a cut (the voice stopped as the cut came): nothing more was said.
      history_.assign(utterance_.begin(), utterance_.end());
      trim_history();
      utterance_.clear();
      in_speech_ = false;
      speech_run_ = 0;
      return;
    }
    u.end_s = static_cast<double>(last_speech_end_) / rate_hz_;
    const std::size_t end = std::min(have_end, last_speech_end_ + post_roll_len_);
    const auto cut = utterance_.begin() + static_cast<std::ptrdiff_t>(end - utterance_first_sample_);
    // What follows the post-roll is silence before whatever comes next: its pre-roll.
    history_.assign(cut, utterance_.end());
    trim_history();
    utterance_.erase(cut, utterance_.end());
    u.clip.samples = std::move(utterance_);
    utterance_.clear();
    in_speech_ = false;
    speech_run_ = 0;
  }
  out.push_back(std::move(u));
}

SpeechListener::SpeechListener(SpeechRecognizer& recognizer, int sample_rate_hz, VadOptions options)
    : recognizer_(recognizer), segmenter_(sample_rate_hz, options) {}

std::vector<HeardUtterance> SpeechListener::feed(std::span<const std::int16_t> samples) {
  return recognise(segmenter_.feed(samples));
}

std::vector<HeardUtterance> SpeechListener::finish() { return recognise(segmenter_.finish()); }

std::vector<HeardUtterance> SpeechListener::recognise(const std::vector<SegmentedUtterance>& utterances) {
  std::vector<HeardUtterance> out;
  out.reserve(utterances.size());
  for (const auto& u : utterances) {
    out.push_back({u.start_s, u.end_s, u.truncated, recognizer_.recognize(u.clip)});
  }
  return out;
}

std::vector<HeardUtterance> listen_to(SpeechRecognizer& recognizer, const AudioClip& recording, VadOptions options) {
  SpeechListener listener(recognizer, recording.sample_rate_hz, options);
  std::vector<HeardUtterance> out = listener.feed(recording.samples);
  for (auto& h : listener.finish()) out.push_back(std::move(h));
  return out;
}

}  // namespace tripodal
