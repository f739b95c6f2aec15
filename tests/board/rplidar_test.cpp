// The RPLIDAR A1 driver (board/rplidar_a1.hpp) and its protocol, against golden bytes decoded by
// hand from Slamtec's protocol tables and against the A1 emulator (sim/rplidar_emulator.hpp)
// through a kernel pseudo-terminal. Both ends run on one simulated clock in lock-step; the rig
// only waits (bounded) for the kernel to hand over bytes one end wrote. No sleeps.
#include <poll.h>

#include <array>
#include <atomic>
#include <catch2/catch.hpp>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <thread>
#include <vector>

#include "tripodal/board/board_hardware.hpp"
#include "tripodal/board/rplidar_a1.hpp"
#include "tripodal/board/rplidar_protocol.hpp"
#include "tripodal/board/serial_port.hpp"
#include "tripodal/robot/plugins.hpp"
#include "tripodal/sim/rplidar_emulator.hpp"
#include "tripodal/sim/simulator.hpp"
#include "tripodal/sim/world.hpp"

using namespace tripodal;
using namespace tripodal::board;
using namespace std::chrono_literals;
namespace rp = tripodal::board::rplidar;

namespace {

using Bytes = std::vector<std::uint8_t>;

template <std::size_t N>
std::span<const std::uint8_t, N> fixed(const Bytes& b, std::size_t at = 0) {
  return std::span<const std::uint8_t, N>(b.data() + at, N);
}

std::vector<rp::Node> decode_all(rp::NodeDecoder& d, const Bytes& bytes, std::size_t chunk) {
  std::vector<rp::Node> nodes;
  for (std::size_t i = 0; i < bytes.size(); i += chunk) {
    d.feed(std::span<const std::uint8_t>(bytes).subspan(i, std::min(chunk, bytes.size() - i)),
           [&](const rp::Node& n) { nodes.push_back(n); });
  }
  return nodes;
}

Bytes node_bytes(const rp::Node& n) {
  Bytes b(rp::kNodeBytes);
  rp::encode_node(n, std::span<std::uint8_t, rp::kNodeBytes>(b.data(), rp::kNodeBytes));
  return b;
}

// A byte stream that remembers whether it was written to, so the rig knows to wait for the kernel.
class Watched final : public ByteStream {
 public:
  explicit Watched(ByteStream& inner) : inner_(inner) {}
  bool write(std::span<const std::uint8_t> bytes) noexcept override {
    wrote_ = true;
    return inner_.write(bytes);
  }
  std::ptrdiff_t read(std::span<std::uint8_t> out, Time deadline) noexcept override { return inner_.read(out, deadline); }
  bool take_wrote() noexcept { return std::exchange(wrote_, false); }

 private:
  ByteStream& inner_;
  bool wrote_ = false;
};

// Waits (100 ms at most, real time) until `fd` has bytes to read.
void await_readable(int fd) {
  pollfd p{fd, POLLIN, 0};
  (void)::poll(&p, 1, 100);
}

// A scene of constant range: 2 m everywhere, 0.5 m between 80 and 100 degrees counter-clockwise.
class RingScene final : public sim::LidarScene {
 public:
  double range_m(double bearing_rad, Time) const noexcept override {
    double deg = std::fmod(bearing_rad * 180.0 / std::numbers::pi, 360.0);
    if (deg < 0.0) deg += 360.0;
    return deg > 80.0 && deg < 100.0 ? 0.5 : 2.0;
  }
};

// The A1 emulator on a pseudo-terminal's master, the driver on its slave, one simulated clock.
struct LidarRig {
  SimClock clock{Time{1s}};
  SteadyClock real;
  PseudoTerminal pty{real};
  SerialPort port{pty.slave_path(), real};
  Watched device_side{pty};
  Watched host_side{port};
  std::unique_ptr<sim::RplidarEmulator> emulator;
  struct Motor final : MotorSwitch {
    LidarRig* rig = nullptr;
    std::uint32_t switched = 0;
    bool stuck = false;  // a rotor that does not turn, whatever DTR says
    bool set_motor(bool on) noexcept override {
      ++switched;
      if (!stuck) rig->emulator->set_motor(on, rig->clock.now());
      return true;
    }
  } motor;
  std::unique_ptr<RplidarA1> lidar;

  LidarRig(const sim::LidarScene& scene, sim::RplidarEmulatorConfig emu = {}, RplidarConfig config = {}) {
    emulator = std::make_unique<sim::RplidarEmulator>(device_side, scene, emu, clock.now());
    motor.rig = this;
    lidar = std::make_unique<RplidarA1>("laser", host_side, config, &motor);
  }
  // One millisecond: the device, then the host, each seeing what the other wrote before.
  void step() {
    clock.advance(1ms);
    emulator->run_until(clock.now());
    if (device_side.take_wrote()) await_readable(port.fd());
    lidar->poll(clock.now());
    if (host_side.take_wrote()) await_readable(pty.master_fd());
  }
  void run_for(Duration d) {
    const Time end = clock.now() + d;
    while (clock.now() < end) step();
  }
  // Until the driver scans (bounded by 2 s of simulated time).
  void run_until_scanning() {
    for (int i = 0; i < 2000 && lidar->state() != RplidarA1::State::scanning; ++i) step();
    REQUIRE(lidar->state() == RplidarA1::State::scanning);
  }
};

}  // namespace

TEST_CASE("RPLIDAR protocol: golden bytes decoded by hand from the protocol tables", "[board][rplidar]") {
  SECTION("a measurement node") {
    // 0x3D = 0011 1101: S = 1, not-S = 0, quality 0x3D >> 2 = 15. Bytes 1-2 little-endian 0x5A01:
    // C = 1, angle_q6 = 0x5A01 >> 1 = 11520 = 180 deg. Bytes 3-4 0x2710 = 10000 q2 = 2500 mm.
    const Bytes b{0x3D, 0x01, 0x5A, 0x10, 0x27};
    REQUIRE(rp::check_node(fixed<5>(b)) == rp::NodeCheck::ok);
    const rp::Node n = rp::decode_node(fixed<5>(b));
    CHECK(n.start);
    CHECK(n.quality == 15);
    CHECK(n.angle_q6 == 11520);
    CHECK(n.angle_deg() == 180.0);
    CHECK(n.distance_q2 == 10000);
    CHECK(n.distance_m() == 2.5);
    CHECK(node_bytes(n) == b);
    // 0xBE = 1011 1110: S = 0, not-S = 1, quality 47; 0x0081 -> angle 64 = 1 deg; 0 = no return.
    const Bytes c{0xBE, 0x81, 0x00, 0x00, 0x00};
    REQUIRE(rp::check_node(fixed<5>(c)) == rp::NodeCheck::ok);
    CHECK(rp::decode_node(fixed<5>(c)) == rp::Node{false, 47, 64, 0});
  }
  SECTION("nodes that fail their checks") {
    CHECK(rp::check_node(fixed<5>(Bytes{0x3F, 0x01, 0, 0, 0})) == rp::NodeCheck::start_bits);  // S and not-S both 1
    CHECK(rp::check_node(fixed<5>(Bytes{0x3C, 0x01, 0, 0, 0})) == rp::NodeCheck::start_bits);  // both 0
    CHECK(rp::check_node(fixed<5>(Bytes{0x3D, 0x00, 0x5A, 0, 0})) == rp::NodeCheck::check_bit);
  }
  SECTION("response descriptors") {
    // SCAN: A5 5A 05 00 00 40 81 -> 0x40000005: length 5, mode 1 (multiple), type 0x81.
    const auto scan = rp::decode_descriptor(fixed<7>(Bytes{0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81}));
    REQUIRE(scan);
    CHECK(*scan == rp::kScanDescriptor);
    CHECK(scan->length == 5);
    CHECK(scan->mode == 1);
    Bytes out(7);
    rp::encode_descriptor(rp::kHealthDescriptor, std::span<std::uint8_t, 7>(out.data(), 7));
    CHECK(out == Bytes{0xA5, 0x5A, 0x03, 0x00, 0x00, 0x00, 0x06});
    rp::encode_descriptor(rp::kInfoDescriptor, std::span<std::uint8_t, 7>(out.data(), 7));
    CHECK(out == Bytes{0xA5, 0x5A, 0x14, 0x00, 0x00, 0x00, 0x04});
    CHECK_FALSE(rp::decode_descriptor(fixed<7>(Bytes{0x5A, 0xA5, 0x05, 0x00, 0x00, 0x40, 0x81})));
  }
  SECTION("requests") {
    std::array<std::uint8_t, 16> out{};
    REQUIRE(rp::encode_request(0x20, {}, out) == 2);
    CHECK(Bytes(out.begin(), out.begin() + 2) == Bytes{0xA5, 0x20});
    // With a payload: A5 F0 02 94 02 and the XOR of them all, A5^F0^02^94^02 = C1.
    const std::array<std::uint8_t, 2> payload{0x94, 0x02};
    REQUIRE(rp::encode_request(0xF0, payload, out) == 6);
    CHECK(Bytes(out.begin(), out.begin() + 6) == Bytes{0xA5, 0xF0, 0x02, 0x94, 0x02, 0xC1});
  }
  SECTION("GET_HEALTH and GET_INFO data") {
    CHECK(rp::decode_health(fixed<3>(Bytes{0x02, 0x34, 0x12})) == rp::Health{2, 0x1234});
    Bytes info{0x18, 0x1D, 0x01, 0x07};
    for (std::uint8_t i = 0; i < 16; ++i) info.push_back(i);
    const rp::DeviceInfo d = rp::decode_info(fixed<20>(info));
    CHECK(d.model == 0x18);
    CHECK(d.firmware_major == 1);
    CHECK(d.firmware_minor == 29);
    CHECK(d.hardware == 7);
    CHECK(d.serial[15] == 15);
  }
}

TEST_CASE("RPLIDAR node decoder: any read sizes, garbage mid-stream resynchronised and counted", "[board][rplidar]") {
  Bytes stream;
  for (std::uint16_t i = 0; i < 40; ++i) {
    const Bytes b = node_bytes(rp::Node{i == 0, 20, static_cast<std::uint16_t>(i * 64), static_cast<std::uint16_t>(4000 + i)});
    stream.insert(stream.end(), b.begin(), b.end());
  }
  Bytes with_garbage = stream;
  // 7 bytes of garbage after node 10: 0xFF fails the start bits wherever the decoder looks.
  with_garbage.insert(with_garbage.begin() + 50, {0xFF, 0xFF, 0x00, 0xFF, 0xFF, 0xFF, 0xFF});
  for (const std::size_t chunk : {std::size_t{1}, std::size_t{3}, std::size_t{64}}) {
    rp::NodeDecoder clean;
    CHECK(decode_all(clean, stream, chunk).size() == 40);
    CHECK(clean.stats().errors == 0);
    rp::NodeDecoder dirty;
    const auto nodes = decode_all(dirty, with_garbage, chunk);
    CHECK(dirty.stats().errors >= 1);
    CHECK(dirty.stats().resyncs == dirty.stats().errors);
    CHECK(dirty.stats().bytes == with_garbage.size());
    // Resynchronised on the first two good nodes after the garbage: none lost after it.
    REQUIRE(nodes.size() >= 38);
    CHECK(nodes.back().distance_q2 == 4039);
    CHECK(nodes[10].distance_q2 == 4010);
  }
}

TEST_CASE("RPLIDAR scan assembler: a revolution per start flag, nearest return per bin", "[board][rplidar]") {
  rp::ScanAssemblerConfig c;
  c.beams = 360;
  c.min_nodes = 10;
  rp::ScanAssembler a(c);
  const Time t0{1s};
  // A partial revolution before the first start flag is dropped.
  for (std::uint16_t i = 0; i < 5; ++i) CHECK_FALSE(a.add(rp::Node{false, 10, static_cast<std::uint16_t>(i * 64), 4000}, t0));
  int completed = 0;
  for (int rev = 0; rev < 3; ++rev) {
    for (std::uint16_t i = 0; i < 360; ++i) {
      // 90 deg clockwise (bin 90: -90 deg + 180) at 1 m, every other at 2 m; 10 deg nothing.
      const std::uint16_t q2 = i == 10 ? 0 : (i == 90 ? 4000 : 8000);
      completed += a.add(rp::Node{i == 0, static_cast<std::uint8_t>(q2 == 0 ? 0 : 10), static_cast<std::uint16_t>(i * 64), q2},
                         t0 + std::chrono::milliseconds(rev * 180))
                       ? 1
                       : 0;
    }
  }
  CHECK(completed == 2);
  CHECK(a.revolutions() == 2);
  CHECK(a.dropped() == 1);
  const LaserScan& s = a.scan();
  REQUIRE(s.ranges_m.size() == 360);
  CHECK(s.stamp == t0 + 180ms);
  CHECK(s.ranges_m[a.bin_of(90.0)] == 1.0F);
  CHECK(a.bin_of(90.0) == 90);    // -90 deg counter-clockwise
  CHECK(a.bin_of(0.0) == 180);    // the front
  CHECK(a.bin_of(270.0) == 270);  // +90 deg, the left
  CHECK(std::isinf(s.ranges_m[a.bin_of(10.0)]));
  CHECK(s.ranges_m[a.bin_of(200.0)] == 2.0F);
  CHECK(s.angle_min_rad == Approx(-std::numbers::pi));
  CHECK(s.angle_increment_rad == Approx(std::numbers::pi / 180.0));
}

TEST_CASE("RPLIDAR A1 over a pty: emulator and driver round trip match the ray caster within quantisation", "[board][rplidar]") {
  sim::World world = sim::load_world(std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs/worlds/workspace.yaml");
  ControllerConfig base;
  base.type = "differential";
  base.differential = {0.42, 0.09};
  sim::Simulator simulator(std::move(world), base, 1);
  sim::SimLidarScene scene(simulator);
  sim::RplidarEmulatorConfig emu;
  emu.sample_rate_hz = 1980.0;  // 360 samples a turn at 5.5 Hz: each sample on a bin's centre
  LidarRig rig(scene, emu);
  rig.run_until_scanning();
  CHECK(rig.lidar->device_info().model == 0x18);
  CHECK(rig.lidar->health().status == 0);
  rig.run_for(1s);
  const RplidarStats& s = rig.lidar->stats();
  CHECK(s.scans >= 4);
  CHECK(s.decoder_errors == 0);
  CHECK(rig.emulator->counters().bytes_lost == 0);
  REQUIRE(rig.lidar->has_reading());
  const LaserScan& scan = rig.lidar->latest();
  REQUIRE(scan.ranges_m.size() == 360);
  std::size_t returns = 0;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double bearing = scan.angle_min_rad + scan.angle_increment_rad * static_cast<double>(i);
    const double expected = scene.range_m(bearing, rig.clock.now());
    INFO("beam " << i << " bearing " << bearing);
    if (std::isfinite(expected) && expected >= 0.15 && expected <= 12.0) {
      ++returns;
      // distance_q2 is a quarter millimetre: rounding errs by 0.125 mm at most, plus float.
      CHECK(std::abs(scan.ranges_m[i] - expected) <= 1.3e-4);
    } else {
      CHECK(std::isinf(scan.ranges_m[i]));
    }
  }
  CHECK(returns > 300);  // the workspace is walled all round
}

TEST_CASE("RPLIDAR A1 over a pty: garbage mid-stream is skipped, counted, and scans go on", "[board][rplidar]") {
  RingScene scene;
  LidarRig rig(scene);
  rig.run_until_scanning();
  rig.run_for(500ms);
  const std::uint64_t before = rig.lidar->stats().scans;
  REQUIRE(before >= 1);
  const std::array<std::uint8_t, 9> garbage{0xFF, 0x00, 0xFF, 0xFC, 0xFF, 0x13, 0x00, 0xFF, 0xFF};
  rig.emulator->inject(garbage);
  rig.run_for(1s);
  const RplidarStats& s = rig.lidar->stats();
  CHECK(s.decoder_errors >= 1);
  CHECK(s.skipped_bytes >= 1);
  CHECK(s.scans >= before + 4);
  CHECK(rig.lidar->state() == RplidarA1::State::scanning);
  CHECK(rig.lidar->take_faults().empty());
  // The scan after the garbage is whole again: 0.5 m between 80 and 100 deg, 2 m elsewhere.
  const LaserScan& scan = rig.lidar->latest();
  CHECK(scan.ranges_m[180 + 90] == Approx(0.5));
  CHECK(scan.ranges_m[180] == Approx(2.0));
}

TEST_CASE("RPLIDAR A1 over a pty: a motor stopped by DTR is a fault within the timeout, and scans resume", "[board][rplidar]") {
  RingScene scene;
  RplidarConfig config;
  config.timeout = 400ms;
  LidarRig rig(scene, {}, config);
  rig.run_until_scanning();
  CHECK(rig.motor.switched >= 1);  // the driver switched the motor on
  CHECK(rig.emulator->motor_on());
  rig.run_for(500ms);
  REQUIRE(rig.lidar->stats().scans >= 1);
  CHECK(rig.lidar->take_faults().empty());
  const std::uint64_t scans_before_stop = rig.lidar->stats().scans;

  rig.emulator->set_motor(false, rig.clock.now());  // the motor stops (a stuck rotor)
  rig.motor.stuck = true;                           // and stays stopped whatever DTR says
  const Time stopped = rig.clock.now();
  Time faulted{};
  std::vector<std::string> faults;
  while (faults.empty() && rig.clock.now() - stopped < 2s) {
    rig.step();
    faults = rig.lidar->take_faults();
    faulted = rig.clock.now();
  }
  REQUIRE(faults.size() == 1);
  CHECK_THAT(faults[0], Catch::Contains("no revolution"));
  CHECK(faulted - stopped <= config.timeout + 10ms);  // the last start flag was before the stop
  CHECK(rig.lidar->state() == RplidarA1::State::stalled);
  CHECK_THAT(rig.lidar->last_error(), Catch::Contains("stopped spinning"));
  // Still stopped: the driver restarts its session and stays quiet (one fault per loss).
  rig.run_for(1s);
  CHECK(rig.lidar->take_faults().empty());
  CHECK(rig.lidar->stats().restarts >= 1);
  CHECK(rig.lidar->stats().scans == scans_before_stop);
  rig.motor.stuck = false;  // freed: the next restart's DTR spins it
  // The driver's restarts switch the motor on again (DTR released): scans resume.
  const std::uint64_t scans = rig.lidar->stats().scans;
  const std::uint32_t switched = rig.motor.switched;
  rig.run_for(1500ms);
  CHECK(rig.motor.switched > switched);
  CHECK(rig.lidar->stats().scans > scans);
  CHECK(rig.lidar->state() == RplidarA1::State::scanning);
}

TEST_CASE("RPLIDAR A1 over a pty: GET_HEALTH reporting an error fails with the code", "[board][rplidar]") {
  RingScene scene;
  sim::RplidarEmulatorConfig emu;
  emu.health = rp::Health{2, 0x1234};
  LidarRig rig(scene, emu);
  for (int i = 0; i < 1000 && rig.lidar->state() != RplidarA1::State::failed; ++i) rig.step();
  CHECK(rig.lidar->state() == RplidarA1::State::failed);
  CHECK_THAT(rig.lidar->last_error(), Catch::Contains("health status error (error code 0x1234)"));
  const auto faults = rig.lidar->take_faults();
  REQUIRE(faults.size() == 1);
  CHECK_THAT(faults[0], Catch::Contains("health status error"));
  CHECK(rig.emulator->counters().nodes == 0);
}

TEST_CASE("RPLIDAR A1 over a pty: a device answering garbage to GET_INFO fails naming it", "[board][rplidar]") {
  SimClock clock{Time{1s}};
  SteadyClock real;
  PseudoTerminal pty{real};
  SerialPort port{pty.slave_path(), real};
  RplidarA1 lidar("laser", port, RplidarConfig{});
  // A device that prints text whatever it is asked (a GPS, a console on the wrong port).
  const std::string text = "$GPGGA,123519,4807.038,N,01131.000,E,1,08,0.9,545.4,M,46.9,M,,*47\r\n";
  for (int i = 0; i < 1000 && lidar.state() != RplidarA1::State::failed; ++i) {
    clock.advance(1ms);
    lidar.poll(clock.now());
    if (i % 20 == 0 && i > 30) {
      REQUIRE(pty.write(std::span<const std::uint8_t>(reinterpret_cast<const std::uint8_t*>(text.data()), text.size())));
      await_readable(port.fd());
    }
  }
  REQUIRE(lidar.state() == RplidarA1::State::failed);
  CHECK_THAT(lidar.last_error(), Catch::Contains("answered GET_INFO with"));
  CHECK_THAT(lidar.last_error(), Catch::Contains("no RPLIDAR response descriptor"));
  CHECK_THAT(lidar.last_error(), Catch::Contains("24 47 50"));  // "$GP"
}

TEST_CASE("RPLIDAR A1 open: a path that does not exist, a regular file, a silent tty", "[board][rplidar]") {
  SteadyClock clock;
  RplidarConfig config;
  config.response_timeout = 50ms;
  REQUIRE_THROWS_WITH(RplidarA1::open("laser", "/dev/ttyUSB_no_such_lidar", config, clock),
                      Catch::Contains("RPLIDAR port /dev/ttyUSB_no_such_lidar does not exist"));
  const auto file = std::filesystem::temp_directory_path() / "tripodal_rplidar_not_a_tty";
  std::ofstream(file) << "not a tty\n";
  REQUIRE_THROWS_WITH(RplidarA1::open("laser", file, config, clock), Catch::Contains("is not a tty (it is a regular file"));
  std::filesystem::remove(file);
  // A tty on which nothing answers: the open gives up after the response timeout.
  PseudoTerminal pty{clock};
  REQUIRE_THROWS_WITH(RplidarA1::open("laser", pty.slave_path(), config, clock),
                      Catch::Contains("no answer to GET_INFO within 0.05 s") && Catch::Contains(pty.slave_path().string()));
}

TEST_CASE("hardware 'board' with lidar_port: the A1 opened beside the board as the resource 'laser'",
          "[board][rplidar][threads]") {
  HardwareRegistry registry("hardware type");
  register_board_hardware(registry);
  SteadyClock real;
  PseudoTerminal board_pty{real};  // the board's port: opened, never spoken to in this test
  PseudoTerminal lidar_pty{real};
  HardwareConfig c;
  c.type = "board";
  c.where = SourceLocation{SourceFile(std::string_view("robot.yaml")), 12, 3};
  ControllerConfig base;
  base.type = "differential";
  base.differential = {0.42, 0.09};
  c.base = &base;
  const auto params = [&](const std::string& lidar_port) {
    return ParameterSet::resolve(registry.manifest("board"),
                                 {{"port", Value{board_pty.slave_path().string()}}, {"lidar_port", Value{lidar_port}}}, c.where);
  };
  c.parameters = params("/nonexistent/ttyLIDAR");
  REQUIRE_THROWS_WITH(
      registry.create("board", c),
      Catch::Contains("robot.yaml:12:3: error: hardware 'board', lidar_port: RPLIDAR port /nonexistent/ttyLIDAR does not exist"));

  // The emulator on its own thread and clock, as in another process.
  RingScene scene;
  sim::RplidarEmulator emulator(lidar_pty, scene, {}, real.now());
  std::atomic<bool> stop{false};
  std::thread device([&] {
    Time next = real.now();
    while (!stop.load()) {
      next += 1ms;
      real.sleep_until(next);
      emulator.run_until(real.now());
    }
  });
  c.parameters = params(lidar_pty.slave_path().string());
  std::unique_ptr<CHardware> hw;
  CHECK_NOTHROW(hw = registry.create("board", c));
  stop.store(true);
  device.join();
  REQUIRE(hw);
  auto& board = dynamic_cast<BoardHardware&>(*hw);
  REQUIRE(board.lidar() != nullptr);
  CHECK(board.lidar()->state() == RplidarA1::State::scanning);
  CHECK(board.lidar()->device_info().model == 0x18);
  CHECK_FALSE(board.lidar()->motor_switchable());  // a pseudo-terminal has no DTR
  ResourceTable table;
  hw->add_resources(table);
  CHECK(table.find<LaserScan>("laser") == board.lidar());
}

TEST_CASE("resource type RplidarA1: registered with its manifest, a port that cannot be opened is a located error",
          "[board][rplidar]") {
  ResourceRegistry resources{"resource type"};
  register_rplidar_resource(resources);
  REQUIRE(resources.contains("RplidarA1"));
  CHECK(resources.manifest("RplidarA1").outputs == std::vector<std::string>{"laser_scan"});
  const SourceLocation where{SourceFile(std::string_view("robot.yaml")), 7, 5};
  REQUIRE_THROWS_WITH(ParameterSet::resolve(resources.manifest("RplidarA1"), {}, where), Catch::Contains("port"));
  const ResourceConfig c{
      "laser",
      ParameterSet::resolve(resources.manifest("RplidarA1"), {{"port", Value{std::string("/nonexistent/ttyUSB7")}}}, where),
      where, nullptr};
  REQUIRE_THROWS_WITH(
      resources.create("RplidarA1", c),
      Catch::Contains("robot.yaml:7:5: error: resource 'laser' (RplidarA1): RPLIDAR port /nonexistent/ttyUSB7 does not exist"));
}

TEST_CASE("A1 emulator: STOP ends the node stream, RESET answers with its banner, a bad checksum is refused",
          "[board][rplidar]") {
  RingScene scene;
  SimClock clock{Time{1s}};
  SteadyClock real;
  PseudoTerminal pty{real};
  SerialPort host{pty.slave_path(), real};
  sim::RplidarEmulator emulator(pty, scene, {}, clock.now());
  std::array<std::uint8_t, 4096> in{};
  const auto request = [&](std::initializer_list<std::uint8_t> bytes) {
    const Bytes b(bytes);
    REQUIRE(host.write(b));
    await_readable(pty.master_fd());
  };
  // Everything the emulator sends in `d`, read as the host would.
  const auto run_for = [&](Duration d) {
    Bytes got;
    const Time end = clock.now() + d;
    while (clock.now() < end) {
      clock.advance(1ms);
      emulator.run_until(clock.now());
      for (std::ptrdiff_t n = host.read(in, Time{}); n > 0; n = host.read(in, Time{}))
        got.insert(got.end(), in.begin(), in.begin() + n);
    }
    for (int i = 0; i < 20; ++i) {  // what the kernel still holds
      await_readable(host.fd());
      const std::ptrdiff_t n = host.read(in, Time{});
      if (n <= 0) break;
      got.insert(got.end(), in.begin(), in.begin() + n);
    }
    return got;
  };
  request({0xA5, 0x20});
  const Bytes scan = run_for(100ms);
  REQUIRE(scan.size() >= 7);
  CHECK(Bytes(scan.begin(), scan.begin() + 7) == Bytes{0xA5, 0x5A, 0x05, 0x00, 0x00, 0x40, 0x81});
  CHECK((scan.size() - 7) / 5 == Approx(200).margin(2));  // 2000 samples/s for 100 ms
  CHECK(emulator.scanning());
  request({0xA5, 0x25});
  (void)run_for(10ms);
  CHECK_FALSE(emulator.scanning());
  CHECK(run_for(100ms).empty());
  request({0xA5, 0x40});
  const Bytes banner = run_for(20ms);
  CHECK_THAT(std::string(banner.begin(), banner.end()), Catch::Contains("RPLIDAR A1"));
  const std::uint64_t requests = emulator.counters().requests;
  request({0xA5, 0x84, 0x01, 0x00, 0x00});  // a payload command whose checksum is wrong
  (void)run_for(10ms);
  CHECK(emulator.counters().requests == requests);
  CHECK(emulator.counters().bad_requests >= 1);
}
