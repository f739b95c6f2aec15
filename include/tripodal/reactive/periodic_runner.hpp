// The wall-clock runtime's pacing: a thread that runs one cycle at absolute deadlines of a clock
// (start + k * period, no drift from relative sleeps), measures its period error, counts overruns
// beyond its budget and raises a deadline fault after a run of them. The robot runs its reactive
// loops and its sequencing loop each on one (Robot::start); LoopRunner is one for a bare ControlLoop.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <thread>

#include "tripodal/core/clock.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal {

/// How a periodic thread is scheduled and when it is late. A missed deadline (a cycle that ends
/// after the next deadline) skips the missed ticks rather than catching up: the next deadline is
/// the first one of the original grid later than the moment the late cycle ended, so the phase is
/// kept and no burst of back-to-back cycles follows an overrun.
struct LoopTimingOptions {
  int realtime_priority = 0;  ///< SCHED_FIFO priority 1..99; 0 = normal scheduling
  int cpu = -1;               ///< pin to this CPU; -1 = no pinning
  bool lock_memory = false;   ///< mlockall(current and future) before the first cycle (process-wide)
  /// A cycle that ends later than its deadline + budget is an overrun; 0 = the period.
  Duration budget{0};
  /// This many overruns in a row raise one deadline fault (the robot posts "<loop>.deadline");
  /// 0 = overruns are counted only.
  std::uint32_t deadline_overruns = 0;
};

/// What a thread was granted of its LoopTimingOptions. `warning` is one line naming what was
/// asked and refused (empty when everything asked was granted).
struct ThreadSetup {
  bool realtime = false;
  bool pinned = false;
  bool memory_locked = false;
  std::string warning;
};

/// Applies `options` to the calling thread (SCHED_FIFO, CPU affinity) and, when asked, locks the
/// process's memory. Never throws: what the process may not do is left as it is and named in the
/// warning (unprivileged is fine: normal scheduling). `who` names the thread in the warning.
[[nodiscard]] ThreadSetup apply_thread_options(const LoopTimingOptions& options, std::string_view who);

/// Period error (wake-up time - deadline on the absolute grid) and execution time statistics, in
/// 1 microsecond histogram bins (quantiles are bin upper edges); no allocation while recording.
class LoopStatistics {
 public:
  static constexpr std::size_t kBins = 20000;  ///< 0..20 ms; later values land in the last bin
  void record(Duration jitter, Duration execution) noexcept;
  /// A cycle ended beyond its budget.
  void record_overrun() noexcept { ++overruns_; }
  /// Ticks of the grid skipped after a cycle that ended past the next deadline.
  void record_skipped(std::uint64_t ticks) noexcept { skipped_ += ticks; }
  void reset() noexcept;
  [[nodiscard]] std::uint64_t cycles() const noexcept { return cycles_; }
  [[nodiscard]] std::uint64_t overruns() const noexcept { return overruns_; }
  [[nodiscard]] std::uint64_t skipped_ticks() const noexcept { return skipped_; }
  /// Quantile q in [0, 1] of the period error (wake time - deadline) and execution time.
  [[nodiscard]] Duration jitter_quantile(double q) const noexcept { return quantile(jitter_, q); }
  [[nodiscard]] Duration execution_quantile(double q) const noexcept { return quantile(exec_, q); }
  [[nodiscard]] Duration max_jitter() const noexcept { return max_jitter_; }
  [[nodiscard]] Duration max_execution() const noexcept { return max_exec_; }
  [[nodiscard]] double mean_jitter_us() const noexcept;

 private:
  Duration quantile(const std::array<std::uint32_t, kBins>& h, double q) const noexcept;
  std::array<std::uint32_t, kBins> jitter_{};
  std::array<std::uint32_t, kBins> exec_{};
  std::uint64_t cycles_ = 0, overruns_ = 0, skipped_ = 0;
  Duration max_jitter_{0}, max_exec_{0};
  double jitter_sum_us_ = 0.0;
};

/// Runs `cycle(now)` on its own thread at absolute deadlines of `clock`: the first one period after
/// start(), then every period. The cycle must not throw (a throwing cycle terminates). Threading:
/// start()/stop() from one owner thread; overruns(), deadline_faults() from any thread;
/// statistics() after stop().
class PeriodicRunner final {
 public:
  using Cycle = std::function<void(Time now)>;
  /// Throws std::invalid_argument for a period <= 0 or an empty cycle.
  PeriodicRunner(std::string name, Duration period, const Clock& clock, Cycle cycle, LoopTimingOptions options = {});
  ~PeriodicRunner();  ///< stops the thread
  PeriodicRunner(const PeriodicRunner&) = delete;
  PeriodicRunner& operator=(const PeriodicRunner&) = delete;

  /// Starts the thread and returns once it has applied its LoopTimingOptions (setup() is then
  /// valid). Throws std::logic_error when already running.
  void start();
  /// Stops after the current cycle and joins; idempotent.
  void stop() noexcept;
  [[nodiscard]] bool running() const noexcept { return running_.load(std::memory_order_acquire); }
  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  [[nodiscard]] Duration period() const noexcept { return period_; }
  /// The overrun budget in force (the options' budget, or the period).
  [[nodiscard]] Duration budget() const noexcept { return budget_; }
  [[nodiscard]] const LoopTimingOptions& options() const noexcept { return options_; }
  /// What the thread was granted; valid after start().
  [[nodiscard]] const ThreadSetup& setup() const noexcept { return setup_; }
  [[nodiscard]] bool realtime_granted() const noexcept { return started_.load(std::memory_order_acquire) && setup_.realtime; }
  /// Cycles beyond their budget so far (any thread).
  [[nodiscard]] std::uint64_t overruns() const noexcept { return overruns_.load(std::memory_order_acquire); }
  /// Runs of options().deadline_overruns overruns in a row so far (any thread): a consumer keeps
  /// the count it has seen and reports each new one as a fault.
  [[nodiscard]] std::uint64_t deadline_faults() const noexcept { return deadline_faults_.load(std::memory_order_acquire); }
  /// Statistics; read them after stop() (the thread writes them while running).
  [[nodiscard]] const LoopStatistics& statistics() const noexcept { return *stats_; }

 private:
  void run() noexcept;
  std::string name_;
  Duration period_;
  Duration budget_;
  const Clock& clock_;
  Cycle cycle_;
  LoopTimingOptions options_;
  ThreadSetup setup_;
  std::thread thread_;
  std::atomic<bool> running_{false};
  std::atomic<bool> stop_{false};
  std::atomic<bool> started_{false};
  std::atomic<std::uint64_t> overruns_{0};
  std::atomic<std::uint64_t> deadline_faults_{0};
  std::unique_ptr<LoopStatistics> stats_;
};

}  // namespace tripodal
