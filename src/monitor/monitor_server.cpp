#include "tripodal/monitor/monitor_server.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <deque>
#include <fstream>
#include <algorithm>
#include <map>
#include <mutex>
#include <random>
#include <stdexcept>
#include <thread>

#include <nlohmann/json.hpp>

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

std::string error_json(std::string_view message) { return nlohmann::json{{"error", message}}.dump(); }

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

struct Connection {
  int fd = -1;
  Kind kind = Kind::http;
  std::string in;
  std::deque<OutFrame> out;
  std::size_t out_offset = 0;  // bytes of out.front() already sent
  std::size_t event_bytes = 0; // queued bytes that may not be dropped
  std::size_t bulk_frames = 0;
  bool close_after_write = false;
  bool dead = false;
  std::uint64_t waiting_for = 0;  // an operator request this HTTP connection waits on
  SteadyTime since{};
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
        history.push_back(std::move(m));
        if (history.size() > options.history) history.pop_front();
      }
    }
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
          enqueue(*c, std::move(response), false);
          c->close_after_write = true;
          break;
        }
      }
    }
  }

  void accept_clients() {
    for (;;) {
      const int fd = ::accept4(listen_fd, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) return;
      if (connections.size() >= options.max_clients) {
        const std::string r = http_response(503, "application/json", error_json("too many clients"));
        [[maybe_unused]] const auto w = ::send(fd, r.data(), r.size(), MSG_NOSIGNAL);
        ::close(fd);
        continue;
      }
      const int one = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
      // A bounded kernel buffer too, so "queued for this client" means what the options say.
      const int sndbuf = static_cast<int>(options.send_buffer_bytes);
      if (sndbuf > 0) ::setsockopt(fd, SOL_SOCKET, SO_SNDBUF, &sndbuf, sizeof sndbuf);
      auto c = std::make_unique<Connection>();
      c->fd = fd;
      c->since = std::chrono::steady_clock::now();
      connections.push_back(std::move(c));
    }
  }

  void expire() {
    const auto now = std::chrono::steady_clock::now();
    const auto idle = std::chrono::duration<double>(options.idle_timeout_s);
    for (auto& c : connections) {
      if (c->kind == Kind::http && c->waiting_for == 0 && c->out.empty() && now - c->since > idle) c->dead = true;
    }
    const auto limit = std::chrono::duration<double>(options.answer_timeout_s);
    for (auto it = pending.begin(); it != pending.end();) {
      if (now - it->second <= limit) {
        ++it;
        continue;
      }
      for (auto& c : connections) {
        if (c->waiting_for == it->first) {
          c->waiting_for = 0;
          enqueue(*c, http_response(503, "application/json", error_json("the robot did not answer in time")), false);
          c->close_after_write = true;
        }
      }
      it = pending.erase(it);
    }
  }

  void reap() {
    std::size_t clients = 0;
    for (auto it = connections.begin(); it != connections.end();) {
      if ((*it)->dead) {
        ::close((*it)->fd);
        it = connections.erase(it);
      } else {
        clients += (*it)->kind != Kind::http ? 1 : 0;
        ++it;
      }
    }
    const std::lock_guard lock(mutex);
    stats.clients = clients;
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
    enqueue(c, http_response(status, "application/json", error_json(message)), false);
    c.close_after_write = true;
    c.in.clear();
  }

  [[nodiscard]] bool token_ok(const HttpRequest& r) const {
    std::string_view given;
    if (const auto a = r.header("authorization"); a && a->starts_with("Bearer ")) given = a->substr(7);
    else if (const auto t = r.header("x-tripodal-token")) given = *t;
    else if (const auto q = r.query("token")) given = *q;
    return !given.empty() && constant_time_equal(given, options.token);
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
    const auto upgrade = r.header("upgrade");
    if (upgrade && (*upgrade == "websocket" || *upgrade == "WebSocket")) return upgrade_ws(c, r);
    if (r.path == "/api/command") {
      if (r.method != "POST") return refuse(c, 405, "POST a JSON command to /api/command");
      if (!token_ok(r)) return refuse(c, 401, "missing or wrong token (Authorization: Bearer TOKEN)");
      const nlohmann::json body = nlohmann::json::parse(r.body, nullptr, false);
      if (body.is_discarded() || !body.is_object() || !body.contains("op") || !body["op"].is_string()) {
        return refuse(c, 400, "body: expected a JSON object with a string \"op\"");
      }
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
      enqueue(c, http_response(200, "text/html; charset=utf-8", html,
                               "Content-Security-Policy: default-src 'self' 'unsafe-inline'; connect-src 'self' ws: wss:; media-src data:\r\n"),
              false);
      c.close_after_write = true;
      return;
    }
    if (r.path == "/api/ping") {
      if (!token_ok(r)) return refuse(c, 401, "missing or wrong token");
      enqueue(c, http_response(200, "application/json", R"({"ok":true})"), false);
      c.close_after_write = true;
      return;
    }
    refuse(c, 404, "not found: the monitor serves / (the page), /rkms (the RKMS administration), /touch (the touch screen), "
                   "/ws (WebSocket) and /api/command");
  }

  void upgrade_ws(Connection& c, const HttpRequest& r) {
    const auto key = r.header("sec-websocket-key");
    if (!key || key->empty()) return refuse(c, 400, "WebSocket upgrade without Sec-WebSocket-Key");
    if (!options.read_without_token && !token_ok(r)) return refuse(c, 401, "missing or wrong token (?token=TOKEN)");
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
                                {"sessionId", options.token.substr(0, 4) + std::to_string(port)}};
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
      nlohmann::json hello{{"topics", nlohmann::json::array()}, {"read_only", !token_ok(r)}};
      for (const Channel& ch : channels) hello["topics"].push_back(ch.topic);
      enqueue(c, ws_frame(WsOpcode::text, R"({"topic":"hello","t":0,"data":)" + hello.dump() + "}"), false);
      for (const Channel& ch : channels) {
        if (ch.has_latest) deliver(c, ch, ch.latest_stamp_s, ch.latest_json);
      }
      for (const Message& m : history) deliver(c, channels[m.channel - 1], m.stamp_s, m.json);
    }
    if (!c.in.empty()) handle_ws(c);
  }

  void handle_ws(Connection& c) {
    for (;;) {
      WsParse p = parse_ws_frame(c.in, kMaxClientFrame);
      if (p.status == WsParse::Status::incomplete) return;
      if (p.status == WsParse::Status::error) {
        std::string reason = "\x03\xEA" + p.error.substr(0, 100);  // 1002 protocol error
        enqueue(c, ws_frame(WsOpcode::close, reason), false);
        c.close_after_write = true;
        c.in.clear();
        return;
      }
      c.in.erase(0, p.consumed);
      switch (p.frame.opcode) {
        case WsOpcode::close:
          enqueue(c, ws_frame(WsOpcode::close, p.frame.payload.substr(0, 2)), false);
          c.close_after_write = true;
          return;
        case WsOpcode::ping: enqueue(c, ws_frame(WsOpcode::pong, p.frame.payload), false); break;
        case WsOpcode::text:
          if (c.kind == Kind::foxglove) foxglove_request(c, p.frame.payload);
          break;
        default: break;  // page clients only listen; commands go through POST /api/command
      }
    }
  }

  void foxglove_request(Connection& c, const std::string& text) {
    const nlohmann::json j = nlohmann::json::parse(text, nullptr, false);
    if (j.is_discarded() || !j.is_object() || !j.contains("op") || !j["op"].is_string()) return;
    const std::string op = j["op"];
    if (op == "subscribe" && j.contains("subscriptions") && j["subscriptions"].is_array()) {
      for (const auto& s : j["subscriptions"]) {
        if (!s.is_object() || !s.contains("id") || !s.contains("channelId")) continue;
        if (!s["id"].is_number_unsigned() || !s["channelId"].is_number_unsigned()) continue;
        const auto channel = s["channelId"].get<std::uint32_t>();
        if (channel == 0 || channel > channels.size()) continue;
        c.subscriptions[channel] = s["id"].get<std::uint32_t>();
        const Channel& ch = channels[channel - 1];
        if (ch.has_latest) deliver(c, ch, ch.latest_stamp_s, ch.latest_json);
        if (ch.delivery == Delivery::event) {  // what happened before the subscription
          for (const Message& m : history) {
            if (m.channel == channel) deliver(c, ch, m.stamp_s, m.json);
          }
        }
      }
    } else if (op == "unsubscribe" && j.contains("subscriptionIds") && j["subscriptionIds"].is_array()) {
      for (const auto& id : j["subscriptionIds"]) {
        if (!id.is_number_unsigned()) continue;
        for (auto it = c.subscriptions.begin(); it != c.subscriptions.end();) {
          it = it->second == id.get<std::uint32_t>() ? c.subscriptions.erase(it) : std::next(it);
        }
      }
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
