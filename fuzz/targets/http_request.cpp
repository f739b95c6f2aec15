// The monitor server's HTTP requests (src/monitor/wire.cpp, docs/monitor.md "Limits"): any bytes
// a peer on the socket may send, read as the server reads them, request after request from one
// connection's buffer. Properties: a complete request never uses more bytes than it was given,
// and no part of it was needed to know it was complete: every shorter prefix is incomplete or
// refused, never read as another request; the limits hold (headers, body); header names are
// lower case; the path is the target without its query; a refusal says what was wrong.
#include <algorithm>
#include <cctype>
#include <string_view>

#include "../fuzz_target.hpp"
#include "tripodal_monitor_internal/wire.hpp"

namespace {

// Small limits so that the fuzzer reaches them without building 16 KiB inputs.
constexpr tripodal::monitor::HttpLimits kLimits{.max_header_bytes = 512, .max_body_bytes = 256};

bool is_lower(std::string_view s) {
  return std::none_of(s.begin(), s.end(), [](char c) { return c >= 'A' && c <= 'Z'; });
}

}  // namespace

TRIPODAL_FUZZ_TARGET(bytes) {
  using namespace tripodal;
  using monitor::HttpParse;
  std::string_view buffer = fuzz::as_text(bytes);
  // A keep-alive peer's pipelined requests: the server reads them one after another.
  for (int requests = 0; requests < 8 && !buffer.empty(); ++requests) {
    const HttpParse p = monitor::parse_http_request(buffer, kLimits);
    if (p.status == HttpParse::Status::bad_request) {
      fuzz::require(!p.error.empty(), "a bad request says what was wrong");
      return;
    }
    if (p.status != HttpParse::Status::complete) {
      fuzz::require(p.consumed == 0, "an unfinished or refused request consumes nothing");
      return;
    }
    fuzz::require(p.consumed > 0 && p.consumed <= buffer.size(), "a request uses at most the bytes given");
    fuzz::require(p.request.body.size() <= kLimits.max_body_bytes, "the body limit holds");
    fuzz::require(p.consumed - p.request.body.size() <= kLimits.max_header_bytes, "the header limit holds");
    fuzz::require(!p.request.target.empty() && p.request.target.front() == '/', "the target is an absolute path");
    fuzz::require(p.request.target.starts_with(p.request.path) &&
                      (p.request.path.size() == p.request.target.size() ||
                       p.request.target[p.request.path.size()] == '?'),
                  "the path is the target up to its query");
    for (const auto& [name, value] : p.request.headers) {
      fuzz::require(is_lower(name), "header names are lower-cased", name);
      fuzz::require(value.find("\r\n") == std::string_view::npos, "a header value holds no line break");
    }
    // The request was complete only once its last byte arrived.
    const HttpParse shorter = monitor::parse_http_request(buffer.substr(0, p.consumed - 1), kLimits);
    fuzz::require(shorter.status != HttpParse::Status::complete, "a request's prefix is not itself a request");
    buffer.remove_prefix(p.consumed);
  }
}
