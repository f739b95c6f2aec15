// The control cycle over a real pseudo-terminal, in real time (issue 17's figures): the simulated
// board's firmware on its own thread ticking every 1 ms behind the pty's master, the host on the
// slave device as it would open the board's UART.
//  - BM_PtyRoundTrip: one DRIVE exchange (9 bytes out, 23 in) per 10 ms, timed from the request's
//    write to the response decoded; percentiles of the round trip as counters. The host wakes on
//    the response's bytes (ppoll on the port); the board answers on arrival (/on_arrival:1) or at
//    its next 1 ms tick (/on_arrival:0, as before issue 42). Target: p99 <= 1 ms.
//  - BM_PtyControlLoop100Hz: the host's BoardLink cycling at 100 Hz (DRIVE plus the sensor polls):
//    cycles, missed responses and the line utilisation the bytes would take at 115200 baud.
// A pseudo-terminal does not pace bytes at the baud rate: the round trip here is the OS's and the
// firmware's tick; a real UART adds 10 bits per byte (32 bytes: 2.78 ms) on top.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cstdint>
#include <thread>
#include <vector>

#include "tripodal/board/board_firmware.hpp"
#include "tripodal/board/board_link.hpp"
#include "tripodal/board/commands.hpp"
#include "tripodal/board/frame.hpp"
#include "tripodal/board/protocol_profile.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/clock.hpp"

using namespace tripodal;
using namespace tripodal::board;
using namespace std::chrono_literals;

namespace {

struct IdlePlant final : BoardPlant {
  void drive(Time, double, double) noexcept override {}
  void sense(Time, PlantSensors& out) noexcept override { out = PlantSensors{}; }
};

// The board on its thread: 1 ms ticks on the steady clock until stopped, and between them each
// request answered as its bytes arrive (serve_until: the UART's receive interrupt). With
// `on_arrival` false, the requests wait for the next tick (the loop before issue 42: p99 1.9 ms).
class BoardThread {
 public:
  explicit BoardThread(const SteadyClock& clock, bool on_arrival = true, const FirmwareConfig& config = {})
      : clock_(clock), pty_(clock), firmware_(config, pty_, plant_, clock.now()) {
    thread_ = std::thread([this, on_arrival] {
      Time next = clock_.now();
      const int fd = on_arrival ? pty_.master_fd() : -1;
      while (!stop_.load(std::memory_order_relaxed)) {
        next += 1ms;
        while (serve_until(firmware_, fd, clock_, next)) {
        }
        firmware_.run_until(clock_.now());
      }
    });
  }
  ~BoardThread() {
    stop_.store(true);
    thread_.join();
  }
  BoardThread(const BoardThread&) = delete;
  BoardThread& operator=(const BoardThread&) = delete;
  [[nodiscard]] const std::filesystem::path& device() const noexcept { return pty_.slave_path(); }

 private:
  const SteadyClock& clock_;
  IdlePlant plant_;
  PseudoTerminal pty_;
  BoardFirmware firmware_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// Sends one request and waits (at most 100 ms) for a response frame; returns the round trip.
Duration exchange(SerialPort& port, FrameDecoder& decoder, const SteadyClock& clock, Command cmd,
                  std::span<const std::uint8_t> payload) {
  std::array<std::uint8_t, kMaxFrameBytes> frame{};
  const std::size_t n = encode_request(static_cast<std::uint8_t>(cmd), payload, frame);
  const Time sent = clock.now();
  if (!port.write(std::span(frame.data(), n))) return Duration::max();
  std::array<std::uint8_t, 256> in{};
  while (clock.now() - sent < 100ms) {
    const std::ptrdiff_t got = port.read(in, clock.now() + 1ms);
    if (got < 0) return Duration::max();
    if (decoder.feed(std::span<const std::uint8_t>(in.data(), static_cast<std::size_t>(got))) > 0) return clock.now() - sent;
  }
  return Duration::max();
}

// Argument 1: the board answers on arrival; 0: at its next 1 ms tick (the comparison).
void BM_PtyRoundTrip(benchmark::State& state) {
  const SteadyClock clock;
  // The exchange below speaks tripodal-v1's frames (the default FrameDecoder's); the thesis's
  // board (FirmwareConfig's default since the protocol profiles) answered none of them: every
  // exchange was lost.
  FirmwareConfig v1;
  v1.protocol = resolve_protocol_profile("tripodal-v1", {});
  BoardThread board(clock, state.range(0) != 0, v1);
  SerialPort port(board.device(), clock);
  FrameDecoder decoder;
  (void)exchange(port, decoder, clock, Command::sync, {});
  std::array<std::uint8_t, 4> speeds{};
  ByteWriter w(speeds);
  pack(w, WheelSpeeds{100, 100});
  std::vector<double> rtt_us;
  std::uint64_t lost = 0;
  Time next = clock.now();
  for (auto _ : state) {
    next += 10ms;
    clock.sleep_until(next);
    const Duration d = exchange(port, decoder, clock, Command::drive, w.written());
    if (d == Duration::max()) {
      ++lost;
      state.SetIterationTime(0.1);
      continue;
    }
    state.SetIterationTime(to_seconds(d));
    rtt_us.push_back(to_seconds(d) * 1e6);
  }
  std::sort(rtt_us.begin(), rtt_us.end());
  const auto pct = [&](double p) { return rtt_us.empty() ? 0.0 : rtt_us[static_cast<std::size_t>(p * static_cast<double>(rtt_us.size() - 1))]; };
  state.counters["p50_us"] = pct(0.5);
  state.counters["p90_us"] = pct(0.9);
  state.counters["p99_us"] = pct(0.99);
  state.counters["max_us"] = pct(1.0);
  state.counters["lost"] = static_cast<double>(lost);
}
BENCHMARK(BM_PtyRoundTrip)
    ->ArgName("on_arrival")
    ->Arg(0)
    ->Arg(1)
    ->UseManualTime()
    ->Iterations(300)
    ->Unit(benchmark::kMicrosecond);

void BM_PtyControlLoop100Hz(benchmark::State& state) {
  const SteadyClock clock;
  BoardThread board(clock);
  SerialPort port(board.device(), clock);
  BoardLink link(port);
  Time next = clock.now();
  std::uint64_t late_cycles = 0;
  const Time start = clock.now();
  for (auto _ : state) {
    next += 10ms;
    clock.sleep_until(next);
    if (clock.now() - next > 5ms) ++late_cycles;  // the host itself woke half a period late
    link.cycle(clock.now(), WheelSpeeds{100, 100});
  }
  const double seconds = to_seconds(clock.now() - start);
  const LinkStats& s = link.stats();
  state.counters["cycles_per_s"] = static_cast<double>(state.iterations()) / seconds;
  state.counters["requests"] = static_cast<double>(s.requests);
  state.counters["responses"] = static_cast<double>(s.responses);
  state.counters["missed"] = static_cast<double>(s.missed);
  state.counters["link_losses"] = static_cast<double>(s.link_losses);
  state.counters["late_cycles"] = static_cast<double>(late_cycles);
  // 10 bits per byte at 115200 baud: the share of each direction the same bytes would take.
  state.counters["util_out_pct"] = 100.0 * static_cast<double>(port.bytes_written()) * 10.0 / 115200.0 / seconds;
  state.counters["util_in_pct"] = 100.0 * static_cast<double>(port.bytes_read()) * 10.0 / 115200.0 / seconds;
}
BENCHMARK(BM_PtyControlLoop100Hz)->Iterations(500)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
