#include "tripodal/board/serial_port.hpp"

#include <fcntl.h>
#include <poll.h>
#include <pty.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace tripodal::board {
namespace {

struct BaudRate {
  std::uint32_t baud;
  speed_t speed;
};
constexpr std::array<BaudRate, 8> kBaudRates{{{9600, B9600},
                                               {19200, B19200},
                                               {38400, B38400},
                                               {57600, B57600},
                                               {115200, B115200},
                                               {230400, B230400},
                                               {460800, B460800},
                                               {921600, B921600}}};

const BaudRate* find_rate(std::uint32_t baud) noexcept {
  const auto rate = std::find_if(kBaudRates.begin(), kBaudRates.end(), [&](const BaudRate& r) { return r.baud == baud; });
  return rate == kBaudRates.end() ? nullptr : &*rate;
}

// One flag of the raw settings: where it lives, whether configure_raw sets or clears it, and the
// message when it is found otherwise (stty's name for it).
enum class Field { input, output, control, local };
struct FlagRule {
  Field field;
  tcflag_t mask;
  bool on;
  std::string_view mismatch;
};
constexpr std::array<FlagRule, 22> kRawRules{{
    {Field::local, ICANON, false, "icanon on, expected off"},
    {Field::local, ECHO, false, "echo on, expected off"},
    {Field::local, ECHONL, false, "echonl on, expected off"},
    {Field::local, ISIG, false, "isig on, expected off"},
    {Field::local, IEXTEN, false, "iexten on, expected off"},
    {Field::input, IGNBRK, false, "ignbrk on, expected off"},
    {Field::input, BRKINT, false, "brkint on, expected off"},
    {Field::input, PARMRK, false, "parmrk on, expected off"},
    {Field::input, ISTRIP, false, "istrip on, expected off"},
    {Field::input, INLCR, false, "inlcr on, expected off"},
    {Field::input, IGNCR, false, "igncr on, expected off"},
    {Field::input, ICRNL, false, "icrnl on, expected off"},
    {Field::input, IXON, false, "ixon on, expected off"},
    {Field::input, IXOFF, false, "ixoff on, expected off"},
    {Field::input, IXANY, false, "ixany on, expected off"},
    {Field::output, OPOST, false, "opost on, expected off"},
    {Field::control, PARENB, false, "parenb on, expected off (no parity)"},
    {Field::control, CSTOPB, false, "cstopb on, expected off (one stop bit)"},
    {Field::control, CRTSCTS, false, "crtscts on, expected off (no flow control)"},
    {Field::control, CREAD, true, "cread off, expected on"},
    {Field::control, CLOCAL, true, "clocal off, expected on"},
    {Field::control, CSIZE, true, "cs8 off, expected 8 data bits"},  // checked as CS8 below
}};

std::string_view mismatch_of(const termios& t, const BaudRate& rate) noexcept {
  for (const FlagRule& r : kRawRules) {
    const tcflag_t flags = r.field == Field::input    ? t.c_iflag
                           : r.field == Field::output ? t.c_oflag
                           : r.field == Field::control ? t.c_cflag
                                                       : t.c_lflag;
    const bool ok = r.mask == CSIZE ? (flags & CSIZE) == CS8 : ((flags & r.mask) != 0) == r.on;
    if (!ok) return r.mismatch;
  }
  if (t.c_cc[VMIN] != 0) return "min not 0 (reads would block)";
  if (t.c_cc[VTIME] != 0) return "time not 0 (reads would wait)";
  if (::cfgetispeed(&t) != rate.speed) return "ispeed differs from the configured baud";
  if (::cfgetospeed(&t) != rate.speed) return "ospeed differs from the configured baud";
  return {};
}

[[noreturn]] void fail_os(const std::string& what, const char* step) {
  throw std::runtime_error(fmt::format("{}: {}: {}", what, step, std::strerror(errno)));
}

// One bounded wait for input, then one non-blocking read. Without a wait (the control loops and
// the firmware take what has arrived, every cycle) the read comes first: when bytes are there it
// is the only system call (the ppoll before it was a second one on the round trip's path). An
// empty read is ambiguous (with VMIN = VTIME = 0 a tty reads 0 bytes both when nothing has
// arrived and when the other end hung up), so the poll below still decides that case.
std::ptrdiff_t read_fd(int fd, std::span<std::uint8_t> out, Duration wait) noexcept {
  if (fd < 0) return -1;
  if (out.empty()) return 0;
  if (wait <= Duration{0}) {
    const ssize_t n = ::read(fd, out.data(), out.size());
    if (n > 0) return n;
    if (n < 0 && errno != EAGAIN && errno != EINTR) return -1;
  }
  pollfd p{fd, POLLIN, 0};
  const auto ns = wait.count();
  const timespec timeout{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  const int ready = ::ppoll(&p, 1, &timeout, nullptr);
  if (ready < 0) return errno == EINTR ? 0 : -1;
  if (ready == 0) return 0;
  if ((p.revents & POLLIN) == 0) return (p.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0 ? -1 : 0;
  const ssize_t n = ::read(fd, out.data(), out.size());
  if (n < 0) return (errno == EAGAIN || errno == EINTR) ? 0 : -1;
  // Readable but nothing read: end of file, the other end hung up.
  if (n == 0) return -1;
  return n;
}

// Writes everything, waiting for room at most kMaxReadWait at a time (a UART's output queue
// drains at the line rate; a full queue for longer than that is a stuck line).
bool write_fd(int fd, std::span<const std::uint8_t> bytes) noexcept {
  if (fd < 0) return false;
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n > 0) {
      bytes = bytes.subspan(static_cast<std::size_t>(n));
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && errno != EAGAIN) return false;
    pollfd p{fd, POLLOUT, 0};
    const timespec timeout{0, static_cast<long>(kMaxReadWait.count())};
    if (::ppoll(&p, 1, &timeout, nullptr) <= 0) return false;
  }
  return true;
}

}  // namespace

Duration read_wait(Time now, Time deadline) noexcept {
  return std::clamp(deadline - now, Duration{0}, kMaxReadWait);
}

bool wait_readable(int fd, Duration max_wait) noexcept {
  if (fd < 0) return false;
  pollfd p{fd, POLLIN, 0};
  const auto ns = std::max(max_wait, Duration{0}).count();
  const timespec timeout{static_cast<time_t>(ns / 1'000'000'000), static_cast<long>(ns % 1'000'000'000)};
  return ::ppoll(&p, 1, &timeout, nullptr) > 0 && (p.revents & POLLIN) != 0;
}

std::string_view raw_settings_mismatch(int fd, std::uint32_t baud) noexcept {
  const BaudRate* rate = find_rate(baud);
  if (rate == nullptr) return "baud not supported";
  termios t{};
  if (::tcgetattr(fd, &t) != 0) return kDeviceGone;
  return mismatch_of(t, *rate);
}

void configure_raw(int fd, std::uint32_t baud, const std::string& what) {
  const BaudRate* rate = find_rate(baud);
  if (rate == nullptr) {
    throw std::runtime_error(fmt::format("{}: baud {} is not supported; expected one of 9600, 19200, 38400, 57600, "
                                         "115200, 230400, 460800, 921600",
                                         what, baud));
  }
  termios t{};
  if (::tcgetattr(fd, &t) != 0) fail_os(what, "tcgetattr");
  ::cfmakeraw(&t);  // no echo, no line editing, no signals, no translation, 8 bits
  t.c_cflag &= ~static_cast<tcflag_t>(PARENB | CSTOPB | CSIZE | CRTSCTS);
  t.c_cflag |= CS8 | CLOCAL | CREAD;
  t.c_iflag &= ~static_cast<tcflag_t>(IXON | IXOFF | IXANY);
  t.c_cc[VMIN] = 0;  // reads never block: the waiting is ppoll's, bounded
  t.c_cc[VTIME] = 0;
  if (::cfsetispeed(&t, rate->speed) != 0 || ::cfsetospeed(&t, rate->speed) != 0) fail_os(what, "cfsetspeed");
  if (::tcsetattr(fd, TCSANOW, &t) != 0) fail_os(what, "tcsetattr");
  // tcsetattr succeeds when any one change took: read them back, as a driver may refuse some.
  termios back{};
  if (::tcgetattr(fd, &back) != 0) fail_os(what, "tcgetattr (read back)");
  const std::string_view mismatch = mismatch_of(back, *rate);
  if (!mismatch.empty()) throw std::runtime_error(fmt::format("{}: settings read back differ: {}", what, mismatch));
}

SerialPort::SerialPort(const std::filesystem::path& path, const Clock& clock, SerialSettings settings)
    : path_(path), clock_(clock), settings_(settings), fd_(open_port()) {}

int SerialPort::open_port() const {
  const std::string what = fmt::format("serial port {}", path_.string());
  const int fd = ::open(path_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0 && errno == EBUSY) {
    throw std::runtime_error(fmt::format("{}: open: {} (another process holds the port exclusively)", what, std::strerror(errno)));
  }
  if (fd < 0) fail_os(what, "open");
  try {
    configure_raw(fd, settings_.baud, what);  // first: a file that is no tty fails at tcgetattr
    // Ours alone: a second opener (a terminal program, a stray stty) would share the line and its
    // settings; TIOCEXCL makes its open fail with EBUSY instead (root with CAP_SYS_ADMIN excepted).
    if (::ioctl(fd, TIOCEXCL) != 0) fail_os(what, "ioctl TIOCEXCL");
    ::tcflush(fd, TCIOFLUSH);  // nothing of a previous session
  } catch (...) {
    ::close(fd);
    throw;
  }
  return fd;
}

namespace {
// The exclusive flag belongs to the tty, not to our descriptor: it outlives a close while anyone
// else holds the device (the pseudo-terminal's keeper), so clear it or our own reopen is refused.
void close_port(int fd) noexcept {
  if (fd < 0) return;
  (void)::ioctl(fd, TIOCNXCL);
  ::close(fd);
}
}  // namespace

bool SerialPort::reopen() noexcept {
  close_port(fd_);
  fd_ = -1;
  try {
    fd_ = open_port();
    reopen_error_.clear();
  } catch (const std::exception& e) {
    try {
      reopen_error_ = e.what();
    } catch (...) {
      reopen_error_.clear();
    }
    return false;  // not back yet: the caller tries again later
  }
  return true;
}

std::string_view SerialPort::check() noexcept {
  if (fd_ < 0) return kDeviceGone;
  return raw_settings_mismatch(fd_, settings_.baud);
}

SerialPort::~SerialPort() { close_port(fd_); }

bool SerialPort::set_dtr(bool asserted) noexcept {
  if (fd_ < 0) return false;
  const int bits = TIOCM_DTR;
  return ::ioctl(fd_, asserted ? TIOCMBIS : TIOCMBIC, &bits) == 0;
}

bool SerialPort::write(std::span<const std::uint8_t> bytes) noexcept {
  const bool ok = write_fd(fd_, bytes);
  if (ok) written_ += bytes.size();
  return ok;
}

std::ptrdiff_t SerialPort::read(std::span<std::uint8_t> out, Time deadline) noexcept {
  const std::ptrdiff_t n = read_fd(fd_, out, read_wait(clock_.now(), deadline));
  if (n > 0) read_ += static_cast<std::uint64_t>(n);
  return n;
}

PseudoTerminal::PseudoTerminal(const Clock& clock, SerialSettings settings) : clock_(clock) {
  std::array<char, 256> name{};
  if (::openpty(&master_, &slave_, name.data(), nullptr, nullptr) != 0) fail_os("pseudo-terminal", "openpty");
  slave_path_ = name.data();
  try {
    const std::string what = fmt::format("pseudo-terminal {}", slave_path_.string());
    configure_raw(slave_, settings.baud, what);
    configure_raw(master_, settings.baud, what);
    const int flags = ::fcntl(master_, F_GETFL);
    if (flags < 0 || ::fcntl(master_, F_SETFL, flags | O_NONBLOCK) != 0) fail_os(what, "fcntl");
    ::fcntl(master_, F_SETFD, FD_CLOEXEC);
    ::fcntl(slave_, F_SETFD, FD_CLOEXEC);
  } catch (...) {
    ::close(master_);
    ::close(slave_);
    throw;
  }
}

PseudoTerminal::~PseudoTerminal() {
  if (master_ >= 0) ::close(master_);
  if (slave_ >= 0) ::close(slave_);
}

bool PseudoTerminal::write(std::span<const std::uint8_t> bytes) noexcept { return write_fd(master_, bytes); }

std::ptrdiff_t PseudoTerminal::read(std::span<std::uint8_t> out, Time deadline) noexcept {
  return read_fd(master_, out, read_wait(clock_.now(), deadline));
}

}  // namespace tripodal::board
