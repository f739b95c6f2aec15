// The wire formats of the monitor server (monitor area, the top of the area graph beside app),
// private to the area (never installed; the tests and fuzz targets reach it by its path):
// HTTP/1.1 requests read with size limits, the WebSocket handshake (RFC 6455: SHA-1 and base64
// of the key) and WebSocket frames. Written here rather than taken from websocketpp/asio so the
// server's one poll() thread owns every byte queued per client: that is what lets it shed bulk
// data oldest-first and disconnect a slow client instead of losing an event (docs/monitor.md).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tripodal/monitor/monitor_server.hpp"  // HttpLimits

namespace tripodal::monitor {

/// SHA-1 of `data` (FIPS 180-4); the WebSocket handshake needs nothing stronger.
[[nodiscard]] std::array<std::uint8_t, 20> sha1(std::string_view data) noexcept;
[[nodiscard]] std::string base64(std::string_view bytes);
/// Sec-WebSocket-Accept for a client's Sec-WebSocket-Key.
[[nodiscard]] std::string websocket_accept(std::string_view key);

struct HttpRequest {
  std::string method;
  std::string target;  ///< as sent: path and query
  std::string path;    ///< without the query
  std::vector<std::pair<std::string, std::string>> headers;  ///< names lower-cased
  std::string body;
  /// The header `name` (lower case); nullopt when absent.
  [[nodiscard]] std::optional<std::string_view> header(std::string_view name) const noexcept;
  /// The query parameter `name` (not percent-decoded: tokens are hex); nullopt when absent.
  [[nodiscard]] std::optional<std::string_view> query(std::string_view name) const noexcept;
};

/// Reads one request from the bytes received so far.
struct HttpParse {
  enum class Status { incomplete, complete, bad_request, headers_too_large, body_too_large };
  Status status = Status::incomplete;
  HttpRequest request;
  std::size_t consumed = 0;  ///< bytes of `buffer` the complete request used
  std::string error;         ///< for bad_request: what was wrong
};
[[nodiscard]] HttpParse parse_http_request(std::string_view buffer, const HttpLimits& limits = {});

/// A complete HTTP/1.1 response that closes the connection.
[[nodiscard]] std::string http_response(int status, std::string_view content_type, std::string_view body,
                                        std::string_view extra_headers = {});
[[nodiscard]] std::string_view http_reason(int status) noexcept;

enum class WsOpcode : std::uint8_t { continuation = 0x0, text = 0x1, binary = 0x2, close = 0x8, ping = 0x9, pong = 0xA };

/// A server frame (never masked, never fragmented).
[[nodiscard]] std::string ws_frame(WsOpcode opcode, std::string_view payload);

struct WsFrame {
  WsOpcode opcode = WsOpcode::text;
  bool fin = true;
  std::string payload;  ///< unmasked
};

/// Reads one client frame from the bytes received so far. Clients must mask (RFC 6455 5.1);
/// frames above `max_payload` are refused.
struct WsParse {
  enum class Status { incomplete, complete, error };
  Status status = Status::incomplete;
  WsFrame frame;
  std::size_t consumed = 0;
  std::string error;
};
[[nodiscard]] WsParse parse_ws_frame(std::string_view buffer, std::size_t max_payload = 64 * 1024);

/// Encodes a client frame (masked with `mask`), for tests and the benchmark's clients.
[[nodiscard]] std::string ws_client_frame(WsOpcode opcode, std::string_view payload, std::uint32_t mask = 0x12345678U);

/// Whether a request's `Host` value ("name[:port]") names this server from a browser's point of
/// view: an IP literal (IPv4, or IPv6 in brackets), `localhost`, or one of `allowed_hosts` (names
/// compared without case). Any other name may be a DNS-rebinding page's: refused.
[[nodiscard]] bool host_allowed(std::string_view host, const std::vector<std::string>& allowed_hosts);

/// Whether `origin` (an `Origin` header) is the origin of a page served by the server the request
/// names in `host`: "http://HOST" or "https://HOST", compared without case. "null" is not.
[[nodiscard]] bool same_origin(std::string_view origin, std::string_view host) noexcept;

/// The media type of a Content-Type value, lower case, without parameters ("application/json").
[[nodiscard]] std::string media_type(std::string_view content_type);

/// Whether two secrets are equal, in time independent of where they differ.
[[nodiscard]] bool constant_time_equal(std::string_view a, std::string_view b) noexcept;

}  // namespace tripodal::monitor
