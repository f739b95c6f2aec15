// Lock-free hand-over of the latest value from one thread to others, for the wall-clock runtime:
// the reactive loop publishes what it measured, the sequencing layer reads the newest complete copy.
// Neither side waits or allocates (after the buffers have grown to the values' steady size), so the
// reactive path stays real-time. TripleBuffer carries any copyable value to one reader;
// SeqlockValue a small trivially copyable one (a pose) to any number of readers.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace tripodal {

/// The latest value from one writer thread to one reader thread. The writer fills back() and
/// publish()es it; the reader fetch()es the newest published buffer into front(). Three buffers
/// rotate through one atomic index, so the writer never overwrites what the reader holds and
/// neither waits: a reader that is slower than the writer skips values, never sees a torn one.
template <class T>
class TripleBuffer {
 public:
  TripleBuffer() = default;
  /// All three buffers start as `initial` (a value reserved to its steady size: no allocation later).
  explicit TripleBuffer(const T& initial) : buffers_{initial, initial, initial} {}

  // --- writer thread ---
  /// The buffer being written; the reader never sees it before publish().
  [[nodiscard]] T& back() noexcept { return buffers_[back_]; }
  /// Makes back() the newest value; back() is then another buffer (holding an older value).
  void publish() noexcept {
    const std::uint8_t previous = middle_.exchange(static_cast<std::uint8_t>(back_ | kFresh), std::memory_order_acq_rel);
    back_ = static_cast<std::uint8_t>(previous & kIndex);
  }

  // --- reader thread ---
  /// Takes the newest published value into front(); false (front() unchanged) when nothing new
  /// was published since the last fetch.
  bool fetch() noexcept {
    if ((middle_.load(std::memory_order_acquire) & kFresh) == 0) return false;
    const std::uint8_t previous = middle_.exchange(front_, std::memory_order_acq_rel);
    front_ = static_cast<std::uint8_t>(previous & kIndex);
    return true;
  }
  /// The value fetched last (a default or the initial value before the first fetch).
  [[nodiscard]] const T& front() const noexcept { return buffers_[front_]; }

 private:
  static constexpr std::uint8_t kIndex = 0x3;
  static constexpr std::uint8_t kFresh = 0x4;
  std::array<T, 3> buffers_{};
  std::uint8_t back_ = 0;   // the writer's
  std::uint8_t front_ = 1;  // the reader's
  std::atomic<std::uint8_t> middle_{2};
};

/// A small trivially copyable value written by one thread and read by any number: a sequence
/// counter around the value's words (all atomics, so no access is a data race). A reader retries
/// while a write is under way; the writer never waits.
template <class T>
class SeqlockValue {
  static_assert(std::is_trivially_copyable_v<T>, "SeqlockValue holds trivially copyable values");

 public:
  explicit SeqlockValue(const T& initial = T{}) noexcept { store(initial); }
  /// Writer thread only.
  void store(const T& value) noexcept {
    std::array<std::uint64_t, kWords> words{};
    std::memcpy(words.data(), &value, sizeof(T));
    const std::uint64_t s = seq_.load(std::memory_order_relaxed);
    seq_.store(s + 1, std::memory_order_relaxed);  // odd: a write is under way
    // Release stores (no standalone fences: ThreadSanitizer does not model them): the odd count
    // cannot move after a word, and a reader that sees a word also sees the odd count.
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(words[i], std::memory_order_release);
    seq_.store(s + 2, std::memory_order_release);
  }
  /// Any thread: a value stored whole.
  [[nodiscard]] T load() const noexcept {
    std::array<std::uint64_t, kWords> words{};
    for (;;) {
      const std::uint64_t before = seq_.load(std::memory_order_acquire);
      if ((before & 1U) != 0) continue;
      // Acquire loads: the second look at the count cannot move before them.
      for (std::size_t i = 0; i < kWords; ++i) words[i] = words_[i].load(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) == before) break;
    }
    T out;
    std::memcpy(static_cast<void*>(&out), words.data(), sizeof(T));
    return out;
  }

 private:
  static constexpr std::size_t kWords = (sizeof(T) + sizeof(std::uint64_t) - 1) / sizeof(std::uint64_t);
  std::array<std::atomic<std::uint64_t>, kWords> words_{};
  std::atomic<std::uint64_t> seq_{0};
};

}  // namespace tripodal
