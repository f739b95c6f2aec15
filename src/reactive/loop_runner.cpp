#include <algorithm>
#include <stdexcept>

#include "tripodal/reactive/control_loop.hpp"

#if defined(__linux__)
#include <pthread.h>
#include <sched.h>
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

LoopRunner::LoopRunner(ControlLoop& loop, const Clock& clock, LoopTimingOptions options)
    : loop_(loop), clock_(clock), options_(options), owned_stats_(std::make_unique<LoopStatistics>()), stats_(*owned_stats_) {}

LoopRunner::~LoopRunner() { stop(); }

void LoopRunner::start() {
  if (running_.load(std::memory_order_acquire) || thread_.joinable()) {
    throw std::logic_error("LoopRunner for '" + loop_.name() + "' is already running");
  }
  stop_.store(false, std::memory_order_release);
  stats_.reset();
  running_.store(true, std::memory_order_release);
  thread_ = std::thread([this] { run(); });
}

void LoopRunner::stop() noexcept {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
  running_.store(false, std::memory_order_release);
}

void LoopRunner::run() noexcept {
#if defined(__linux__)
  if (options_.cpu >= 0) {
    cpu_set_t set;
    CPU_ZERO(&set);
    CPU_SET(options_.cpu, &set);
    pthread_setaffinity_np(pthread_self(), sizeof set, &set);  // best effort
  }
  if (options_.realtime_priority > 0) {
    sched_param param{};
    param.sched_priority = std::clamp(options_.realtime_priority, sched_get_priority_min(SCHED_FIFO),
                                      sched_get_priority_max(SCHED_FIFO));
    // Refused without CAP_SYS_NICE or an rtprio limit: the loop then keeps normal scheduling.
    realtime_granted_.store(pthread_setschedparam(pthread_self(), SCHED_FIFO, &param) == 0, std::memory_order_release);
  }
#endif
  const Duration period = loop_.period();
  Time deadline = clock_.now() + period;
  while (!stop_.load(std::memory_order_acquire)) {
    clock_.sleep_until(deadline);
    const Time wake = clock_.now();
    loop_.step(wake);
    const Time end = clock_.now();
    stats_.record(wake - deadline, end - wake);
    deadline += period;
    if (end >= deadline) {
      // Overrun: skip the ticks already missed, keep the phase of the original grid.
      const auto missed = static_cast<std::uint64_t>((end - deadline) / period) + 1;
      deadline += static_cast<std::int64_t>(missed) * period;
      stats_.record_overrun(missed);
    }
  }
}

void SimLoopDriver::add(ControlLoop& loop) { loops_.push_back({&loop, clock_.now()}); }

std::size_t SimLoopDriver::run_until(Time until) noexcept {
  std::size_t cycles = 0;
  for (;;) {
    Entry* next = nullptr;
    for (Entry& e : loops_) {
      if (e.next <= until && (next == nullptr || e.next < next->next)) next = &e;
    }
    if (next == nullptr) break;
    clock_.set(next->next);
    next->loop->step(next->next);
    next->next += next->loop->period();
    ++cycles;
  }
  clock_.set(until);
  return cycles;
}

}  // namespace tripodal
