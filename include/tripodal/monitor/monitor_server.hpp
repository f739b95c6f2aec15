// MonitorServer: the HTTP and WebSocket server of the robot monitor (monitor area, beside the
// application at the top of the area graph). One thread of its own polls every socket; the robot's
// thread only appends to a briefly locked outbox and takes operator requests when it is ready, so
// no client can slow a control or sequencing loop. It serves the embedded page, a stream of topics
// to page clients and to Foxglove clients (subprotocol foxglove.websocket.v1), and operator
// commands (POST /api/command) that need the token. docs/monitor.md describes protocol and limits.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "tripodal/monitor/wire.hpp"

namespace tripodal::monitor {

/// How a topic's messages travel to a client whose queue fills up.
enum class Delivery {
  bulk,   ///< poses, scans, maps of cleaned cells: the oldest queued is shed when the queue is full
  state,  ///< nets, the map: never dropped; the latest is sent to a client when it joins
  event,  ///< life cycle, faults: never dropped (a client that cannot keep up is disconnected);
          ///< the last `history` are replayed to a client when it joins
};

struct MonitorServerOptions {
  std::string address = "127.0.0.1";  ///< loopback unless the operator says otherwise
  std::uint16_t port = 0;              ///< 0: a free port (port() says which)
  std::string token;                   ///< empty: 128 random bits, hex
  bool read_without_token = false;     ///< open the read-only streams without the token
  std::size_t max_clients = 32;
  std::size_t max_bulk_frames = 16;    ///< per client; beyond it the oldest bulk frame is shed
  std::size_t max_event_bytes = 8U << 20U;  ///< per client; beyond it the client is disconnected
  std::size_t send_buffer_bytes = 256U << 10U;  ///< the kernel's send buffer per client (SO_SNDBUF)
  std::size_t history = 2000;          ///< event messages kept for clients that join later
  double answer_timeout_s = 5.0;       ///< an operator request the robot leaves unanswered: 503
  double idle_timeout_s = 10.0;        ///< an HTTP request not complete by then: closed
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
  std::uint64_t frames_sent = 0;
  std::uint64_t bytes_sent = 0;
  std::uint64_t bulk_shed = 0;         ///< bulk frames dropped from a full client queue
  std::uint64_t slow_disconnects = 0;  ///< clients dropped because their events did not fit
  std::uint64_t unauthorized = 0;      ///< requests refused with 401
  std::uint64_t published = 0;
};

class MonitorServer final {
 public:
  /// Binds and listens (the thread starts with start()). Throws std::runtime_error naming the
  /// address when it cannot.
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
