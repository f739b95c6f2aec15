// MonitorServer: the HTTP and WebSocket server of the robot monitor (monitor area, beside the
// application at the top of the area graph). One thread of its own polls every socket; the robot's
// thread only appends to a briefly locked outbox and takes operator requests when it is ready, so
// no client can slow a control or sequencing loop. It serves the embedded page, a stream of topics
// to page clients and to Foxglove clients (subprotocol foxglove.websocket.v1), and operator
// commands (POST /api/command) that need the token. Every request's Host and Origin are checked, so
// a page of another site cannot use the operator's browser against the robot, and everything a
// client can make it keep has a budget. docs/monitor.md describes protocol, checks and budgets.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace tripodal::monitor {

/// How much of a request the server reads before it answers 431 or 413.
struct HttpLimits {
  std::size_t max_header_bytes = 16 * 1024;  ///< request line and headers
  std::size_t max_body_bytes = 64 * 1024;
};

/// How a topic's messages travel to a client whose queue fills up.
enum class Delivery {
  bulk,   ///< poses, scans, maps of cleaned cells: the oldest queued is shed when the queue is full
  state,  ///< nets, the map: never dropped; the latest is sent to a client when it joins
  event,  ///< life cycle, faults: never dropped (a client that cannot keep up is disconnected);
          ///< the last `history` are replayed to a client when it joins
};

// Every budget below bounds what a client, with or without the token, can make the robot's process
// keep; docs/monitor.md, "Budgets", says what happens past each. The constructor refuses values that
// break the server's own guarantees (std::invalid_argument naming the option).
struct MonitorServerOptions {
  std::string address = "127.0.0.1";  ///< loopback unless the operator says otherwise
  std::uint16_t port = 0;              ///< 0: a free port (port() says which)
  std::string token;                   ///< empty: 128 random bits, hex
  bool read_without_token = false;     ///< open the read-only streams without the token
  /// Connections that showed the token: WebSocket clients and operator requests; past it: 503.
  std::size_t max_clients = 32;
  std::size_t max_bulk_frames = 16;    ///< per client; beyond it the oldest bulk frame is shed
  std::size_t max_event_bytes = 8U << 20U;  ///< per client; beyond it the client is disconnected
  std::size_t send_buffer_bytes = 256U << 10U;  ///< the kernel's send buffer per client (SO_SNDBUF)
  std::size_t history = 2000;          ///< event messages kept for clients that join later
  /// Bytes of those (as framed for a page client); at most max_event_bytes / 2, so the replay to a
  /// client that joins always fits its queue. The oldest go first; a longer message is not kept.
  std::size_t max_history_bytes = 2U << 20U;
  double answer_timeout_s = 5.0;       ///< an operator request the robot leaves unanswered: 503
  /// A connection that has not shown the token is closed this long after it was accepted, whatever
  /// it is doing (request still coming, answer not read); an operator's answer has as long to be read.
  double header_timeout_s = 3.0;
  /// Connections that have not shown the token (yet): a pool of their own, so that half-open
  /// connections cannot starve the operator; a new one evicts the oldest when it is full.
  std::size_t max_unauthenticated = 64;
  /// WebSocket readers without the token (read_without_token only); past it: 503.
  std::size_t max_open_readers = 16;
  /// Host names besides loopback and IP literals that requests may name in `Host` (the robot's
  /// DNS name when it serves a network); any other name is refused with 421 (DNS rebinding).
  std::vector<std::string> allowed_hosts;
  /// Origins besides the page's own (`http://` + the request's Host) allowed to open a WebSocket or
  /// send a command, e.g. "https://app.foxglove.dev"; any other is refused with 403.
  std::vector<std::string> allowed_origins;
  HttpLimits http;
};

/// A command from the operator (the JSON body of POST /api/command, token checked), handed to the
/// robot's thread; answer it with MonitorServer::answer().
struct OperatorRequest {
  std::uint64_t id = 0;
  std::string body;
};

struct MonitorStats {
  std::size_t clients = 0;             ///< WebSocket clients now
  std::size_t unauthenticated = 0;     ///< connections now that have not shown the token
  std::uint64_t frames_sent = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t bulk_shed = 0;         ///< bulk frames dropped from a full client queue
  std::uint64_t slow_disconnects = 0;  ///< clients dropped because their events did not fit
  std::uint64_t unauthorized = 0;      ///< requests refused with 401
  std::uint64_t published = 0;
  std::uint64_t header_timeouts = 0;   ///< connections without the token closed at header_timeout_s
  std::uint64_t evicted = 0;           ///< connections without the token closed for a newer one
  std::uint64_t busy = 0;              ///< refused with 503: the client or reader pool was full
  std::uint64_t refused_host = 0;      ///< refused with 421: a Host that is not this server's
  std::uint64_t refused_origin = 0;    ///< refused with 403: an Origin that is not the page's own
  std::uint64_t client_errors = 0;     ///< client messages refused (Foxglove status) or ignored
  std::uint64_t history_not_kept = 0;  ///< event messages longer than max_history_bytes (sent, not kept)
  std::size_t history_entries = 0;     ///< event messages kept for clients that join now
  std::size_t history_bytes = 0;       ///< and their bytes
};

class MonitorServer final {
 public:
  /// Binds and listens (the thread starts with start()). Throws std::invalid_argument naming the
  /// option for options it refuses, std::runtime_error naming the address when it cannot listen.
  explicit MonitorServer(MonitorServerOptions options = {});
  ~MonitorServer();
  MonitorServer(const MonitorServer&) = delete;
  MonitorServer& operator=(const MonitorServer&) = delete;

  /// Declares a topic (before start()); returns its channel id. `schema` is a JSON schema.
  std::uint32_t advertise(std::string topic, std::string schema_name, std::string schema, Delivery delivery);
  /// The page served at "/" (default: the embedded one).
  void set_page(std::string html);
  void start();
  void stop() noexcept;

  /// Any thread: queues a JSON message of `channel`, stamped `stamp_s` (robot time). Never waits
  /// for a socket: it appends under a mutex held for a move.
  void publish(std::uint32_t channel, double stamp_s, std::string json);
  /// Any thread (the robot's): the operator requests received since the last call.
  [[nodiscard]] std::vector<OperatorRequest> take_requests();
  /// Answers request `id` with an HTTP status and a JSON body.
  void answer(std::uint64_t id, int status, const std::string& json);

  [[nodiscard]] std::uint16_t port() const noexcept;
  [[nodiscard]] const std::string& token() const noexcept;
  /// http://ADDRESS:PORT/?token=TOKEN, what the operator opens.
  [[nodiscard]] std::string url() const;
  [[nodiscard]] MonitorStats stats() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// Options for "[ADDR:]PORT" ("8765", "0.0.0.0:8765"), with the token read from `token_file`
/// (its first line) when given. Throws std::invalid_argument saying what is wrong and what was
/// expected.
[[nodiscard]] MonitorServerOptions server_options(std::string_view spec, const std::filesystem::path& token_file = {});

/// The embedded page (assets compiled into the binary).
[[nodiscard]] std::string_view embedded_page() noexcept;
/// The RKMS administration page (served at /rkms) and the visitors' touch page (/touch).
[[nodiscard]] std::string_view embedded_rkms_page() noexcept;
[[nodiscard]] std::string_view embedded_touch_page() noexcept;

}  // namespace tripodal::monitor
