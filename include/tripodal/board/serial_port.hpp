// The serial transport of the control-board link (seed 001, section 3.3.1: UART, 115200 bit/s,
// 8N1): a POSIX tty in raw mode read against deadlines of an injected clock, so the control loop
// never waits on the port longer than it allows (1 ms at most per read). Also the pseudo-terminal
// pair that lets the simulated board stand in for the real one (tests, tripodal-board-sim).
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>
#include <string>
#include <string_view>

#include "tripodal/core/clock.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal::board {

/// What ByteStream::check says when the settings cannot be read at all: the device is gone, was
/// closed under its owner, or is not a tty.
inline constexpr std::string_view kDeviceGone = "tcgetattr failed: the device is gone or not a tty";
/// What ByteStream::check says of a TCP connection (tcp_stream.hpp) the peer closed or reset.
inline constexpr std::string_view kConnectionGone = "the TCP connection is closed";

/// A byte pipe to the other end of the link: the serial port, or an in-memory line in simulation.
/// One thread reads, one writes (may be the same).
class ByteStream {
 public:
  virtual ~ByteStream() = default;
  /// Queues all of `bytes` for sending; false when the stream failed or could not take them all.
  virtual bool write(std::span<const std::uint8_t> bytes) noexcept = 0;
  /// Reads what has arrived into `out`, waiting for a first byte until `deadline` at most; returns
  /// the bytes read (0: none by the deadline) or -1 when the stream failed (closed, I/O error).
  virtual std::ptrdiff_t read(std::span<std::uint8_t> out, Time deadline) noexcept = 0;
  /// After a failure (-1 from read, false from write): opens the device again, as when a board
  /// was unplugged or its process restarted. False when it cannot, or the stream has no device.
  virtual bool reopen() noexcept { return false; }
  /// Reads the device's settings back and compares them with those it was opened with (another
  /// process may have run `stty icanon echo` on the line, or the device gone): empty while they
  /// match, else what differs, named as stty names it ("icanon on, expected off"), or kDeviceGone.
  /// A static string; no allocation.
  [[nodiscard]] virtual std::string_view check() noexcept { return {}; }
};

/// The longest a read waits, whatever its deadline: the control loop's budget on the port.
inline constexpr Duration kMaxReadWait = std::chrono::milliseconds(1);
/// How long a read with `deadline` waits at `now`: deadline - now, within [0, kMaxReadWait].
[[nodiscard]] Duration read_wait(Time now, Time deadline) noexcept;
/// Waits until `fd` has bytes to read, at most `max_wait` (ppoll: the wake-up is the bytes'
/// arrival, not a timer's tick). True when it has; false on timeout, a signal, or a descriptor
/// that failed or hung up (the caller's read finds out which). Does not read.
[[nodiscard]] bool wait_readable(int fd, Duration max_wait) noexcept;

/// Line settings; the thesis's are the defaults.
struct SerialSettings {
  std::uint32_t baud = 115200;  ///< one of the standard rates 9600..921600
};

/// A tty opened exclusively (TIOCEXCL: another process's open fails with EBUSY, unless it has
/// CAP_SYS_ADMIN) and raw: 8 data bits, no parity, 1 stop bit, no flow control, no echo, no line
/// editing, no character translation; non-blocking, reads bounded by read_wait. The settings are
/// read back after every (re)open and verified; check() verifies them again while running.
class SerialPort final : public ByteStream {
 public:
  /// Opens and configures `path`. Throws std::runtime_error naming the path, the step that failed
  /// and the OS error ("serial port /dev/ttyS9: open: No such file or directory", "...: open:
  /// Device or resource busy (another process holds the port exclusively)"), an unsupported baud
  /// rate ("baud 1234 is not supported; expected one of 9600, ..."), or a setting the device did
  /// not take ("settings read back differ: crtscts on, expected off").
  SerialPort(const std::filesystem::path& path, const Clock& clock, SerialSettings settings = {});
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  bool write(std::span<const std::uint8_t> bytes) noexcept override;
  std::ptrdiff_t read(std::span<std::uint8_t> out, Time deadline) noexcept override;
  /// Closes the port and opens `path` again (a symbolic link may now name another device), with
  /// the settings applied and verified as by the constructor. False when it cannot (the reason:
  /// last_reopen_error()).
  bool reopen() noexcept override;
  [[nodiscard]] std::string_view check() noexcept override;
  /// Why the latest reopen failed (empty after a success).
  [[nodiscard]] const std::string& last_reopen_error() const noexcept { return reopen_error_; }

  /// Asserts or releases the DTR modem line (TIOCMBIS / TIOCMBIC): what switches the RPLIDAR A1's
  /// motor on its USB adapter. False when the device has no modem lines (a pseudo-terminal).
  bool set_dtr(bool asserted) noexcept;

  [[nodiscard]] const std::filesystem::path& path() const noexcept { return path_; }
  [[nodiscard]] int fd() const noexcept { return fd_; }
  /// Bytes written and read so far.
  [[nodiscard]] std::uint64_t bytes_written() const noexcept { return written_; }
  [[nodiscard]] std::uint64_t bytes_read() const noexcept { return read_; }

 private:
  // Opens and configures path_ (throws as the constructor says).
  [[nodiscard]] int open_port() const;
  std::filesystem::path path_;
  const Clock& clock_;
  SerialSettings settings_;
  int fd_ = -1;
  std::uint64_t written_ = 0;
  std::uint64_t read_ = 0;
  std::string reopen_error_;
};

/// Configures an open tty raw 8N1 at `baud` (what SerialPort does; the pseudo-terminal's master
/// side uses it too), then reads the settings back and verifies them. Throws std::runtime_error
/// with `what` and the OS error, or the first setting that did not take.
void configure_raw(int fd, std::uint32_t baud, const std::string& what);

/// Reads a tty's settings (tcgetattr) and compares them with what configure_raw sets: empty when
/// they match, else the first that differs, named as stty does ("icanon on, expected off",
/// "ispeed differs from the configured baud"), or kDeviceGone when they cannot be read.
/// A static string; noexcept and allocation-free, so the control loop may call it.
[[nodiscard]] std::string_view raw_settings_mismatch(int fd, std::uint32_t baud) noexcept;

/// A pseudo-terminal (openpty): the master end, held by the simulated board, and the slave
/// device's path, which the host opens as its SerialPort. Both configured raw at 115200.
class PseudoTerminal final : public ByteStream {
 public:
  /// Throws std::runtime_error when no pseudo-terminal can be allocated.
  explicit PseudoTerminal(const Clock& clock, SerialSettings settings = {});
  ~PseudoTerminal() override;
  PseudoTerminal(const PseudoTerminal&) = delete;
  PseudoTerminal& operator=(const PseudoTerminal&) = delete;

  /// The slave device ("/dev/pts/7").
  [[nodiscard]] const std::filesystem::path& slave_path() const noexcept { return slave_path_; }
  [[nodiscard]] int master_fd() const noexcept { return master_; }

  /// The master side: what the slave's opener writes arrives here, and the reverse.
  bool write(std::span<const std::uint8_t> bytes) noexcept override;
  std::ptrdiff_t read(std::span<std::uint8_t> out, Time deadline) noexcept override;

 private:
  const Clock& clock_;
  int master_ = -1;
  int slave_ = -1;  // kept open so the master never sees a hang-up while the host reopens
  std::filesystem::path slave_path_;
};

}  // namespace tripodal::board
