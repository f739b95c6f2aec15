#include "wire.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>

#include <algorithm>
#include <cctype>

namespace tripodal::monitor {
namespace {

std::uint32_t rotl(std::uint32_t x, int n) noexcept { return (x << n) | (x >> (32 - n)); }

std::string lower(std::string_view s) {
  std::string out(s);
  std::transform(out.begin(), out.end(), out.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return out;
}

std::string_view trim(std::string_view s) noexcept {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.remove_suffix(1);
  return s;
}

}  // namespace

std::array<std::uint8_t, 20> sha1(std::string_view data) noexcept {
  std::uint32_t h[5] = {0x67452301U, 0xEFCDAB89U, 0x98BADCFEU, 0x10325476U, 0xC3D2E1F0U};
  const std::uint64_t bit_length = static_cast<std::uint64_t>(data.size()) * 8U;
  // The message, a 1 bit, zeros, then the 64-bit length: processed block by block without a copy
  // of the whole message.
  const std::size_t total = ((data.size() + 8U) / 64U + 1U) * 64U;
  std::uint8_t block[64];
  for (std::size_t offset = 0; offset < total; offset += 64) {
    for (std::size_t i = 0; i < 64; ++i) {
      const std::size_t k = offset + i;
      std::uint8_t b = 0;
      if (k < data.size()) b = static_cast<std::uint8_t>(data[k]);
      else if (k == data.size()) b = 0x80;
      else if (k >= total - 8) b = static_cast<std::uint8_t>(bit_length >> (8U * (total - 1 - k)));
      block[i] = b;
    }
    std::uint32_t w[80];
    for (std::size_t i = 0; i < 16; ++i) {
      w[i] = (std::uint32_t{block[4 * i]} << 24) | (std::uint32_t{block[4 * i + 1]} << 16) |
             (std::uint32_t{block[4 * i + 2]} << 8) | std::uint32_t{block[4 * i + 3]};
    }
    for (int i = 16; i < 80; ++i) w[i] = rotl(w[i - 3] ^ w[i - 8] ^ w[i - 14] ^ w[i - 16], 1);
    std::uint32_t a = h[0], b = h[1], c = h[2], d = h[3], e = h[4];
    for (int i = 0; i < 80; ++i) {
      std::uint32_t f = 0, k = 0;
      if (i < 20) { f = (b & c) | (~b & d); k = 0x5A827999U; }
      else if (i < 40) { f = b ^ c ^ d; k = 0x6ED9EBA1U; }
      else if (i < 60) { f = (b & c) | (b & d) | (c & d); k = 0x8F1BBCDCU; }
      else { f = b ^ c ^ d; k = 0xCA62C1D6U; }
      const std::uint32_t t = rotl(a, 5) + f + e + k + w[i];
      e = d;
      d = c;
      c = rotl(b, 30);
      b = a;
      a = t;
    }
    h[0] += a; h[1] += b; h[2] += c; h[3] += d; h[4] += e;
  }
  std::array<std::uint8_t, 20> out{};
  for (std::size_t i = 0; i < 20; ++i) out[i] = static_cast<std::uint8_t>(h[i / 4] >> (24 - 8 * (i % 4)));
  return out;
}

std::string base64(std::string_view bytes) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  for (std::size_t i = 0; i < bytes.size(); i += 3) {
    const std::size_t n = std::min<std::size_t>(3, bytes.size() - i);
    std::uint32_t v = 0;
    for (std::size_t k = 0; k < 3; ++k) v = (v << 8) | (k < n ? static_cast<std::uint8_t>(bytes[i + k]) : 0U);
    for (std::size_t k = 0; k < 4; ++k) out += k <= n ? kAlphabet[(v >> (18 - 6 * k)) & 0x3FU] : '=';
  }
  return out;
}

std::string websocket_accept(std::string_view key) {
  const auto digest = sha1(std::string(key) + "258EAFA5-E914-47DA-95CA-C5AB0DC85B11");
  return base64(std::string_view(reinterpret_cast<const char*>(digest.data()), digest.size()));
}

std::optional<std::string_view> HttpRequest::header(std::string_view name) const noexcept {
  for (const auto& [k, v] : headers) {
    if (k == name) return std::string_view(v);
  }
  return std::nullopt;
}

std::optional<std::string_view> HttpRequest::query(std::string_view name) const noexcept {
  const std::size_t q = target.find('?');
  if (q == std::string::npos) return std::nullopt;
  std::string_view rest = std::string_view(target).substr(q + 1);
  while (!rest.empty()) {
    const std::size_t amp = rest.find('&');
    const std::string_view pair = rest.substr(0, amp);
    const std::size_t eq = pair.find('=');
    if (pair.substr(0, eq) == name) return eq == std::string_view::npos ? std::string_view{} : pair.substr(eq + 1);
    if (amp == std::string_view::npos) break;
    rest.remove_prefix(amp + 1);
  }
  return std::nullopt;
}

HttpParse parse_http_request(std::string_view buffer, const HttpLimits& limits) {
  HttpParse p;
  const std::size_t end = buffer.find("\r\n\r\n");
  if (end == std::string_view::npos) {
    if (buffer.size() > limits.max_header_bytes) p.status = HttpParse::Status::headers_too_large;
    return p;
  }
  if (end + 4 > limits.max_header_bytes) {
    p.status = HttpParse::Status::headers_too_large;
    return p;
  }
  auto bad = [&p](std::string what) {
    p.status = HttpParse::Status::bad_request;
    p.error = std::move(what);
    return p;
  };
  std::string_view head = buffer.substr(0, end);
  const std::size_t line_end = head.find("\r\n");
  const std::string_view line = head.substr(0, line_end);
  const std::size_t s1 = line.find(' ');
  const std::size_t s2 = s1 == std::string_view::npos ? s1 : line.find(' ', s1 + 1);
  if (s2 == std::string_view::npos) return bad("request line '" + std::string(line.substr(0, 80)) + "': expected METHOD TARGET HTTP/1.x");
  p.request.method = std::string(line.substr(0, s1));
  p.request.target = std::string(line.substr(s1 + 1, s2 - s1 - 1));
  if (!line.substr(s2 + 1).starts_with("HTTP/1.")) return bad("request line: expected HTTP/1.x, got '" + std::string(line.substr(s2 + 1, 16)) + "'");
  if (p.request.target.empty() || p.request.target.front() != '/') return bad("target '" + p.request.target.substr(0, 80) + "': expected an absolute path");
  p.request.path = p.request.target.substr(0, p.request.target.find('?'));
  std::string_view rest = line_end == std::string_view::npos ? std::string_view{} : head.substr(line_end + 2);
  while (!rest.empty()) {
    const std::size_t nl = rest.find("\r\n");
    const std::string_view h = rest.substr(0, nl);
    const std::size_t colon = h.find(':');
    if (colon == std::string_view::npos || colon == 0) return bad("header '" + std::string(h.substr(0, 80)) + "': expected NAME: VALUE");
    p.request.headers.emplace_back(lower(trim(h.substr(0, colon))), std::string(trim(h.substr(colon + 1))));
    if (nl == std::string_view::npos) break;
    rest.remove_prefix(nl + 2);
  }
  std::size_t body_bytes = 0;
  if (const auto cl = p.request.header("content-length")) {
    if (cl->empty() || cl->size() > 12 || !std::all_of(cl->begin(), cl->end(), [](char c) { return c >= '0' && c <= '9'; })) {
      return bad("Content-Length '" + std::string(cl->substr(0, 20)) + "': expected a decimal byte count");
    }
    body_bytes = std::stoull(std::string(*cl));
  }
  if (p.request.header("transfer-encoding")) return bad("Transfer-Encoding is not supported: send Content-Length");
  if (body_bytes > limits.max_body_bytes) {
    p.status = HttpParse::Status::body_too_large;
    return p;
  }
  if (buffer.size() < end + 4 + body_bytes) return HttpParse{};  // the body is still coming
  p.request.body = std::string(buffer.substr(end + 4, body_bytes));
  p.consumed = end + 4 + body_bytes;
  p.status = HttpParse::Status::complete;
  return p;
}

std::string_view http_reason(int status) noexcept {
  switch (status) {
    case 101: return "Switching Protocols";
    case 200: return "OK";
    case 400: return "Bad Request";
    case 401: return "Unauthorized";
    case 403: return "Forbidden";
    case 404: return "Not Found";
    case 405: return "Method Not Allowed";
    case 409: return "Conflict";
    case 413: return "Payload Too Large";
    case 415: return "Unsupported Media Type";
    case 421: return "Misdirected Request";
    case 431: return "Request Header Fields Too Large";
    case 503: return "Service Unavailable";
    default: return "Error";
  }
}

std::string http_response(int status, std::string_view content_type, std::string_view body, std::string_view extra_headers) {
  std::string out = "HTTP/1.1 " + std::to_string(status) + " " + std::string(http_reason(status)) + "\r\n";
  out += "Content-Type: " + std::string(content_type) + "\r\n";
  out += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  // The page is the only document: it must not be framed or sniffed into something else.
  out += "Cache-Control: no-store\r\nX-Content-Type-Options: nosniff\r\nX-Frame-Options: DENY\r\nConnection: close\r\n";
  out += extra_headers;
  out += "\r\n";
  out += body;
  return out;
}

std::string ws_frame(WsOpcode opcode, std::string_view payload) {
  std::string out;
  out.reserve(payload.size() + 10);
  out += static_cast<char>(0x80U | static_cast<std::uint8_t>(opcode));
  const std::uint64_t n = payload.size();
  if (n < 126) {
    out += static_cast<char>(n);
  } else if (n <= 0xFFFF) {
    out += static_cast<char>(126);
    out += static_cast<char>(n >> 8);
    out += static_cast<char>(n & 0xFFU);
  } else {
    out += static_cast<char>(127);
    for (int i = 7; i >= 0; --i) out += static_cast<char>((n >> (8 * i)) & 0xFFU);
  }
  out += payload;
  return out;
}

WsParse parse_ws_frame(std::string_view buffer, std::size_t max_payload) {
  WsParse p;
  if (buffer.size() < 2) return p;
  const auto b0 = static_cast<std::uint8_t>(buffer[0]);
  const auto b1 = static_cast<std::uint8_t>(buffer[1]);
  auto fail = [&p](std::string what) {
    p.status = WsParse::Status::error;
    p.error = std::move(what);
    return p;
  };
  if ((b0 & 0x70U) != 0) return fail("reserved bits set (no extension was negotiated)");
  if ((b1 & 0x80U) == 0) return fail("client frame not masked (RFC 6455 5.1)");
  std::uint64_t n = b1 & 0x7FU;
  std::size_t pos = 2;
  if (n == 126) {
    if (buffer.size() < 4) return p;
    n = (std::uint64_t{static_cast<std::uint8_t>(buffer[2])} << 8) | static_cast<std::uint8_t>(buffer[3]);
    pos = 4;
  } else if (n == 127) {
    if (buffer.size() < 10) return p;
    n = 0;
    for (std::size_t i = 2; i < 10; ++i) n = (n << 8) | static_cast<std::uint8_t>(buffer[i]);
    pos = 10;
  }
  if (n > max_payload) return fail("frame of " + std::to_string(n) + " bytes: the limit is " + std::to_string(max_payload));
  if (buffer.size() < pos + 4 + n) return p;
  const std::string_view mask = buffer.substr(pos, 4);
  pos += 4;
  p.frame.fin = (b0 & 0x80U) != 0;
  p.frame.opcode = static_cast<WsOpcode>(b0 & 0x0FU);
  p.frame.payload.resize(static_cast<std::size_t>(n));
  for (std::size_t i = 0; i < n; ++i) p.frame.payload[i] = static_cast<char>(buffer[pos + i] ^ mask[i % 4]);
  p.consumed = pos + static_cast<std::size_t>(n);
  p.status = WsParse::Status::complete;
  return p;
}

std::string ws_client_frame(WsOpcode opcode, std::string_view payload, std::uint32_t mask) {
  std::string out = ws_frame(opcode, payload);
  const std::size_t header = out.size() - payload.size();
  out[1] = static_cast<char>(static_cast<std::uint8_t>(out[1]) | 0x80U);
  const char m[4] = {static_cast<char>(mask >> 24), static_cast<char>(mask >> 16), static_cast<char>(mask >> 8), static_cast<char>(mask)};
  out.insert(header, m, 4);
  for (std::size_t i = 0; i < payload.size(); ++i) out[header + 4 + i] = static_cast<char>(payload[i] ^ m[i % 4]);
  return out;
}

bool host_allowed(std::string_view host, const std::vector<std::string>& allowed_hosts) {
  std::string_view name = host;
  std::string_view port;
  if (name.starts_with('[')) {  // [IPv6]:port
    const std::size_t close = name.find(']');
    if (close == std::string_view::npos) return false;
    port = name.substr(close + 1);
    name = name.substr(1, close - 1);
    if (!port.empty() && !port.starts_with(':')) return false;
    in6_addr probe{};
    if (::inet_pton(AF_INET6, std::string(name).c_str(), &probe) != 1) return false;
  } else {
    const std::size_t colon = name.find(':');
    if (colon != std::string_view::npos) {
      port = name.substr(colon);
      name = name.substr(0, colon);
    }
  }
  if (!port.empty()) {
    port.remove_prefix(1);
    if (port.empty() || port.size() > 5 || !std::all_of(port.begin(), port.end(), [](char c) { return c >= '0' && c <= '9'; })) return false;
  }
  if (host.starts_with('[')) return true;  // an IPv6 literal, checked above
  if (name.empty()) return false;
  // An address literal cannot be rebound: a page that names it is served from that very origin.
  in_addr v4{};
  if (::inet_pton(AF_INET, std::string(name).c_str(), &v4) == 1) return true;
  const std::string n = lower(name);
  if (n == "localhost") return true;
  return std::any_of(allowed_hosts.begin(), allowed_hosts.end(), [&n](const std::string& a) { return lower(a) == n; });
}

bool same_origin(std::string_view origin, std::string_view host) noexcept {
  if (host.empty()) return false;
  for (const std::string_view scheme : {std::string_view("http://"), std::string_view("https://")}) {
    if (origin.size() != scheme.size() + host.size()) continue;
    bool equal = true;
    for (std::size_t i = 0; i < origin.size() && equal; ++i) {
      const char expected = i < scheme.size() ? scheme[i] : host[i - scheme.size()];
      equal = std::tolower(static_cast<unsigned char>(origin[i])) == std::tolower(static_cast<unsigned char>(expected));
    }
    if (equal) return true;
  }
  return false;
}

std::string media_type(std::string_view content_type) { return lower(trim(content_type.substr(0, content_type.find(';')))); }

bool constant_time_equal(std::string_view a, std::string_view b) noexcept {
  unsigned char diff = a.size() == b.size() ? 0 : 1;
  const std::size_t n = std::max(a.size(), b.size());
  for (std::size_t i = 0; i < n; ++i) {
    const char x = i < a.size() ? a[i] : '\0';
    const char y = i < b.size() ? b[i] : '\0';
    diff = static_cast<unsigned char>(diff | static_cast<unsigned char>(x ^ y));
  }
  return diff == 0;
}

}  // namespace tripodal::monitor
