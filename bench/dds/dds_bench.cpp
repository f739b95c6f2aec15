// cmd_vel round trip on loopback between two processes: this one publishes a Twist on
// rt/<ns>/cmd_vel, a copy of itself started with --echo (another process, so the sample crosses
// the loopback interface rather than Cyclone's in-process path) publishes it back on
// rt/<ns>/cmd_vel_echo, and this one waits for it. Reports the median and the 99th percentile.
// And a 1 kHz nav_msgs/Odometry stream on rt/<ns>/odom from another process (a copy of itself
// started with --odom-publisher) to a reader here, with the robot bridge's odometry QoS: what was
// sent, received, lost, out of order, the publisher's rate and worst overrun, the latency.
//   tripodal_dds_bench [--domain N] [--odom-seconds S] [benchmark options]
//   (domain 200, odometry stream 60 s unless given)
#include <benchmark/benchmark.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "tripodal/dds/endpoint.hpp"

extern char** environ;

using namespace tripodal::dds;
using namespace std::chrono_literals;

namespace {

std::uint32_t domain_id = 200;
std::int64_t odom_seconds = 60;
volatile std::sig_atomic_t stop = 0;

std::string ns() { return "tripodal_bench"; }

ParticipantOptions options() {
  ParticipantOptions o;
  o.domain_id = domain_id;
  return o;
}

int run_echo() {
  std::signal(SIGTERM, [](int) { stop = 1; });
  Participant p(options());
  Publisher<msg::Twist> back(p, ros_topic("cmd_vel_echo", ns()), {.kind = TopicKind::command});
  Subscriber<msg::Twist> in(p, ros_topic("cmd_vel", ns()), {.kind = TopicKind::command},
                            [&back](const msg::Twist& t) { back.publish(t); });
  while (stop == 0) std::this_thread::sleep_for(10ms);
  return 0;
}

void BM_CmdVelRoundTrip(benchmark::State& state) {
  Participant p(options());
  Publisher<msg::Twist> out(p, ros_topic("cmd_vel", ns()), {.kind = TopicKind::command});
  Subscriber<msg::Twist> back(p, ros_topic("cmd_vel_echo", ns()), {.kind = TopicKind::command});
  if (!out.wait_for_subscribers(1, 10s) || !back.wait_for_publishers(1, 10s)) {
    state.SkipWithError("the echo process did not match within 10 s");
    return;
  }
  // Warm up the path (and let the transient-local sample of a previous run pass).
  for (int i = 0; i < 100; ++i) {
    out.publish({});
    (void)back.take_one(1s);
  }
  (void)back.take(1000);
  std::vector<double> us;
  us.reserve(100000);
  msg::Twist t{{0.3, 0.0, 0.0}, {0.0, 0.0, 0.1}};
  for (auto _ : state) {
    t.linear.y += 1.0;  // a new value each time: the echo is this sample's, not an earlier one's
    const auto start = std::chrono::steady_clock::now();
    out.publish(t);
    std::optional<msg::Twist> got;
    do {
      got = back.take_one(1s);
    } while (got && got->linear.y != t.linear.y);
    const auto end = std::chrono::steady_clock::now();
    if (!got) {
      state.SkipWithError("a cmd_vel did not come back within 1 s");
      return;
    }
    const double elapsed = std::chrono::duration<double>(end - start).count();
    state.SetIterationTime(elapsed);
    us.push_back(elapsed * 1e6);
  }
  std::sort(us.begin(), us.end());
  state.counters["median_us"] = us[us.size() / 2];
  state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
  state.counters["max_us"] = us.back();
}
BENCHMARK(BM_CmdVelRoundTrip)->UseManualTime()->Unit(benchmark::kMicrosecond)->Iterations(5000);

// --- 1 kHz odometry stream ------------------------------------------------------------------
// The sample's sequence number travels in pose.covariance[0] (a double holds it exactly) and its
// send time in header.stamp, from the publisher's steady clock: std::chrono::steady_clock is
// CLOCK_MONOTONIC on Linux, one clock for every process of the host, so the reader's receive time
// minus the stamp is the latency across the two processes.
constexpr std::chrono::microseconds kOdomPeriod{1000};

msg::Time steady_stamp(std::chrono::steady_clock::time_point t) {
  const auto ns = std::chrono::duration_cast<std::chrono::nanoseconds>(t.time_since_epoch()).count();
  return {static_cast<std::int32_t>(ns / 1'000'000'000), static_cast<std::uint32_t>(ns % 1'000'000'000)};
}

std::chrono::steady_clock::time_point from_stamp(const msg::Time& t) {
  return std::chrono::steady_clock::time_point(std::chrono::seconds(t.sec) + std::chrono::nanoseconds(t.nanosec));
}

// The publisher process: waits for the reader's "go" (so that both sides have matched before the
// first sample), publishes `seconds` x 1000 samples at absolute deadlines start + k ms (a late
// sample does not shift the next ones), then its own figures on rt/<ns>/odom_summary.
int run_odom_publisher(std::int64_t seconds) {
  Participant p(options());
  Publisher<msg::Odometry> odom(p, ros_topic("odom", ns()), {.kind = TopicKind::state});
  // Event QoS (reliable, transient local both sides): neither message is lost to the order in
  // which the two processes discover each other.
  Subscriber<msg::String> go(p, ros_topic("odom_go", ns()), {.kind = TopicKind::event});
  Publisher<msg::String> summary(p, ros_topic("odom_summary", ns()), {.kind = TopicKind::event});
  if (!odom.wait_for_subscribers(1, 10s) || !go.take_one(10s)) {
    std::fprintf(stderr, "tripodal_dds_bench --odom-publisher: no reader within 10 s\n");
    return 1;
  }
  msg::Odometry m;
  m.header.frame_id = "odom";
  m.child_frame_id = "base_link";
  const std::int64_t n = seconds * 1000;
  using clock = std::chrono::steady_clock;
  const clock::time_point start = clock::now() + 10ms;
  clock::duration worst_overrun{0};
  std::int64_t late = 0;  // samples sent more than one period after their deadline
  clock::time_point first;
  clock::time_point last;
  for (std::int64_t k = 0; k < n; ++k) {
    const clock::time_point deadline = start + k * kOdomPeriod;
    std::this_thread::sleep_until(deadline);
    const clock::time_point now = clock::now();
    worst_overrun = std::max(worst_overrun, now - deadline);
    if (now - deadline > kOdomPeriod) ++late;
    if (k == 0) first = now;
    last = now;
    m.header.stamp = steady_stamp(now);
    m.pose.covariance[0] = static_cast<double>(k);
    m.pose.pose.position.x = 0.001 * static_cast<double>(k);  // a robot moving at 1 m/s
    m.twist.twist.linear.x = 1.0;
    odom.publish(m);
  }
  const bool acked = odom.wait_for_acknowledgments(10s);
  const double span_s = std::chrono::duration<double>(last - first).count();
  const double rate_hz = n > 1 && span_s > 0.0 ? static_cast<double>(n - 1) / span_s : 0.0;
  char text[160];
  std::snprintf(text, sizeof text, "%lld %.3f %.3f %d %lld", static_cast<long long>(n),
                std::chrono::duration<double, std::micro>(worst_overrun).count(), rate_hz, acked ? 1 : 0,
                static_cast<long long>(late));
  summary.publish({text});
  return summary.wait_for_acknowledgments(10s) ? 0 : 1;
}

void BM_OdometryStream(benchmark::State& state) {
  const std::int64_t seconds = state.range(0);
  struct Arrival {
    std::int64_t seq;
    double latency_us;
  };
  std::mutex mutex;
  std::vector<Arrival> arrivals;
  arrivals.reserve(static_cast<std::size_t>(seconds) * 1000 + 1000);
  Participant p(options());
  // The bridge's odometry QoS (TopicKind::state: reliable, volatile, keep last 10); the callback
  // takes each sample as it arrives, so the reader's history never has to hold ten.
  Subscriber<msg::Odometry> odom(p, ros_topic("odom", ns()), {.kind = TopicKind::state},
                                 [&](const msg::Odometry& m) {
                                   const auto now = std::chrono::steady_clock::now();
                                   const double us = std::chrono::duration<double, std::micro>(
                                                         now - from_stamp(m.header.stamp))
                                                         .count();
                                   const std::lock_guard lock(mutex);
                                   arrivals.push_back({static_cast<std::int64_t>(m.pose.covariance[0]), us});
                                 });
  Publisher<msg::String> go(p, ros_topic("odom_go", ns()), {.kind = TopicKind::event});
  Subscriber<msg::String> summary(p, ros_topic("odom_summary", ns()), {.kind = TopicKind::event});

  std::string self = "/proc/self/exe";
  std::string domain_text = std::to_string(domain_id);
  std::string seconds_text = std::to_string(seconds);
  std::vector<char*> child{self.data(),         const_cast<char*>("--odom-publisher"),
                           const_cast<char*>("--domain"), domain_text.data(),
                           const_cast<char*>("--odom-seconds"), seconds_text.data(), nullptr};
  pid_t pid = 0;
  if (posix_spawn(&pid, self.c_str(), nullptr, nullptr, child.data(), environ) != 0) {
    state.SkipWithError("cannot start the odometry publisher process");
    return;
  }
  std::optional<msg::String> result;
  for (auto _ : state) {
    const auto begin = std::chrono::steady_clock::now();
    if (odom.wait_for_publishers(1, 10s)) {
      go.publish({"go"});
      result = summary.take_one(std::chrono::seconds(seconds + 30));
    }
    // The whole exchange: the stream, then the publisher's wait for its acknowledgments.
    state.SetIterationTime(std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count());
  }
  if (!result) ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);
  long long sent = 0;
  double worst_overrun_us = 0.0;
  double rate_hz = 0.0;
  int acked = 0;
  long long late = 0;
  if (!result || std::sscanf(result->data.c_str(), "%lld %lf %lf %d %lld", &sent, &worst_overrun_us, &rate_hz,
                             &acked, &late) != 5) {
    state.SkipWithError("the odometry publisher gave no summary (no match within 10 s, or it died)");
    return;
  }
  // The publisher waited for the acknowledgment of every sample before its summary (all_acked);
  // the last callbacks may still be running.
  for (int i = 0; i < 100; ++i) {
    {
      const std::lock_guard lock(mutex);
      if (static_cast<long long>(arrivals.size()) >= sent) break;
    }
    std::this_thread::sleep_for(10ms);
  }
  std::vector<Arrival> got;
  {
    const std::lock_guard lock(mutex);
    got = arrivals;
  }
  std::vector<bool> seen(static_cast<std::size_t>(sent), false);
  std::int64_t out_of_order = 0;
  std::int64_t duplicates = 0;
  std::int64_t highest = -1;
  std::vector<double> us;
  us.reserve(got.size());
  for (const Arrival& a : got) {
    if (a.seq < 0 || a.seq >= sent) {
      state.SkipWithError("a sample with a sequence number outside the stream");
      return;
    }
    if (seen[static_cast<std::size_t>(a.seq)]) ++duplicates;
    seen[static_cast<std::size_t>(a.seq)] = true;
    if (a.seq < highest) ++out_of_order;
    highest = std::max(highest, a.seq);
    us.push_back(a.latency_us);
  }
  const auto distinct = std::count(seen.begin(), seen.end(), true);
  std::sort(us.begin(), us.end());
  state.counters["sent"] = static_cast<double>(sent);
  state.counters["received"] = static_cast<double>(got.size());
  state.counters["lost"] = static_cast<double>(sent - distinct);
  state.counters["out_of_order"] = static_cast<double>(out_of_order);
  state.counters["duplicates"] = static_cast<double>(duplicates);
  state.counters["all_acked"] = acked;
  state.counters["rate_hz"] = rate_hz;
  state.counters["worst_overrun_us"] = worst_overrun_us;
  state.counters["late_over_1ms"] = static_cast<double>(late);
  if (!us.empty()) {
    state.counters["median_us"] = us[us.size() / 2];
    state.counters["p99_us"] = us[std::min(us.size() - 1, us.size() * 99 / 100)];
    state.counters["max_us"] = us.back();
  }
}

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  bool echo = false;
  bool odom_publisher = false;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--echo") == 0) {
      echo = true;
    } else if (std::strcmp(argv[i], "--odom-publisher") == 0) {
      odom_publisher = true;
    } else if (std::strcmp(argv[i], "--domain") == 0 && i + 1 < argc) {
      domain_id = static_cast<std::uint32_t>(std::stoul(argv[++i]));
    } else if (std::strcmp(argv[i], "--odom-seconds") == 0 && i + 1 < argc) {
      odom_seconds = std::stoll(argv[++i]);
    } else {
      args.push_back(argv[i]);
    }
  }
  if (echo) return run_echo();
  if (odom_publisher) return run_odom_publisher(odom_seconds);
  if (odom_seconds < 1) {
    std::fprintf(stderr, "tripodal_dds_bench: --odom-seconds must be at least 1, got %lld\n",
                 static_cast<long long>(odom_seconds));
    return 1;
  }
  // Registered here so that --odom-seconds sets its length (BM_OdometryStream/<seconds>).
  benchmark::RegisterBenchmark("BM_OdometryStream", BM_OdometryStream)
      ->Arg(odom_seconds)
      ->UseManualTime()
      ->Unit(benchmark::kSecond)
      ->Iterations(1);

  std::string self = "/proc/self/exe";
  std::string domain_text = std::to_string(domain_id);
  std::vector<char*> child{self.data(), const_cast<char*>("--echo"), const_cast<char*>("--domain"),
                           domain_text.data(), nullptr};
  pid_t pid = 0;
  if (posix_spawn(&pid, self.c_str(), nullptr, nullptr, child.data(), environ) != 0) {
    std::perror("tripodal_dds_bench: cannot start the echo process");
    return 1;
  }
  int count = static_cast<int>(args.size());
  benchmark::Initialize(&count, args.data());
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  ::kill(pid, SIGTERM);
  ::waitpid(pid, nullptr, 0);
  return 0;
}
