#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "tripodal/reactive/control_loop.hpp"

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
#include <sys/mman.h>
#endif

namespace tripodal {

void LoopStatistics::record(Duration jitter, Duration execution) noexcept {
  auto bin = [](Duration d) noexcept {
    const auto us = std::max<std::int64_t>(0, d.count() / 1000);
    return static_cast<std::size_t>(std::min<std::int64_t>(us, static_cast<std::int64_t>(kBins) - 1));
  };
  ++jitter_[bin(jitter)];
  ++exec_[bin(execution)];
  ++cycles_;
  max_jitter_ = std::max(max_jitter_, jitter);
  max_exec_ = std::max(max_exec_, execution);
  jitter_sum_us_ += static_cast<double>(jitter.count()) / 1000.0;
}

void LoopStatistics::reset() noexcept {
  jitter_.fill(0);
  exec_.fill(0);
  cycles_ = overruns_ = skipped_ = 0;
  max_jitter_ = max_exec_ = Duration{0};
  jitter_sum_us_ = 0.0;
}

double LoopStatistics::mean_jitter_us() const noexcept {
  return cycles_ == 0 ? 0.0 : jitter_sum_us_ / static_cast<double>(cycles_);
}

Duration LoopStatistics::quantile(const std::array<std::uint32_t, kBins>& h, double q) const noexcept {
  if (cycles_ == 0) return Duration{0};
  q = std::clamp(q, 0.0, 1.0);
  // The smallest bin whose cumulative count reaches ceil(q * n) (at least 1).
  const auto target = std::max<std::uint64_t>(1, static_cast<std::uint64_t>(q * static_cast<double>(cycles_) + 0.999999));
  std::uint64_t seen = 0;
  for (std::size_t i = 0; i < kBins; ++i) {
    seen += h[i];
    if (seen >= target) return std::chrono::microseconds(static_cast<std::int64_t>(i) + 1);
  }
  return std::chrono::microseconds(static_cast<std::int64_t>(kBins));
}

ThreadSetup apply_thread_options(const LoopTimingOptions& options, std::string_view who) {
  ThreadSetup out;
  std::string refused;
  auto refuse = [&](const std::string& what, int err) {
    refused += (refused.empty() ? "" : ", ") + what + " (" + std::strerror(err) + ")";
  };
#if defined(__linux__)
  if (options.lock_memory) {
    // Process-wide: the first thread that asks locks what is mapped now and what is mapped later.
    static std::atomic<int> locked{-1};  // -1: not tried; else the errno of the one attempt (0: locked)
    int expected = -1;
    if (locked.load(std::memory_order_acquire) == -1) {
      const int err = mlockall(MCL_CURRENT | MCL_FUTURE) == 0 ? 0 : errno;
      locked.compare_exchange_strong(expected, err, std::memory_order_acq_rel);
    }
    const int err = locked.load(std::memory_order_acquire);
    out.memory_locked = err == 0;
    if (err != 0) refuse("mlockall", err);
  }
  if (options.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(options.cpu, &set);
    const int err = pthread_setaffinity_np(pthread_self(), sizeof set, &set);
    out.pinned = err == 0;
    if (err != 0) refuse("CPU " + std::to_string(options.cpu), err);
  }
  if (options.realtime_priority > 0) {
    sched_param param{};
    param.sched_priority =
        std::clamp(options.realtime_priority, sched_get_priority_min(SCHED_FIFO), sched_get_priority_max(SCHED_FIFO));
    // Refused without CAP_SYS_NICE or an rtprio limit: the loop then keeps normal scheduling.
    const int err = pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
    out.realtime = err == 0;
    if (err != 0) refuse("SCHED_FIFO " + std::to_string(param.sched_priority), err);
  }
#else
  if (options.lock_memory) refused += "mlockall (not on this system)";
  if (options.cpu >= 0) refused += std::string(refused.empty() ? "" : ", ") + "CPU pinning (not on this system)";
  if (options.realtime_priority > 0) refused += std::string(refused.empty() ? "" : ", ") + "SCHED_FIFO (not on this system)";
#endif
  if (!refused.empty())
    out.warning = "warning: " + std::string(who) + ": not permitted: " + refused + "; running with normal scheduling";
  return out;
}

PeriodicRunner::PeriodicRunner(std::string name, Duration period, const Clock& clock, Cycle cycle, LoopTimingOptions options)
    : name_(std::move(name)),
      period_(period),
      budget_(options.budget > Duration{0} ? options.budget : period),
      clock_(clock),
      cycle_(std::move(cycle)),
      options_(options),
      stats_(std::make_unique<LoopStatistics>()) {
  if (period_ <= Duration{0}) throw std::invalid_argument("periodic thread '" + name_ + "': the period must be > 0");
  if (!cycle_) throw std::invalid_argument("periodic thread '" + name_ + "': no cycle to run");
}

PeriodicRunner::~PeriodicRunner() {
  stop();
}

void PeriodicRunner::start() {
  if (running_.load(std::memory_order_acquire) || thread_.joinable()) {
    throw std::logic_error("periodic thread '" + name_ + "' is already running");
  }
  stop_.store(false, std::memory_order_release);
  started_.store(false, std::memory_order_release);
  stats_->reset();
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this] { run(); });
  // setup() is the thread's until it says it has applied its options.
  while (!started_.load(std::memory_order_acquire)) std::this_thread::yield();
}

void PeriodicRunner::stop() noexcept {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  running_.store(false, std::memory_order_release);
}

void PeriodicRunner::run() noexcept {
  setup_ = apply_thread_options(options_, "loop '" + name_ + "'");
  started_.store(true, std::memory_order_release);
  Time deadline = clock_.now() + period_;
  std::uint32_t in_a_row = 0;
  while (!stop_.load(std::memory_order_acquire)) {
    clock_.sleep_until(deadline);
    const Time wake = clock_.now();
    cycle_(wake);
    const Time end = clock_.now();
    stats_->record(wake - deadline, end - wake);
    if (end - deadline > budget_) {
      stats_->record_overrun();
      overruns_.fetch_add(1, std::memory_order_acq_rel);
      // One fault per run of N: a loop that stays late does not flood the supervisor.
      if (++in_a_row == options_.deadline_overruns) deadline_faults_.fetch_add(1, std::memory_order_acq_rel);
    } else {
      in_a_row = 0;
    }
    deadline += period_;
    if (end >= deadline) {
      // Skip the ticks already missed, keep the phase of the original grid.
      const auto missed = static_cast<std::uint64_t>((end - deadline) / period_) + 1;
      deadline += static_cast<std::int64_t>(missed) * period_;
      stats_->record_skipped(missed);
    }
  }
}

LoopRunner::LoopRunner(ControlLoop& loop, const Clock& clock, LoopTimingOptions options)
    : runner_(
          loop.name(), loop.period(), clock, [&loop](Time now) { (void)loop.step(now); }, options) {}

}  // namespace tripodal
