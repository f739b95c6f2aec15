// cmd_vel round trip on loopback between two processes: this one publishes a Twist on
// rt/<ns>/cmd_vel, a copy of itself started with --echo (another process, so the sample crosses
// the loopback interface rather than Cyclone's in-process path) publishes it back on
// rt/<ns>/cmd_vel_echo, and this one waits for it. Reports the median and the 99th percentile.
//   tripodal_dds_bench [--domain N] [benchmark options]   (domain 200 unless given)
#include <benchmark/benchmark.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <csignal>
#include <cstring>
#include <string>
#include <thread>
#include <vector>

#include "tripodal/dds/endpoint.hpp"

extern char** environ;

using namespace tripodal::dds;
using namespace std::chrono_literals;

namespace {

std::uint32_t domain_id = 200;
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

}  // namespace

int main(int argc, char** argv) {
  std::vector<char*> args;
  bool echo = false;
  for (int i = 0; i < argc; ++i) {
    if (std::strcmp(argv[i], "--echo") == 0) {
      echo = true;
    } else if (std::strcmp(argv[i], "--domain") == 0 && i + 1 < argc) {
      domain_id = static_cast<std::uint32_t>(std::stoul(argv[++i]));
    } else {
      args.push_back(argv[i]);
    }
  }
  if (echo) return run_echo();

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
