// The control board's backup transport (seed 001, sections 2.2 and 3.1: the ESP8266 Wi-Fi module
// wired to the MCU, "a backup communication channel"): the protocol's frames over a TCP byte
// stream instead of the UART. TcpStream is the host's end (a port spec `tcp://HOST:PORT` beside a
// tty path), reconnected by the link like a reopened tty; TcpServerStream is the board's end (the
// module listening), for the simulated board and the tests, on loopback.
#pragma once

#include <cstdint>
#include <string>
#include <string_view>

#include "tripodal/board/serial_port.hpp"
#include "tripodal/core/clock.hpp"

namespace tripodal::board {

/// Whether a port spec names the TCP transport ("tcp://HOST:PORT").
[[nodiscard]] bool is_tcp_port(std::string_view spec) noexcept;

/// The host's end: connects to `tcp://HOST:PORT` (TCP_NODELAY: a frame leaves at once), reads
/// bounded by read_wait like the serial port. A closed connection makes read return -1; reopen()
/// connects again.
class TcpStream final : public ByteStream {
 public:
  /// Throws std::runtime_error naming the spec and what failed ("tcp://127.0.0.1:1: connect:
  /// Connection refused", "...: expected tcp://HOST:PORT with PORT 1 to 65535").
  TcpStream(const std::string& spec, const Clock& clock);
  ~TcpStream() override;
  TcpStream(const TcpStream&) = delete;
  TcpStream& operator=(const TcpStream&) = delete;

  bool write(std::span<const std::uint8_t> bytes) noexcept override;
  std::ptrdiff_t read(std::span<std::uint8_t> out, Time deadline) noexcept override;
  /// Closes and connects again; false when the board does not accept (why: last_reopen_error()).
  bool reopen() noexcept override;
  /// Empty while connected, kConnectionGone after the peer closed it.
  [[nodiscard]] std::string_view check() noexcept override;
  [[nodiscard]] const std::string& last_reopen_error() const noexcept { return reopen_error_; }

 private:
  [[nodiscard]] int connect_once() const;  // throws as the constructor says
  std::string spec_;
  std::string host_;
  std::uint16_t port_ = 0;
  const Clock& clock_;
  int fd_ = -1;
  std::string reopen_error_;
};

/// The board's end: listens on 127.0.0.1 (port 0: one the kernel picks, see port()) and serves
/// one connection at a time, taking the next when the host reconnects. Until a host connects,
/// reads return 0 and writes are lost (false), as on an unplugged line.
class TcpServerStream final : public ByteStream {
 public:
  /// Throws std::runtime_error when it cannot listen.
  TcpServerStream(const Clock& clock, std::uint16_t port = 0);
  ~TcpServerStream() override;
  TcpServerStream(const TcpServerStream&) = delete;
  TcpServerStream& operator=(const TcpServerStream&) = delete;

  bool write(std::span<const std::uint8_t> bytes) noexcept override;
  std::ptrdiff_t read(std::span<std::uint8_t> out, Time deadline) noexcept override;
  [[nodiscard]] std::uint16_t port() const noexcept { return port_; }
  /// "tcp://127.0.0.1:PORT": the host's port spec.
  [[nodiscard]] std::string spec() const;
  [[nodiscard]] bool connected() const noexcept { return conn_ >= 0; }
  /// Drops the current connection (the module reset): the host sees it closed.
  void drop() noexcept;
  [[nodiscard]] std::uint64_t connections() const noexcept { return connections_; }

 private:
  void accept_pending() noexcept;
  const Clock& clock_;
  int listener_ = -1;
  int conn_ = -1;
  std::uint16_t port_ = 0;
  std::uint64_t connections_ = 0;
};

}  // namespace tripodal::board
