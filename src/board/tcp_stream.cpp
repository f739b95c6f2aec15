#include "tripodal/board/tcp_stream.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fmt/format.h>

namespace tripodal::board {
namespace {

[[noreturn]] void fail(const std::string& what, const char* step) {
  throw std::runtime_error(fmt::format("{}: {}: {}", what, step, std::strerror(errno)));
}

void set_nonblocking(int fd) noexcept {
  const int flags = ::fcntl(fd, F_GETFL);
  if (flags >= 0) ::fcntl(fd, F_SETFL, flags | O_NONBLOCK);
  ::fcntl(fd, F_SETFD, FD_CLOEXEC);
  const int one = 1;
  ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
}

// All of `bytes`, or false: a frame is never left half sent (short frames: the socket buffer takes
// them whole unless the peer stopped reading for long).
bool send_all(int fd, std::span<const std::uint8_t> bytes) noexcept {
  std::size_t sent = 0;
  int stalls = 0;
  while (sent < bytes.size()) {
    const ssize_t n = ::send(fd, bytes.data() + sent, bytes.size() - sent, MSG_NOSIGNAL);
    if (n > 0) {
      sent += static_cast<std::size_t>(n);
      continue;
    }
    if (n < 0 && errno == EINTR) continue;
    if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) && ++stalls < 3) {
      pollfd p{fd, POLLOUT, 0};
      (void)::poll(&p, 1, 1);
      continue;
    }
    return false;
  }
  return true;
}

// What arrived within `wait`: > 0 bytes, 0 none, -1 closed or failed.
std::ptrdiff_t recv_some(int fd, std::span<std::uint8_t> out, Duration wait) noexcept {
  if (fd < 0) return -1;
  pollfd p{fd, POLLIN, 0};
  const int ms = static_cast<int>(std::chrono::ceil<std::chrono::milliseconds>(wait).count());
  const int r = ::poll(&p, 1, ms);
  if (r < 0) return errno == EINTR ? 0 : -1;
  if (r == 0) return 0;
  const ssize_t n = ::recv(fd, out.data(), out.size(), 0);
  if (n > 0) return n;
  if (n < 0 && (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR)) return 0;
  return -1;  // 0: the peer closed the connection
}

}  // namespace

bool is_tcp_port(std::string_view spec) noexcept { return spec.substr(0, 6) == "tcp://"; }

TcpStream::TcpStream(const std::string& spec, const Clock& clock) : spec_(spec), clock_(clock) {
  const std::string rest = is_tcp_port(spec) ? spec.substr(6) : std::string();
  const std::size_t colon = rest.rfind(':');
  unsigned long port = 0;
  bool ok = colon != std::string::npos && colon > 0 && colon + 1 < rest.size();
  if (ok) {
    std::size_t used = 0;
    try {
      port = std::stoul(rest.substr(colon + 1), &used, 10);
    } catch (const std::exception&) {
      ok = false;
    }
    ok = ok && used == rest.size() - colon - 1 && port >= 1 && port <= 65535;
  }
  if (!ok) throw std::runtime_error(fmt::format("{}: expected tcp://HOST:PORT with PORT 1 to 65535", spec));
  host_ = rest.substr(0, colon);
  port_ = static_cast<std::uint16_t>(port);
  fd_ = connect_once();
}

TcpStream::~TcpStream() {
  if (fd_ >= 0) ::close(fd_);
}

int TcpStream::connect_once() const {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  addrinfo* found = nullptr;
  const std::string service = std::to_string(port_);
  if (const int e = ::getaddrinfo(host_.c_str(), service.c_str(), &hints, &found); e != 0) {
    throw std::runtime_error(fmt::format("{}: resolve: {}", spec_, ::gai_strerror(e)));
  }
  int fd = -1;
  int error = 0;
  for (addrinfo* a = found; a != nullptr && fd < 0; a = a->ai_next) {
    fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) continue;
    // A blocking connect: the board's module is on the local network (loopback in tests).
    if (::connect(fd, a->ai_addr, a->ai_addrlen) != 0) {
      error = errno;
      ::close(fd);
      fd = -1;
    }
  }
  ::freeaddrinfo(found);
  if (fd < 0) {
    errno = error;
    fail(spec_, "connect");
  }
  set_nonblocking(fd);
  return fd;
}

bool TcpStream::write(std::span<const std::uint8_t> bytes) noexcept { return fd_ >= 0 && send_all(fd_, bytes); }

std::ptrdiff_t TcpStream::read(std::span<std::uint8_t> out, Time deadline) noexcept {
  const std::ptrdiff_t n = recv_some(fd_, out, read_wait(clock_.now(), deadline));
  if (n < 0 && fd_ >= 0) {
    ::close(fd_);
    fd_ = -1;
  }
  return n;
}

bool TcpStream::reopen() noexcept {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
  try {
    fd_ = connect_once();
    reopen_error_.clear();
    return true;
  } catch (const std::exception& e) {
    reopen_error_ = e.what();
    return false;
  }
}

std::string_view TcpStream::check() noexcept {
  if (fd_ < 0) return kConnectionGone;
  pollfd p{fd_, POLLRDHUP, 0};
  if (::poll(&p, 1, 0) > 0 && (p.revents & (POLLRDHUP | POLLHUP | POLLERR)) != 0) return kConnectionGone;
  return {};
}

TcpServerStream::TcpServerStream(const Clock& clock, std::uint16_t port) : clock_(clock) {
  listener_ = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
  if (listener_ < 0) fail("tcp board end", "socket");
  const int one = 1;
  ::setsockopt(listener_, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = htons(port);
  socklen_t len = sizeof a;
  if (::bind(listener_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0 || ::listen(listener_, 1) != 0 ||
      ::getsockname(listener_, reinterpret_cast<sockaddr*>(&a), &len) != 0) {
    const int e = errno;
    ::close(listener_);
    errno = e;
    fail(fmt::format("tcp board end 127.0.0.1:{}", port), "listen");
  }
  port_ = ntohs(a.sin_port);
}

TcpServerStream::~TcpServerStream() {
  drop();
  if (listener_ >= 0) ::close(listener_);
}

std::string TcpServerStream::spec() const { return fmt::format("tcp://127.0.0.1:{}", port_); }

void TcpServerStream::drop() noexcept {
  if (conn_ >= 0) ::close(conn_);
  conn_ = -1;
}

void TcpServerStream::accept_pending() noexcept {
  if (conn_ >= 0) return;
  const int fd = ::accept4(listener_, nullptr, nullptr, SOCK_CLOEXEC);
  if (fd < 0) return;
  set_nonblocking(fd);
  conn_ = fd;
  ++connections_;
}

bool TcpServerStream::write(std::span<const std::uint8_t> bytes) noexcept {
  accept_pending();
  return conn_ >= 0 && send_all(conn_, bytes);
}

std::ptrdiff_t TcpServerStream::read(std::span<std::uint8_t> out, Time deadline) noexcept {
  accept_pending();
  if (conn_ < 0) return 0;
  const std::ptrdiff_t n = recv_some(conn_, out, read_wait(clock_.now(), deadline));
  if (n < 0) {
    drop();  // the host went away: wait for the next connection
    return 0;
  }
  return n;
}

}  // namespace tripodal::board
