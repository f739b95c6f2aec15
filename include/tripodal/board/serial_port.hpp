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

#include "tripodal/core/clock.hpp"
#include "tripodal/core/time.hpp"

namespace tripodal::board {

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
};

/// The longest a read waits, whatever its deadline: the control loop's budget on the port.
inline constexpr Duration kMaxReadWait = std::chrono::milliseconds(1);
/// How long a read with `deadline` waits at `now`: deadline - now, within [0, kMaxReadWait].
[[nodiscard]] Duration read_wait(Time now, Time deadline) noexcept;

/// Line settings; the thesis's are the defaults.
struct SerialSettings {
  std::uint32_t baud = 115200;  ///< one of the standard rates 9600..921600
};

/// A tty opened raw: 8 data bits, no parity, 1 stop bit, no flow control, no echo, no line
/// editing, no character translation; non-blocking, reads bounded by read_wait.
class SerialPort final : public ByteStream {
 public:
  /// Opens and configures `path`. Throws std::runtime_error naming the path, the step that failed
  /// and the OS error ("serial port /dev/ttyS9: open: No such file or directory"), or an
  /// unsupported baud rate ("baud 1234 is not supported; expected one of 9600, ...").
  SerialPort(const std::filesystem::path& path, const Clock& clock, SerialSettings settings = {});
  ~SerialPort() override;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  bool write(std::span<const std::uint8_t> bytes) noexcept override;
  std::ptrdiff_t read(std::span<std::uint8_t> out, Time deadline) noexcept override;
  /// Closes the port and opens `path` again (a symbolic link may now name another device).
  bool reopen() noexcept override;

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
};

/// Configures an open tty raw 8N1 at `baud` (what SerialPort does; the pseudo-terminal's master
/// side uses it too). Throws std::runtime_error with `what` and the OS error.
void configure_raw(int fd, std::uint32_t baud, const std::string& what);

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
