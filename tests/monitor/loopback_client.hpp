// A blocking loopback client for the monitor's tests: enough HTTP and WebSocket to talk to the
// server (tests/monitor only; waits are bounded, never measured).
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <cstdint>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "tripodal_monitor_internal/wire.hpp"

namespace tripodal::monitor::test {

// A blocking loopback client: enough to speak HTTP and WebSocket to the server in a test.
class Client {
 public:
  explicit Client(std::uint16_t port, int receive_buffer_bytes = 0) {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    if (receive_buffer_bytes > 0) ::setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &receive_buffer_bytes, sizeof receive_buffer_bytes);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    REQUIRE(::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
  }
  ~Client() { ::close(fd_); }
  Client(const Client&) = delete;
  Client& operator=(const Client&) = delete;
  void send(const std::string& s) const { REQUIRE(::send(fd_, s.data(), s.size(), MSG_NOSIGNAL) == static_cast<ssize_t>(s.size())); }
  // Reads until `done` holds for what arrived, the peer closes, or 10 s pass (a hang, not a measure).
  template <class Done>
  std::string read_until(Done done, std::chrono::milliseconds patience = std::chrono::seconds(10)) {
    const auto give_up = std::chrono::steady_clock::now() + patience;
    while (!done(buf_) && std::chrono::steady_clock::now() < give_up) {
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, 100) <= 0) continue;
      char b[65536];
      const ssize_t n = ::recv(fd_, b, sizeof b, 0);
      if (n <= 0) {
        closed_ = true;
        break;
      }
      buf_.append(b, static_cast<std::size_t>(n));
    }
    return buf_;
  }
  std::string read_all() {
    return read_until([](const std::string&) { return false; });
  }
  void consume(std::size_t n) { buf_.erase(0, n); }
  int fd() const { return fd_; }
  /// Whether the server closed the connection (seen by a read).
  bool closed() const { return closed_; }

 private:
  int fd_ = -1;
  bool closed_ = false;
  std::string buf_;
};

inline std::string ws_upgrade(const std::string& path, const std::string& protocol = {}) {
  std::string r = "GET " + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                  "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n";
  if (!protocol.empty()) r += "Sec-WebSocket-Protocol: " + protocol + "\r\n";
  return r + "\r\n";
}

// Server frames (unmasked) in `bytes` after the handshake.
inline std::vector<WsFrame> server_frames(std::string_view bytes) {
  std::vector<WsFrame> out;
  while (bytes.size() >= 2) {
    std::uint64_t n = static_cast<std::uint8_t>(bytes[1]) & 0x7FU;
    std::size_t pos = 2;
    if (n == 126) {
      n = (std::uint64_t{static_cast<std::uint8_t>(bytes[2])} << 8) | static_cast<std::uint8_t>(bytes[3]);
      pos = 4;
    } else if (n == 127) {
      n = 0;
      for (std::size_t i = 2; i < 10; ++i) n = (n << 8) | static_cast<std::uint8_t>(bytes[i]);
      pos = 10;
    }
    if (bytes.size() < pos + n) break;
    out.push_back(WsFrame{static_cast<WsOpcode>(static_cast<std::uint8_t>(bytes[0]) & 0x0FU), true, std::string(bytes.substr(pos, n))});
    bytes.remove_prefix(pos + n);
  }
  return out;
}

template <class Pred>
bool wait_for(Pred p) {
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (!p()) {
    if (std::chrono::steady_clock::now() > give_up) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  return true;
}

}  // namespace tripodal::monitor::test
