#include "tripodal/board/serial_port.hpp"

#include <catch2/catch.hpp>

#include <fcntl.h>
#include <linux/capability.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <memory>
#include <vector>

#include "tripodal/board/frame.hpp"
#include "tripodal/board/serial_line.hpp"

using namespace tripodal;
using namespace tripodal::board;
using namespace std::chrono_literals;

namespace {

// Reads until `n` bytes came or `tries` bounded reads (1 ms each at most) passed: no sleeps, and
// a simulated clock that stands still makes every read wait its whole 1 ms budget at most.
std::vector<std::uint8_t> read_n(ByteStream& s, std::size_t n, const Clock& clock, int tries = 2000) {
  std::vector<std::uint8_t> got;
  std::array<std::uint8_t, 256> buf{};
  while (got.size() < n && tries-- > 0) {
    const std::ptrdiff_t r = s.read(buf, clock.now() + 1s);
    REQUIRE(r >= 0);
    got.insert(got.end(), buf.begin(), buf.begin() + r);
  }
  return got;
}

}  // namespace

TEST_CASE("a read waits for its deadline, never more than 1 ms", "[board][serial]") {
  CHECK(read_wait(Time{}, Time{5s}) == 1ms);
  CHECK(read_wait(Time{10ms}, Time{10ms + 300us}) == 300us);
  CHECK(read_wait(Time{10ms}, Time{10ms}) == 0ns);
  CHECK(read_wait(Time{10ms}, Time{9ms}) == 0ns);  // deadline passed: just poll
}

TEST_CASE("the port is raw 115200 8N1 and carries every byte value unchanged", "[board][serial]") {
  SimClock clock;
  PseudoTerminal pty(clock);
  SerialPort port(pty.slave_path(), clock);

  termios t{};
  REQUIRE(::tcgetattr(port.fd(), &t) == 0);
  CHECK(::cfgetispeed(&t) == B115200);
  CHECK(::cfgetospeed(&t) == B115200);
  CHECK((t.c_cflag & CSIZE) == CS8);
  CHECK((t.c_cflag & PARENB) == 0);
  CHECK((t.c_cflag & CSTOPB) == 0);
  CHECK((t.c_cflag & CRTSCTS) == 0);
  CHECK((t.c_lflag & (ICANON | ECHO | ISIG | IEXTEN)) == 0);
  CHECK((t.c_iflag & (ICRNL | INLCR | IGNCR | IXON | IXOFF | ISTRIP)) == 0);
  CHECK((t.c_oflag & OPOST) == 0);
  CHECK(t.c_cc[VMIN] == 0);

  // All 256 values, CR, LF, XON/XOFF, ^C and DEL included, both ways.
  std::vector<std::uint8_t> all(256);
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<std::uint8_t>(i);
  REQUIRE(port.write(all));
  CHECK(read_n(pty, all.size(), clock) == all);
  REQUIRE(pty.write(all));
  CHECK(read_n(port, all.size(), clock) == all);
  CHECK(port.bytes_written() == 256);
  CHECK(port.bytes_read() == 256);
}

TEST_CASE("frames cross the pseudo-terminal and decode on the other side", "[board][serial]") {
  SimClock clock;
  PseudoTerminal pty(clock);
  SerialPort port(pty.slave_path(), clock);
  std::array<std::uint8_t, kMaxFrameBytes> out{};
  const std::array<std::uint8_t, 4> speeds{0xC8, 0x00, 0xFA, 0x00};
  const std::size_t n = encode_request(0x12, speeds, out);
  for (int i = 0; i < 10; ++i) REQUIRE(port.write(std::span<const std::uint8_t>(out).first(n)));
  const auto got = read_n(pty, 10 * n, clock);
  FrameDecoder d;
  CHECK(d.feed(got) == 10);
  CHECK(d.frame().body[1] == 0x12);
}

TEST_CASE("a read with nothing to read returns 0 at its deadline", "[board][serial]") {
  SimClock clock(Time{1s});
  PseudoTerminal pty(clock);
  SerialPort port(pty.slave_path(), clock);
  std::array<std::uint8_t, 16> buf{};
  CHECK(port.read(buf, clock.now()) == 0);       // deadline now: a poll
  CHECK(port.read(buf, clock.now() + 1h) == 0);  // bounded to 1 ms
  CHECK(pty.read(buf, clock.now()) == 0);
}

TEST_CASE("a port whose other end hangs up reports it", "[board][serial]") {
  SimClock clock;
  auto pty = std::make_unique<PseudoTerminal>(clock);
  SerialPort port(pty->slave_path(), clock);
  pty.reset();
  std::array<std::uint8_t, 16> buf{};
  CHECK(port.read(buf, clock.now()) == -1);  // a poll (no wait, the read alone) sees it too
  CHECK(port.read(buf, clock.now() + 1s) == -1);
}

TEST_CASE("opening a port that is not one fails with the path and the reason", "[board][serial]") {
  SimClock clock;
  REQUIRE_THROWS_WITH(SerialPort("/nonexistent/ttyBOARD", clock),
                      "serial port /nonexistent/ttyBOARD: open: No such file or directory");
  const std::filesystem::path file = std::filesystem::temp_directory_path() / "tripodal_not_a_tty";
  std::ofstream(file) << "x";
  REQUIRE_THROWS_WITH(SerialPort(file, clock),
                      Catch::Contains("tripodal_not_a_tty: tcgetattr: Inappropriate ioctl for device"));
  std::filesystem::remove(file);
  PseudoTerminal pty(clock);
  REQUIRE_THROWS_WITH(SerialPort(pty.slave_path(), clock, SerialSettings{1234}),
                      Catch::Contains("baud 1234 is not supported; expected one of 9600"));
}

namespace {
// Another process opens `path` as a terminal program would: its errno (0 when it opened). It
// drops CAP_SYS_ADMIN first, as the tests run as root and an administrator may open an exclusive
// tty all the same.
int open_from_another_process(const std::filesystem::path& path) {
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    __user_cap_header_struct header{_LINUX_CAPABILITY_VERSION_3, 0};
    std::array<__user_cap_data_struct, 2> caps{};
    if (::syscall(SYS_capget, &header, caps.data()) != 0) ::_exit(250);
    caps[CAP_SYS_ADMIN / 32].effective &= ~(1U << (CAP_SYS_ADMIN % 32));
    if (::syscall(SYS_capset, &header, caps.data()) != 0) ::_exit(251);
    const int fd = ::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK);
    ::_exit(fd >= 0 ? 0 : errno);
  }
  int status = 0;
  REQUIRE(::waitpid(pid, &status, 0) == pid);
  REQUIRE(WIFEXITED(status));
  return WEXITSTATUS(status);
}
}  // namespace

TEST_CASE("the port is opened exclusively: another process's open fails with EBUSY", "[board][serial]") {
  SimClock clock;
  PseudoTerminal pty(clock);
  CHECK(open_from_another_process(pty.slave_path()) == 0);  // free before the host takes it
  {
    SerialPort port(pty.slave_path(), clock);
    CHECK(open_from_another_process(pty.slave_path()) == EBUSY);
    REQUIRE(port.reopen());  // our own reopen is not refused: the flag is cleared before closing
    CHECK(open_from_another_process(pty.slave_path()) == EBUSY);
  }
  // Closed: the tty lives on (the pseudo-terminal holds it) and is free again.
  CHECK(open_from_another_process(pty.slave_path()) == 0);
}

TEST_CASE("the settings are read back and a change under the port names the setting", "[board][serial]") {
  SimClock clock;
  PseudoTerminal pty(clock);
  // A neighbour that had the line open before the host took it.
  const int other = ::open(pty.slave_path().c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  REQUIRE(other >= 0);
  SerialPort port(pty.slave_path(), clock);
  CHECK(port.check().empty());
  CHECK(raw_settings_mismatch(other, 115200).empty());
  CHECK(raw_settings_mismatch(other, 9600) == "ispeed differs from the configured baud");

  const auto change = [&](auto&& edit) {
    termios t{};
    REQUIRE(::tcgetattr(other, &t) == 0);
    edit(t);
    const int rc = ::tcsetattr(other, TCSANOW, &t);
    INFO("tcsetattr: " << std::strerror(errno));
    REQUIRE(rc == 0);
  };
  change([](termios& t) { t.c_lflag |= ICANON | ECHO; });  // `stty icanon echo`
  CHECK(port.check() == "icanon on, expected off");
  REQUIRE(port.reopen());
  CHECK(port.check().empty());
  change([](termios& t) { t.c_lflag |= ECHO; });
  CHECK(port.check() == "echo on, expected off");
  REQUIRE(port.reopen());
  change([](termios& t) { t.c_iflag |= IXON; });  // (a pseudo-terminal refuses parity: no cflag case)
  CHECK(port.check() == "ixon on, expected off");
  REQUIRE(port.reopen());
  change([](termios& t) { t.c_oflag |= OPOST; });
  CHECK(port.check() == "opost on, expected off");
  REQUIRE(port.reopen());
  change([](termios& t) { t.c_cc[VMIN] = 1; });
  CHECK(port.check() == "min not 0 (reads would block)");
  REQUIRE(port.reopen());
  change([](termios& t) {
    ::cfsetispeed(&t, B9600);
    ::cfsetospeed(&t, B9600);
  });
  CHECK(port.check() == "ispeed differs from the configured baud");
  REQUIRE(port.reopen());
  CHECK(port.check().empty());
  ::close(other);
  CHECK(raw_settings_mismatch(-1, 115200) == kDeviceGone);
}

TEST_CASE("a port that cannot be reopened says why", "[board][serial]") {
  SimClock clock;
  const std::filesystem::path link = std::filesystem::temp_directory_path() / "tripodal_serial_reopen_link";
  std::filesystem::remove(link);
  auto pty = std::make_unique<PseudoTerminal>(clock);
  std::filesystem::create_symlink(pty->slave_path(), link);
  SerialPort port(link, clock);
  std::filesystem::remove(link);
  CHECK_FALSE(port.reopen());
  CHECK_THAT(port.last_reopen_error(), Catch::Contains("tripodal_serial_reopen_link: open: No such file or directory"));
  CHECK(port.check() == kDeviceGone);
  std::filesystem::create_symlink(pty->slave_path(), link);
  CHECK(port.reopen());
  CHECK(port.last_reopen_error().empty());
  std::filesystem::remove(link);
}

TEST_CASE("a noisy line corrupts, drops and duplicates bytes at its rates, repeatably by seed", "[board][serial][noise]") {
  const auto carry = [](const LineNoise& noise, std::vector<std::uint8_t>& got) {
    SimClock clock;
    SerialLine line(clock);
    line.host().set_noise(noise);
    std::vector<std::uint8_t> chunk(1000);
    for (std::size_t i = 0; i < chunk.size(); ++i) chunk[i] = static_cast<std::uint8_t>(i * 7);
    std::array<std::uint8_t, 4096> buf{};
    for (int k = 0; k < 100; ++k) {
      REQUIRE(line.host().write(chunk));
      clock.advance(line.byte_time() * 3000);
      const std::ptrdiff_t n = line.board().read(buf, clock.now());
      REQUIRE(n >= 0);
      got.insert(got.end(), buf.begin(), buf.begin() + n);
    }
    return std::array<std::uint64_t, 4>{line.host().bytes_sent(), line.host().bytes_corrupted(), line.host().bytes_dropped(),
                                        line.host().bytes_duplicated()};
  };
  std::vector<std::uint8_t> a, b, c, clean;
  const auto counts = carry(LineNoise{0.01, 0.01, 0.01, 7}, a);
  CHECK(counts[0] == 100'000);
  CHECK(counts[1] == Approx(1000).epsilon(0.15));  // 1 % of 100 000, 3 sigma about 10 %
  CHECK(counts[2] == Approx(1000).epsilon(0.15));
  CHECK(counts[3] == Approx(1000).epsilon(0.15));
  CHECK(a.size() == counts[0] - counts[2] + counts[3]);
  (void)carry(LineNoise{0.01, 0.01, 0.01, 7}, b);
  CHECK(a == b);  // the same seed, the same line
  (void)carry(LineNoise{0.01, 0.01, 0.01, 8}, c);
  CHECK(a != c);
  const auto none = carry(LineNoise{}, clean);
  CHECK(none[1] + none[2] + none[3] == 0);
  CHECK(clean.size() == 100'000);
}

// `tripodal run --board pty`: the simulated line's timing, the bytes through the kernel.
TEST_CASE("a line carried over a pseudo-terminal delivers what the in-process line does, when it does", "[board][serial]") {
  SimClock sim;
  const SteadyClock real;
  PseudoTerminal pty(real);
  SerialPort port(pty.slave_path(), real);
  SerialLine carried(sim);
  carried.carry_over(port, pty, real);
  SerialLine plain(sim);

  std::vector<std::uint8_t> request(20);
  for (std::size_t i = 0; i < request.size(); ++i) request[i] = static_cast<std::uint8_t>(0xA0 + i);
  REQUIRE(carried.host().write(request));
  REQUIRE(plain.host().write(request));
  CHECK(port.bytes_written() == request.size());  // into the kernel's tty, not a copy in memory

  std::array<std::uint8_t, 64> a{};
  std::array<std::uint8_t, 64> b{};
  sim.advance(carried.byte_time() * 10);  // ten characters on the wire so far
  const std::ptrdiff_t na = carried.board().read(a, sim.now());
  const std::ptrdiff_t nb = plain.board().read(b, sim.now());
  REQUIRE(na == 10);
  REQUIRE(nb == 10);
  CHECK(std::equal(a.begin(), a.begin() + 10, b.begin()));
  sim.advance(carried.byte_time() * 10);
  REQUIRE(carried.board().read(a, sim.now()) == 10);
  CHECK(std::equal(a.begin(), a.begin() + 10, request.begin() + 10));

  const std::array<std::uint8_t, 3> response{0x10, 0x02, 0x81};
  REQUIRE(carried.board().write(response));
  CHECK(carried.host().read(a, sim.now()) == 0);  // still on the wire
  sim.advance(carried.byte_time() * 3);
  REQUIRE(carried.host().read(a, sim.now()) == 3);
  CHECK(std::equal(response.begin(), response.end(), a.begin()));
  CHECK(carried.board().bytes_lost() == 0);
  CHECK(carried.host().bytes_lost() == 0);
}

namespace {
// A carrier that takes bytes and never delivers them; each read costs 1 ms of its clock.
class DeadCarrier final : public ByteStream {
 public:
  explicit DeadCarrier(SimClock& clock) : clock_(clock) {}
  bool write(std::span<const std::uint8_t>) noexcept override { return true; }
  std::ptrdiff_t read(std::span<std::uint8_t>, Time) noexcept override {
    clock_.advance(1ms);
    ++reads;
    return 0;
  }
  int reads = 0;

 private:
  SimClock& clock_;
};
}  // namespace

TEST_CASE("bytes a stalled carrier owes are counted lost once its time limit passes", "[board][serial]") {
  SimClock sim;
  SimClock carrier_clock;
  DeadCarrier dead(carrier_clock);
  SerialLine line(sim);
  line.carry_over(dead, dead, carrier_clock, 20ms);
  const std::array<std::uint8_t, 5> bytes{1, 2, 3, 4, 5};
  REQUIRE(line.host().write(bytes));
  sim.advance(line.byte_time() * 5);
  std::array<std::uint8_t, 16> out{};
  CHECK(line.board().read(out, sim.now()) == 0);
  CHECK(line.board().bytes_lost() == 5);
  CHECK(dead.reads >= 20);
  CHECK(dead.reads <= 21);
  // The line goes on: nothing is owed any more, later bytes are waited for afresh.
  CHECK(line.board().read(out, sim.now()) == 0);
  CHECK(line.board().bytes_lost() == 5);
}
