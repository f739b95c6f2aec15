#include "tripodal/monitor/monitor_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <fstream>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <stdexcept>
#include <thread>

#include "wire.hpp"

namespace tripodal::monitor {
namespace {

using SteadyTime = std::chrono::steady_clock::time_point;

constexpr std::string_view kFoxglove = "foxglove.websocket.v1";
constexpr std::size_t kMaxClientFrame = std::size_t{64} * 1024;
constexpr std::size_t kMaxOutbox = 4096;  // messages published but not yet taken by the server thread

std::string random_token() {
  std::random_device rd;
  std::string out;
  static constexpr char kHex[] = "0123456789abcdef";
  for (int i = 0; i < 8; ++i) {
    const unsigned v = rd();
    for (int k = 0; k < 4; ++k) out += kHex[(v >> (4 * k)) & 0xFU];
  }
  return out;
}

// Messages may quote what a client sent (a request line, a header): bytes that are not UTF-8 are
// replaced rather than thrown on.
std::string error_json(std::string_view message) {
  return nlohmann::json{{"error", message}}.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

void append_le(std::string& out, std::uint64_t v, int bytes) {
  for (int i = 0; i < bytes; ++i) out += static_cast<char>((v >> (8 * i)) & 0xFFU);
}

struct Channel {
  std::uint32_t id = 0;
  std::string topic, schema_name, schema;
  Delivery delivery = Delivery::bulk;
  std::string latest_json;  // state: the latest message, for clients that join
  double latest_stamp_s = 0.0;
  bool has_latest = false;
};

struct Message {
  std::uint32_t channel = 0;
  double stamp_s = 0.0;
  std::string json;
};

struct OutFrame {
  std::string bytes;
  bool bulk = false;
};

enum class Kind { http, page, foxglove };

// Which budget a connection counts against (docs/monitor.md, "Budgets"): one that has not shown the
// token may not take the place of one that has.
enum class Pool { unauthenticated, authenticated, reader };

struct Connection {
  int fd = -1;
  Kind kind = Kind::http;
  Pool pool = Pool::unauthenticated;
  SteadyTime accepted{};
  SteadyTime deadline = SteadyTime::max();  // closed then (unauthenticated, or an answer unread)
  std::string in;
  std::deque<OutFrame> out;
  std::size_t out_offset = 0;  // bytes of out.front() already sent
  std::size_t event_bytes = 0; // queued bytes that may not be dropped
  std::size_t bulk_frames = 0;
  bool close_after_write = false;
  bool dead = false;
  std::uint64_t waiting_for = 0;  // an operator request this HTTP connection waits on
  std::map<std::uint32_t, std::uint32_t> subscriptions;  // foxglove: channel id -> subscription id
};

}  // namespace

struct MonitorServer::Impl {
  MonitorServerOptions options;
  std::string page{embedded_page()};
  int listen_fd = -1;
  int wake_fd = -1;
  std::uint16_t port = 0;
  std::vector<Channel> channels;
  std::string session_id = random_token().substr(0, 16);  // Foxglove's sessionId: nothing of the token
  std::thread thread;
  std::atomic<bool> running{false};

  // Shared with the publishing threads.
  mutable std::mutex mutex;
  std::vector<Message> outbox;
  std::vector<OperatorRequest> requests;
  std::vector<std::pair<std::uint64_t, std::string>> answers;  // id -> complete HTTP response
  MonitorStats stats;

  // The server thread's own.
  std::vector<std::unique_ptr<Connection>> connections;
  std::deque<Message> history;
  std::size_t history_bytes = 0;  // as framed for a page client (what a joining client is sent)
  std::uint64_t next_request = 1;
  std::map<std::uint64_t, SteadyTime> pending;  // requests handed to the robot, by id

  void wake() const noexcept {
    const std::uint64_t one = 1;
    [[maybe_unused]] const auto n = ::write(wake_fd, &one, sizeof one);
  }

  void count(std::uint64_t MonitorStats::*field, std::uint64_t n = 1) {
    const std::lock_guard lock(mutex);
    stats.*field += n;
  }

  // --- queues ----------------------------------------------------------------------------------

  void enqueue(Connection& c, std::string bytes, bool bulk) {
    if (c.dead) return;
    if (bulk) {
      if (c.bulk_frames >= options.max_bulk_frames) {
        // Shed the oldest bulk frame not already on the wire.
        for (std::size_t i = c.out_offset > 0 ? 1 : 0; i < c.out.size(); ++i) {
          if (c.out[i].bulk) {
            c.out.erase(c.out.begin() + static_cast<std::ptrdiff_t>(i));
            --c.bulk_frames;
            count(&MonitorStats::bulk_shed);
            break;
          }
        }
      }
      ++c.bulk_frames;
    } else {
      c.event_bytes += bytes.size();
      if (c.event_bytes > options.max_event_bytes) {
        // Events may not be lost: a client that cannot take them is let go instead.
        c.dead = true;
        count(&MonitorStats::slow_disconnects);
        return;
      }
    }
    c.out.push_back(OutFrame{std::move(bytes), bulk});
  }

  std::string page_frame(const Channel& ch, double stamp_s, const std::string& json) const {
    std::string text = R"({"topic":)" + nlohmann::json(ch.topic).dump() + R"(,"t":)" + std::to_string(stamp_s) + R"(,"data":)";
    text += json;
    text += '}';
    return ws_frame(WsOpcode::text, text);
  }

  static std::string foxglove_frame(std::uint32_t subscription, double stamp_s, const std::string& json) {
    std::string payload;
    payload.reserve(json.size() + 13);
    payload += static_cast<char>(0x01);  // messageData
    append_le(payload, subscription, 4);
    append_le(payload, static_cast<std::uint64_t>(stamp_s < 0 ? 0.0 : stamp_s * 1e9), 8);
    payload += json;
    return ws_frame(WsOpcode::binary, payload);
  }

  void deliver(Connection& c, const Channel& ch, double stamp_s, const std::string& json) {
    const bool bulk = ch.delivery == Delivery::bulk;
    if (c.kind == Kind::page) {
      enqueue(c, page_frame(ch, stamp_s, json), bulk);
    } else if (c.kind == Kind::foxglove) {
      const auto it = c.subscriptions.find(ch.id);
      if (it != c.subscriptions.end()) enqueue(c, foxglove_frame(it->second, stamp_s, json), bulk);
    }
  }

  void distribute(std::vector<Message>& batch) {
    for (Message& m : batch) {
      if (m.channel == 0 || m.channel > channels.size()) continue;
      Channel& ch = channels[m.channel - 1];
      for (auto& c : connections) deliver(*c, ch, m.stamp_s, m.json);
      if (ch.delivery == Delivery::state) {
        ch.latest_json = std::move(m.json);
        ch.latest_stamp_s = m.stamp_s;
        ch.has_latest = true;
      } else if (ch.delivery == Delivery::event) {
        keep(ch, std::move(m));
      }
    }
  }

  // The history replayed to clients that join is budgeted in count and in bytes, so that the
  // replay always fits a client's event queue (max_history_bytes <= max_event_bytes / 2).
  void keep(const Channel& ch, Message m) {
    const std::size_t bytes = page_frame(ch, m.stamp_s, m.json).size();
    if (bytes > options.max_history_bytes || options.history == 0) {
      count(&MonitorStats::history_not_kept);
    } else {
      history.push_back(std::move(m));
      history_bytes += bytes;
    }
    while (history.size() > options.history || history_bytes > options.max_history_bytes) {
      const Message& old = history.front();
      history_bytes -= page_frame(channels[old.channel - 1], old.stamp_s, old.json).size();
      history.pop_front();
    }
    const std::lock_guard lock(mutex);
    stats.history_entries = history.size();
    stats.history_bytes = history_bytes;
  }

  // --- the thread --------------------------------------------------------------------------------

  void run() {
    std::vector<pollfd> fds;
    while (running.load(std::memory_order_acquire)) {
      fds.clear();
      fds.push_back({listen_fd, POLLIN, 0});
      fds.push_back({wake_fd, POLLIN, 0});
      for (auto& c : connections) {
        short ev = POLLIN;
        if (!c->out.empty()) ev = static_cast<short>(ev | POLLOUT);
        fds.push_back({c->fd, ev, 0});
      }
      const int n = ::poll(fds.data(), fds.size(), 100);
      if (n < 0 && errno != EINTR) break;
      if ((fds[1].revents & POLLIN) != 0) {
        std::uint64_t v = 0;
        [[maybe_unused]] const auto r = ::read(wake_fd, &v, sizeof v);
      }
      take_outbox();
      for (std::size_t i = 0; i < connections.size(); ++i) {
        Connection& c = *connections[i];
        const short rev = fds[i + 2].revents;
        if ((rev & (POLLERR | POLLHUP | POLLNVAL)) != 0 && (rev & POLLIN) == 0) c.dead = true;
        if (!c.dead && (rev & POLLIN) != 0) read_from(c);
        if (!c.dead && !c.out.empty()) write_to(c);
      }
      if ((fds[0].revents & POLLIN) != 0) accept_clients();
      expire();
      reap();
    }
    for (auto& c : connections) ::close(c->fd);
    connections.clear();
  }

  void take_outbox() {
    std::vector<Message> batch;
    std::vector<std::pair<std::uint64_t, std::string>> done;
    {
      const std::lock_guard lock(mutex);
      batch.swap(outbox);
      done.swap(answers);
    }
    distribute(batch);
    for (auto& [id, response] : done) {
      pending.erase(id);
      for (auto& c : connections) {
        if (c->waiting_for == id) {
          c->waiting_for = 0;
          answer_now(*c, std::move(response));
          break;
        }
      }
    }
  }

  // An answer to an operator's request: the client has header_timeout_s to read it.
  void answer_now(Connection& c, std::string response) {
    enqueue(c, std::move(response), false);
    c.close_after_write = true;
    if (c.pool != Pool::unauthenticated) c.deadline = std::chrono::steady_clock::now() + seconds(options.header_timeout_s);
  }

  static std::chrono::steady_clock::duration seconds(double s) {
    return std::chrono::duration_cast<std::chrono::steady_clock::duration>(std::chrono::duration<double>(s));
  }

  [[nodiscard]] std::size_t in_pool(Pool pool) const noexcept {
    return static_cast<std::size_t>(
        std::count_if(connections.begin(), connections.end(), [pool](const auto& c) { return !c->dead && c->pool == pool; }));
  }

  void accept_clients() {
    // At most half the unauthenticated pool per round: a connection accepted in this round has its
    // request read in the next one before it could be evicted by newer connections.
    const std::size_t per_round = std::max<std::size_t>(1, options.max_unauthenticated / 2);
    for (std::size_t accepted = 0; accepted < per_round; ++accepted) {
      const int fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) return;
      if (in_pool(Pool::unauthenticated) >= options.max_unauthenticated) {
        // Half-open connections (slowloris) must not lock the operator out: the oldest goes.
        Connection* oldest = nullptr;
        for (auto& c : connections) {
          if (!c->dead && c->pool == Pool::unauthenticated && (oldest == nullptr || c->accepted < oldest->accepted)) oldest = c.get();
        }
        if (oldest != nullptr) {
          oldest->dead = true;
          count(&MonitorStats::evicted);
        }
      }
      const int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      // A bounded kernel buffer too, so "queued for this client" means what the options say.
      const int sndbuf = static_cast<int>(options.send_buffer_bytes);
      if (sndbuf > 0) ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf);
      auto c = std::make_unique<Connection>();
      c->fd = fd;
      c->accepted = std::chrono::steady_clock::now();
      c->deadline = c->accepted + seconds(options.header_timeout_s);
      connections.push_back(std::move(c));
    }
  }

  void expire() {
    const auto now = std::chrono::steady_clock::now();
    for (auto& c : connections) {
      if (c->dead || c->kind != Kind::http || now < c->deadline) continue;
      c->dead = true;
      if (c->pool == Pool::unauthenticated) count(&MonitorStats::header_timeouts);
    }
    const auto limit = seconds(options.answer_timeout_s);
    for (auto it = pending.begin(); it != pending.end();) {
      if (now - it->second <= limit) {
        ++it;
        continue;
      }
      for (auto& c : connections) {
        if (c->waiting_for == it->first) {
          c->waiting_for = 0;
          answer_now(*c, http_response(503, "application/json", error_json("the robot did not answer in time")));
        }
      }
      it = pending.erase(it);
    }
  }

  void reap() {
    std::size_t clients = 0;
    std::size_t unauthenticated = 0;
    for (auto it = connections.begin(); it != connections.end();) {
      if ((*it)->dead) {
        ::close((*it)->fd);
        it = connections.erase(it);
      } else {
        clients += (*it)->kind != Kind::http ? 1 : 0;
        unauthenticated += (*it)->pool == Pool::unauthenticated ? 1 : 0;
        ++it;
      }
    }
    const std::lock_guard lock(mutex);
    stats.clients = clients;
    stats.unauthenticated = unauthenticated;
  }

  void write_to(Connection& c) {
    while (!c.out.empty()) {
      const std::string& b = c.out.front().bytes;
      const ssize_t n = ::send(c.fd, b.data() + c.out_offset, b.size() - c.out_offset, MSG_NOSIGNAL | MSG_DONTWAIT);
      if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) c.dead = true;
        return;
      }
      c.out_offset += static_cast<std::size_t>(n);
      {
        const std::lock_guard lock(mutex);
        stats.bytes_sent += static_cast<std::uint64_t>(n);
      }
      if (c.out_offset < b.size()) return;
      if (c.out.front().bulk) --c.bulk_frames;
      else c.event_bytes -= b.size();
      c.out.pop_front();
      c.out_offset = 0;
      count(&MonitorStats::frames_sent);
    }
    if (c.close_after_write) {
      ::shutdown(c.fd, SHUT_WR);
      c.dead = true;
    }
  }

  void read_from(Connection& c) {
    char buf[16384];
    for (;;) {
      const ssize_t n = ::recv(c.fd, buf, sizeof buf, MSG_DONTWAIT);
      if (n == 0) {
        c.dead = true;
        return;
      }
      if (n < 0) {
        if (errno != EAGAIN && errno != EWOULDBLOCK && errno != EINTR) c.dead = true;
        break;
      }
      c.in.append(buf, static_cast<std::size_t>(n));
      if (c.in.size() > options.http.max_header_bytes + options.http.max_body_bytes + kMaxClientFrame) break;
    }
    if (c.kind == Kind::http) handle_http(c);
    else handle_ws(c);
  }

  void refuse(Connection& c, int status, std::string_view message) {
    if (status == 401) count(&MonitorStats::unauthorized);
    if (status == 503) count(&MonitorStats::busy);
    if (status == 421) count(&MonitorStats::refused_host);
    if (status == 403) count(&MonitorStats::refused_origin);
    answer_now(c, http_response(status, "application/json", error_json(message)));
    c.in.clear();
  }

  // The token from a header; commands take it from nothing else, so that a cross-site form or
  // "simple" request cannot carry it (a custom header needs a CORS preflight, never answered).
  [[nodiscard]] bool header_token_ok(const HttpRequest& r) const {
    std::string_view given;
    if (const auto a = r.header("authorization"); a && a->starts_with("Bearer ")) given = a->substr(7);
    else if (const auto t = r.header("x-tripodal-token")) given = *t;
    return !given.empty() && constant_time_equal(given, options.token);
  }

  // Streams and GETs also take it from the address (?token=): a browser's WebSocket cannot send a
  // header. The Origin check keeps other pages from using it.
  [[nodiscard]] bool token_ok(const HttpRequest& r) const {
    if (r.header("authorization") || r.header("x-tripodal-token")) return header_token_ok(r);
    const auto q = r.query("token");
    return q && !q->empty() && constant_time_equal(*q, options.token);
  }

  // Moves `c` into the authenticated or reader pool; false (and 503) when that pool is full.
  bool admit(Connection& c, Pool pool) {
    const std::size_t limit = pool == Pool::authenticated ? options.max_clients : options.max_open_readers;
    if (in_pool(pool) >= limit) {
      refuse(c, 503, pool == Pool::authenticated ? "too many clients" : "too many read-only clients without the token");
      return false;
    }
    c.pool = pool;
    c.deadline = SteadyTime::max();
    return true;
  }

  // Browser-grade checks (docs/monitor.md, "Host and Origin"): a page of another site may make the
  // browser send a request here, with a DNS name rebound to this address or from its own origin.
  [[nodiscard]] std::string_view browser_refusal(const HttpRequest& r, int& status) const {
    const auto host = r.header("host");
    if (host && !host_allowed(*host, options.allowed_hosts)) {
      status = 421;
      return "Host is not this server's name: loopback names and IP addresses are served, other names only when "
             "allowed (MonitorServerOptions::allowed_hosts)";
    }
    if (const auto origin = r.header("origin")) {
      const bool own = host && same_origin(*origin, *host);
      const bool allowed = std::find(options.allowed_origins.begin(), options.allowed_origins.end(), *origin) != options.allowed_origins.end();
      if (!own && !allowed) {
        status = 403;
        return "Origin is not this server's page: streams and commands are served to the monitor's own pages and to "
               "clients that are not browsers";
      }
    }
    return {};
  }

  void handle_http(Connection& c) {
    if (c.waiting_for != 0 || c.close_after_write) {
      c.in.clear();  // one request per connection
      return;
    }
    HttpParse p = parse_http_request(c.in, options.http);
    switch (p.status) {
      case HttpParse::Status::incomplete: return;
      case HttpParse::Status::bad_request: return refuse(c, 400, p.error);
      case HttpParse::Status::headers_too_large:
        return refuse(c, 431, "request line and headers over " + std::to_string(options.http.max_header_bytes) + " bytes");
      case HttpParse::Status::body_too_large:
        return refuse(c, 413, "body over " + std::to_string(options.http.max_body_bytes) + " bytes");
      case HttpParse::Status::complete: break;
    }
    c.in.erase(0, p.consumed);
    const HttpRequest& r = p.request;
    int status = 0;
    if (const std::string_view why = browser_refusal(r, status); !why.empty()) return refuse(c, status, why);
    const auto upgrade = r.header("upgrade");
    if (upgrade && (*upgrade == "websocket" || *upgrade == "WebSocket")) return upgrade_ws(c, r);
    if (r.path == "/api/command") {
      if (r.method != "POST") return refuse(c, 405, "POST a JSON command to /api/command");
      if (const auto type = r.header("content-type"); type && media_type(*type) != "application/json") {
        return refuse(c, 415, "Content-Type '" + std::string(type->substr(0, 60)) + "': commands are application/json");
      }
      if (!header_token_ok(r)) return refuse(c, 401, "missing or wrong token (Authorization: Bearer TOKEN)");
      const nlohmann::json body = nlohmann::json::parse(r.body, nullptr, false);
      if (body.is_discarded() || !body.is_object() || !body.contains("op") || !body["op"].is_string()) {
        return refuse(c, 400, "body: expected a JSON object with a string \"op\"");
      }
      if (!admit(c, Pool::authenticated)) return;
      const std::uint64_t id = next_request++;
      c.waiting_for = id;
      pending.emplace(id, std::chrono::steady_clock::now());
      const std::lock_guard lock(mutex);
      requests.push_back(OperatorRequest{id, r.body});
      return;
    }
    if (r.method != "GET") return refuse(c, 405, "only GET is served here");
    const std::string_view html = r.path == "/" || r.path == "/index.html" ? std::string_view(page)
                                  : r.path == "/rkms"                         ? embedded_rkms_page()
                                  : r.path == "/touch"                        ? embedded_touch_page()
                                                                              : std::string_view();
    if (!html.empty()) {
      // Pages carry no secret (the token comes with the address or is typed): served to anyone.
      // Audio the touch page plays is a data: URL of the answer, hence media-src data:.
      answer_now(c, http_response(200, "text/html; charset=utf-8", html,
                                  "Content-Security-Policy: default-src 'self' 'unsafe-inline'; connect-src 'self' ws: wss:; media-src data:\r\n"));
      return;
    }
    if (r.path == "/api/ping") {
      if (!token_ok(r)) return refuse(c, 401, "missing or wrong token");
      if (!admit(c, Pool::authenticated)) return;
      answer_now(c, http_response(200, "application/json", R"({"ok":true})"));
      return;
    }
    refuse(c, 404, "not found: the monitor serves / (the page), /rkms (the RKMS administration), /touch (the touch screen), "
                   "/ws (WebSocket) and /api/command");
  }

  void upgrade_ws(Connection& c, const HttpRequest& r) {
    const auto key = r.header("sec-websocket-key");
    if (!key || key->empty()) return refuse(c, 400, "WebSocket upgrade without Sec-WebSocket-Key");
    const bool with_token = token_ok(r);
    if (!options.read_without_token && !with_token) return refuse(c, 401, "missing or wrong token (?token=TOKEN)");
    if (!admit(c, with_token ? Pool::authenticated : Pool::reader)) return;
    bool foxglove = false;
    if (const auto proto = r.header("sec-websocket-protocol")) foxglove = proto->find(kFoxglove) != std::string_view::npos;
    std::string response = "HTTP/1.1 101 Switching Protocols\r\nUpgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Accept: " +
                           websocket_accept(*key) + "\r\n";
    if (foxglove) response += "Sec-WebSocket-Protocol: " + std::string(kFoxglove) + "\r\n";
    response += "\r\n";
    c.kind = foxglove ? Kind::foxglove : Kind::page;
    enqueue(c, std::move(response), false);
    if (foxglove) {
      const nlohmann::json info{{"op", "serverInfo"},
                                {"name", "tripodal monitor"},
                                {"capabilities", nlohmann::json::array()},
                                {"supportedEncodings", {"json"}},
                                {"metadata", nlohmann::json::object()},
                                {"sessionId", session_id}};
      enqueue(c, ws_frame(WsOpcode::text, info.dump()), false);
      nlohmann::json adv{{"op", "advertise"}, {"channels", nlohmann::json::array()}};
      for (const Channel& ch : channels) {
        adv["channels"].push_back({{"id", ch.id},
                                   {"topic", ch.topic},
                                   {"encoding", "json"},
                                   {"schemaName", ch.schema_name},
                                   {"schema", ch.schema},
                                   {"schemaEncoding", "jsonschema"}});
      }
      enqueue(c, ws_frame(WsOpcode::text, adv.dump()), false);
    } else {
      nlohmann::json hello{{"topics", nlohmann::json::array()}, {"read_only", !with_token}};
      for (const Channel& ch : channels) hello["topics"].push_back(ch.topic);
      enqueue(c, ws_frame(WsOpcode::text, R"({"topic":"hello","t":0,"data":)" + hello.dump() + "}"), false);
      for (const Channel& ch : channels) {
        if (ch.has_latest) deliver(c, ch, ch.latest_stamp_s, ch.latest_json);
      }
      for (const Message& m : history) deliver(c, channels[m.channel - 1], m.stamp_s, m.json);
    }
    if (!c.in.empty()) handle_ws(c);
  }

  void protocol_error(Connection& c, std::string_view why) {
    std::string reason = "\x03\xEA" + std::string(why.substr(0, 100));  // 1002 protocol error
    enqueue(c, ws_frame(WsOpcode::close, reason), false);
    c.close_after_write = true;
    c.in.clear();
  }

  void handle_ws(Connection& c) {
    while (!c.close_after_write) {
      WsParse p = parse_ws_frame(c.in, kMaxClientFrame);
      if (p.status == WsParse::Status::incomplete) return;
      if (p.status == WsParse::Status::error) return protocol_error(c, p.error);
      c.in.erase(0, p.consumed);
      const auto op = static_cast<std::uint8_t>(p.frame.opcode);
      const bool control = (op & 0x8U) != 0;
      if (control && (!p.frame.fin || p.frame.payload.size() > 125)) {
        return protocol_error(c, "control frame fragmented or over 125 bytes (RFC 6455 5.5)");
      }
      switch (p.frame.opcode) {
        case WsOpcode::close:
          enqueue(c, ws_frame(WsOpcode::close, p.frame.payload.substr(0, 2)), false);
          c.close_after_write = true;
          return;
        case WsOpcode::ping: enqueue(c, ws_frame(WsOpcode::pong, p.frame.payload), false); break;
        case WsOpcode::pong: break;
        case WsOpcode::text:
        case WsOpcode::binary:
        case WsOpcode::continuation:
          // Page clients only listen (commands go through POST /api/command): what they send is
          // counted and dropped. Foxglove clients are answered.
          if (c.kind != Kind::foxglove) {
            count(&MonitorStats::client_errors);
          } else if (p.frame.opcode != WsOpcode::text) {
            foxglove_status(c, "binary client messages (publishing, service calls) are not offered by this server");
          } else if (!p.frame.fin) {
            foxglove_status(c, "fragmented messages are not accepted: send each operation in one frame");
          } else {
            foxglove_request(c, p.frame.payload);
          }
          break;
        default: return protocol_error(c, "unknown opcode " + std::to_string(op));
      }
    }
  }

  // Foxglove's status message, level 2 (error): what a client sent that the server refused.
  void foxglove_status(Connection& c, const std::string& message) {
    count(&MonitorStats::client_errors);
    const nlohmann::json status{{"op", "status"}, {"level", 2}, {"message", message}};
    enqueue(c, ws_frame(WsOpcode::text, status.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace)), false);
  }

  // A subscription or channel id: a whole number that fits 32 bits.
  static std::optional<std::uint32_t> u32(const nlohmann::json& v) {
    if (!v.is_number_unsigned() || v.get<std::uint64_t>() > 0xFFFFFFFFU) return std::nullopt;
    return static_cast<std::uint32_t>(v.get<std::uint64_t>());
  }

  static std::string type_of(const nlohmann::json& v) {
    if (v.is_number_integer() && !v.is_number_unsigned()) return "a negative number";
    if (v.is_number_unsigned()) return "a number over 4294967295";
    return std::string(v.type_name());
  }

  // Client operations of foxglove.websocket.v1. Anything malformed or wrong-typed is answered with
  // a status naming the field and what was expected; nothing throws.
  void foxglove_request(Connection& c, const std::string& text) {
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded()) return foxglove_status(c, "not JSON: expected an object {\"op\": ...}");
    if (!j.is_object()) return foxglove_status(c, "expected a JSON object {\"op\": ...}, got " + std::string(j.type_name()));
    const auto op_it = j.find("op");
    if (op_it == j.end() || !op_it->is_string()) {
      return foxglove_status(c, "\"op\": expected a string, got " + (op_it == j.end() ? std::string("nothing") : std::string(op_it->type_name())));
    }
    const std::string& op = op_it->get_ref<const std::string&>();
    if (op == "subscribe") return subscribe(c, j);
    if (op == "unsubscribe") return unsubscribe(c, j);
    static constexpr std::array<std::string_view, 11> kNotOffered = {
        "advertise", "unadvertise", "getParameters", "setParameters", "subscribeParameterUpdates", "unsubscribeParameterUpdates",
        "callService", "subscribeConnectionGraph", "unsubscribeConnectionGraph", "fetchAsset", "serviceCallRequest"};
    if (std::find(kNotOffered.begin(), kNotOffered.end(), op) != kNotOffered.end()) {
      return foxglove_status(c, "op '" + op + "' is not offered: this server advertises no capabilities (subscribe and unsubscribe only)");
    }
    foxglove_status(c, "unknown op '" + op.substr(0, 60) + "': expected subscribe or unsubscribe");
  }

  void subscribe(Connection& c, const nlohmann::json& j) {
    const auto subs = j.find("subscriptions");
    if (subs == j.end() || !subs->is_array()) {
      return foxglove_status(c, "subscribe: \"subscriptions\": expected an array of {id, channelId}, got " +
                                    (subs == j.end() ? std::string("nothing") : std::string(subs->type_name())));
    }
    for (std::size_t i = 0; i < subs->size(); ++i) {
      const nlohmann::json& s = (*subs)[i];
      const std::string where = "subscribe: subscriptions[" + std::to_string(i) + "]";
      if (!s.is_object()) {
        foxglove_status(c, where + ": expected an object {id, channelId}, got " + std::string(s.type_name()));
        continue;
      }
      const auto id_it = s.find("id");
      const auto ch_it = s.find("channelId");
      const auto id = id_it == s.end() ? std::nullopt : u32(*id_it);
      const auto channel = ch_it == s.end() ? std::nullopt : u32(*ch_it);
      if (!id) {
        foxglove_status(c, where + ".id: expected a whole number 0..4294967295, got " + (id_it == s.end() ? std::string("nothing") : type_of(*id_it)));
        continue;
      }
      if (!channel) {
        foxglove_status(c, where + ".channelId: expected a whole number 0..4294967295, got " +
                               (ch_it == s.end() ? std::string("nothing") : type_of(*ch_it)));
        continue;
      }
      if (*channel == 0 || *channel > channels.size()) {
        foxglove_status(c, where + ".channelId: no channel " + std::to_string(*channel) + " was advertised");
        continue;
      }
      c.subscriptions[*channel] = *id;
      const Channel& ch = channels[*channel - 1];
      if (ch.has_latest) deliver(c, ch, ch.latest_stamp_s, ch.latest_json);
      if (ch.delivery == Delivery::event) {  // what happened before the subscription
        for (const Message& m : history) {
          if (m.channel == *channel) deliver(c, ch, m.stamp_s, m.json);
        }
      }
    }
  }

  void unsubscribe(Connection& c, const nlohmann::json& j) {
    const auto ids = j.find("subscriptionIds");
    if (ids == j.end() || !ids->is_array()) {
      return foxglove_status(c, "unsubscribe: \"subscriptionIds\": expected an array of whole numbers, got " +
                                    (ids == j.end() ? std::string("nothing") : std::string(ids->type_name())));
    }
    for (std::size_t i = 0; i < ids->size(); ++i) {
      const auto id = u32((*ids)[i]);
      if (!id) {
        foxglove_status(c, "unsubscribe: subscriptionIds[" + std::to_string(i) + "]: expected a whole number 0..4294967295, got " +
                               type_of((*ids)[i]));
        continue;
      }
      std::erase_if(c.subscriptions, [&id](const auto& kv) { return kv.second == *id; });
    }
  }
};

MonitorServerOptions server_options(std::string_view spec, const std::filesystem::path& token_file) {
  MonitorServerOptions o;
  std::string_view port = spec;
  if (const std::size_t colon = spec.rfind(':'); colon != std::string_view::npos) {
    o.address = std::string(spec.substr(0, colon));
    port = spec.substr(colon + 1);
    in_addr probe{};
    if (::inet_pton(AF_INET, o.address.c_str(), &probe) != 1) {
      throw std::invalid_argument("monitor address '" + o.address + "': expected an IPv4 address such as 127.0.0.1");
    }
  }
  const bool digits = !port.empty() && port.size() <= 5 && std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; });
  if (!digits || std::stoul(std::string(port)) > 65535) {
    throw std::invalid_argument("monitor port '" + std::string(port) + "' in '" + std::string(spec) + "': expected [ADDR:]PORT with PORT in 0..65535");
  }
  o.port = static_cast<std::uint16_t>(std::stoul(std::string(port)));
  if (!token_file.empty()) {
    std::ifstream f(token_file);
    if (!f) throw std::invalid_argument("monitor token file '" + token_file.string() + "': cannot be read");
    std::string line;
    std::getline(f, line);
    while (!line.empty() && (line.back() == '\r' || line.back() == ' ' || line.back() == '\t')) line.pop_back();
    const bool printable = std::all_of(line.begin(), line.end(), [](unsigned char c) { return c > 0x20 && c < 0x7F; });
    if (line.size() < 8 || !printable) {
      throw std::invalid_argument(token_file.string() + ":1:1: monitor token: expected at least 8 printable characters without spaces on the first line");
    }
    o.token = line;
  }
  return o;
}

MonitorServer::MonitorServer(MonitorServerOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.options = std::move(options);
  if (m.options.token.empty()) m.options.token = random_token();
  const MonitorServerOptions& o = m.options;
  const auto refuse = [](const std::string& what) { throw std::invalid_argument("monitor: " + what); };
  if (o.max_clients == 0 || o.max_unauthenticated == 0) {
    refuse("max_clients and max_unauthenticated: expected at least 1 (got " + std::to_string(o.max_clients) + " and " +
           std::to_string(o.max_unauthenticated) + ")");
  }
  if (o.max_history_bytes > o.max_event_bytes / 2) {
    refuse("max_history_bytes " + std::to_string(o.max_history_bytes) + ": expected at most half of max_event_bytes (" +
           std::to_string(o.max_event_bytes) + "), so that the history replayed to a client that joins fits its queue");
  }
  if (!(o.header_timeout_s > 0.0) || !(o.answer_timeout_s > 0.0) || o.header_timeout_s > 3600.0 || o.answer_timeout_s > 3600.0) {
    refuse("header_timeout_s and answer_timeout_s: expected seconds in (0, 3600] (got " + std::to_string(o.header_timeout_s) + " and " +
           std::to_string(o.answer_timeout_s) + ")");
  }
  const std::string where = m.options.address + ":" + std::to_string(m.options.port);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(m.options.port);
  if (::inet_pton(AF_INET, m.options.address.c_str(), &addr.sin_addr) != 1) {
    throw std::runtime_error("monitor: address '" + m.options.address + "': expected an IPv4 address such as 127.0.0.1");
  }
  m.listen_fd = ::socket(AF_INET, SOCK_STREAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (m.listen_fd < 0) throw std::runtime_error("monitor: socket(): " + std::string(std::strerror(errno)));
  const int one = 1;
  ::setsockopt(m.listen_fd, SOL_SOCKET, SO_REUSEADDR, &one, sizeof one);
  if (::bind(m.listen_fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 || ::listen(m.listen_fd, 64) != 0) {
    const std::string why = std::strerror(errno);
    ::close(m.listen_fd);
    throw std::runtime_error("monitor: cannot listen on " + where + ": " + why);
  }
  socklen_t len = sizeof addr;
  ::getsockname(m.listen_fd, reinterpret_cast<sockaddr*>(&addr), &len);
  m.port = ntohs(addr.sin_port);
  m.wake_fd = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
}

MonitorServer::~MonitorServer() {
  stop();
  ::close(impl_->listen_fd);
  ::close(impl_->wake_fd);
}

std::uint32_t MonitorServer::advertise(std::string topic, std::string schema_name, std::string schema, Delivery delivery) {
  if (impl_->running.load()) throw std::logic_error("monitor: advertise '" + topic + "' before start()");
  Channel ch;
  ch.id = static_cast<std::uint32_t>(impl_->channels.size() + 1);
  ch.topic = std::move(topic);
  ch.schema_name = std::move(schema_name);
  ch.schema = std::move(schema);
  ch.delivery = delivery;
  impl_->channels.push_back(std::move(ch));
  return impl_->channels.back().id;
}

void MonitorServer::set_page(std::string html) { impl_->page = std::move(html); }

void MonitorServer::start() {
  if (impl_->running.exchange(true)) return;
  impl_->thread = std::thread([this] { impl_->run(); });
}

void MonitorServer::stop() noexcept {
  if (!impl_->running.exchange(false)) return;
  impl_->wake();
  if (impl_->thread.joinable()) impl_->thread.join();
}

void MonitorServer::publish(std::uint32_t channel, double stamp_s, std::string json) {
  {
    const std::lock_guard lock(impl_->mutex);
    // A server that is not (or no longer) draining the outbox must not grow it without bound:
    // bulk messages go oldest first here too (the channels do not change once started).
    auto& out = impl_->outbox;
    if (out.size() >= kMaxOutbox) {
      const auto bulk = [this](const Message& m) {
        return m.channel >= 1 && m.channel <= impl_->channels.size() && impl_->channels[m.channel - 1].delivery == Delivery::bulk;
      };
      if (const auto it = std::find_if(out.begin(), out.end(), bulk); it != out.end()) {
        out.erase(it);
        ++impl_->stats.bulk_shed;
      }
    }
    impl_->outbox.push_back(Message{channel, stamp_s, std::move(json)});
    ++impl_->stats.published;
  }
  impl_->wake();
}

std::vector<OperatorRequest> MonitorServer::take_requests() {
  std::vector<OperatorRequest> out;
  const std::lock_guard lock(impl_->mutex);
  out.swap(impl_->requests);
  return out;
}

void MonitorServer::answer(std::uint64_t id, int status, const std::string& json) {
  {
    const std::lock_guard lock(impl_->mutex);
    impl_->answers.emplace_back(id, http_response(status, "application/json", json));
  }
  impl_->wake();
}

std::uint16_t MonitorServer::port() const noexcept { return impl_->port; }
const std::string& MonitorServer::token() const noexcept { return impl_->options.token; }
std::string MonitorServer::url() const {
  return "http://" + impl_->options.address + ":" + std::to_string(impl_->port) + "/?token=" + impl_->options.token;
}
MonitorStats MonitorServer::stats() const {
  const std::lock_guard lock(impl_->mutex);
  return impl_->stats;
}

}  // namespace tripodal::monitor
