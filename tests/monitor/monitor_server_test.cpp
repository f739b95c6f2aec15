// The monitor server's budgets and browser-grade checks over loopback: the pools of connections
// with and without the token (slowloris cannot lock the operator out), the header timeout, the
// history replayed to clients that join (bytes and count), Host and Origin, CSRF-safe commands, the
// Foxglove sessionId, and malformed Foxglove client messages (docs/monitor.md, "Budgets", "Host
// and Origin"). Waits are bounded; nothing asserts a timing figure.
#include "tripodal/monitor/monitor_server.hpp"

#include <catch2/catch.hpp>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "loopback_client.hpp"
#include "tripodal_monitor_internal/wire.hpp"

using namespace tripodal::monitor;
using namespace tripodal::monitor::test;

namespace {

constexpr const char* kToken = "t0ken-for-tests";

std::string request(const std::string& method, const std::string& target, const std::string& headers, const std::string& body = {}) {
  std::string r = method + " " + target + " HTTP/1.1\r\n" + headers;
  if (!body.empty() || method == "POST") r += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  return r + "\r\n" + body;
}

std::string ping(std::uint16_t port) {
  Client c(port);
  c.send(request("GET", "/api/ping", "Host: 127.0.0.1:" + std::to_string(port) + "\r\nAuthorization: Bearer " + kToken + "\r\n"));
  return c.read_all();
}

// Reads the answer to a WebSocket upgrade (101 and the first frame, or a refusal).
std::string upgrade_answer(Client& c) {
  return c.read_until([](const std::string& b) {
    const std::size_t head = b.find("\r\n\r\n");
    return head != std::string::npos && (!b.starts_with("HTTP/1.1 101") || !server_frames(std::string_view(b).substr(head + 4)).empty());
  });
}

// What follows the head of an HTTP answer (nothing while the head is incomplete).
std::string after_head(const std::string& http) {
  const std::size_t head = http.find("\r\n\r\n");
  return head == std::string::npos ? std::string() : http.substr(head + 4);
}

}  // namespace

TEST_CASE("Half-open connections without the token cannot lock the operator out, and close at the header timeout",
          "[monitor][server][budgets][threads]") {
  // Finding 4: 40 half-open tokenless connections (more than the 32 clients of the old shared
  // pool) answered every operator request with 503.
  MonitorServer server(MonitorServerOptions{.token = kToken, .header_timeout_s = 1.0, .max_unauthenticated = 8});
  server.start();
  const std::string half = "GET / HTTP/1.1\r\nHost: 127.0.0.1\r\nX-Slow: ";
  std::vector<std::unique_ptr<Client>> slow;
  for (int i = 0; i < 40; ++i) {
    slow.push_back(std::make_unique<Client>(server.port()));
    slow.back()->send(half);
    if (i % 10 == 9) {  // the operator, between the waves
      const std::string r = ping(server.port());
      CHECK_THAT(r, Catch::StartsWith("HTTP/1.1 200 OK"));
      CHECK_THAT(r, Catch::EndsWith(R"({"ok":true})"));
    }
  }
  // Every half-open connection is closed: evicted by a newer one or at the header timeout.
  for (auto& c : slow) {
    c->read_all();
    CHECK(c->closed());
  }
  REQUIRE(wait_for([&] { return server.stats().unauthenticated == 0; }));
  const MonitorStats s = server.stats();
  CHECK(s.evicted + s.header_timeouts == 40);
  CHECK(s.header_timeouts >= 1);  // the last wave was not evicted: it timed out
  CHECK(s.busy == 0);
}

TEST_CASE("The pool of connections without the token holds its limit, and one past it evicts the oldest",
          "[monitor][server][budgets][threads]") {
  MonitorServer server(MonitorServerOptions{.token = kToken, .header_timeout_s = 600.0, .max_unauthenticated = 4});
  server.start();
  std::vector<std::unique_ptr<Client>> slow;
  for (int i = 0; i < 4; ++i) {
    slow.push_back(std::make_unique<Client>(server.port()));
    slow.back()->send("GET / HTTP/1.1\r\n");
  }
  REQUIRE(wait_for([&] { return server.stats().unauthenticated == 4; }));
  CHECK(server.stats().evicted == 0);  // at the limit: all kept
  for (auto& c : slow) {
    c->read_until([](const std::string&) { return false; }, std::chrono::milliseconds(20));
    CHECK_FALSE(c->closed());
  }
  slow.push_back(std::make_unique<Client>(server.port()));  // one past it
  REQUIRE(wait_for([&] { return server.stats().evicted == 1; }));
  slow.front()->read_all();
  CHECK(slow.front()->closed());  // the oldest went
  for (std::size_t i = 1; i < slow.size(); ++i) {
    slow[i]->read_until([](const std::string&) { return false; }, std::chrono::milliseconds(20));
    CHECK_FALSE(slow[i]->closed());
  }
  // The newest still completes its request.
  slow.back()->send("GET / HTTP/1.1\r\nHost: localhost\r\n\r\n");
  CHECK_THAT(slow.back()->read_all(), Catch::StartsWith("HTTP/1.1 200 OK"));
}

TEST_CASE("Clients with the token and readers without it have pools of their own, each held at its limit",
          "[monitor][server][budgets][threads]") {
  MonitorServer server(MonitorServerOptions{.token = kToken, .read_without_token = true, .max_clients = 2, .max_open_readers = 2});
  server.start();
  std::vector<std::unique_ptr<Client>> clients;
  auto open = [&](const std::string& path) {
    clients.push_back(std::make_unique<Client>(server.port()));
    clients.back()->send(ws_upgrade(path));
    return upgrade_answer(*clients.back());
  };
  CHECK_THAT(open("/ws"), Catch::StartsWith("HTTP/1.1 101"));  // readers without the token: at the limit
  CHECK_THAT(open("/ws"), Catch::StartsWith("HTTP/1.1 101"));
  const std::string third = open("/ws");  // one past it
  CHECK_THAT(third, Catch::StartsWith("HTTP/1.1 503"));
  CHECK_THAT(third, Catch::Contains("too many read-only clients without the token"));
  // The readers did not take the operator's places.
  CHECK_THAT(open(std::string("/ws?token=") + kToken), Catch::StartsWith("HTTP/1.1 101"));
  CHECK_THAT(open(std::string("/ws?token=") + kToken), Catch::StartsWith("HTTP/1.1 101"));
  CHECK_THAT(open(std::string("/ws?token=") + kToken), Catch::StartsWith("HTTP/1.1 503"));
  CHECK(server.stats().busy == 2);
  REQUIRE(wait_for([&] { return server.stats().clients == 4; }));
}

TEST_CASE("The history replayed to a client that joins fits its queue however long the notes are",
          "[monitor][server][budgets][threads]") {
  // Finding 5: 150 life cycle notes of 60 KB (9 MB) overflowed the 8 MiB queue of every client
  // that joined later, and each was dropped.
  MonitorServer server(MonitorServerOptions{.token = kToken});
  const auto life = server.advertise("/lifecycle", "tripodal.LifecycleEntry", "{}", Delivery::event);
  server.start();
  const std::string note = R"({"kind":"note","text":")" + std::string(60000, 'a') + "\"}";
  for (int i = 0; i < 150; ++i) server.publish(life, i, note);
  REQUIRE(wait_for([&] { return server.stats().history_entries > 0 && server.stats().published == 150; }));
  REQUIRE(wait_for([&] { return server.stats().history_bytes > (2U << 20U) - 61000; }));
  const MonitorStats kept = server.stats();
  CHECK(kept.history_bytes <= (2U << 20U));
  CHECK(kept.history_entries < 150);
  for (int join = 0; join < 3; ++join) {
    Client c(server.port());
    c.send(ws_upgrade(std::string("/ws?token=") + kToken));
    const std::string marker = "\"n\":" + std::to_string(join);
    server.publish(life, 1000, "{\"n\":" + std::to_string(join) + "}");
    const std::string live = c.read_until([&](const std::string& b) { return b.find(marker) != std::string::npos; });
    CHECK_THAT(live, Catch::Contains(marker));  // still connected: the replay and a live event came
    CHECK_FALSE(c.closed());
  }
  CHECK(server.stats().slow_disconnects == 0);
}

TEST_CASE("The history is held at its byte and count budgets, and one past either drops the oldest",
          "[monitor][server][budgets][threads]") {
  const auto body = [](int n) { return R"({"n":)" + std::to_string(n) + R"(,"pad":")" + std::string(1000, 'p') + "\"}"; };
  std::size_t per = 0;  // one entry as a page client receives it
  {
    MonitorServer probe(MonitorServerOptions{.token = kToken});
    const auto life = probe.advertise("/lifecycle", "tripodal.LifecycleEntry", "{}", Delivery::event);
    probe.start();
    probe.publish(life, 1.0, body(1));
    REQUIRE(wait_for([&] { return probe.stats().history_entries == 1; }));
    per = probe.stats().history_bytes;
    CHECK(per == ws_frame(WsOpcode::text, R"({"topic":"/lifecycle","t":1.000000,"data":)" + body(1) + "}").size());
  }
  auto replay = [](MonitorServer& server) {
    Client c(server.port());
    c.send(ws_upgrade(std::string("/ws?token=") + kToken));
    std::vector<int> ns;
    const std::string got = c.read_until([](const std::string& b) { return b.find("\"n\":9") != std::string::npos; }, std::chrono::seconds(10));
    for (const WsFrame& f : server_frames(after_head(got))) {
      const auto j = nlohmann::json::parse(f.payload);
      if (j["topic"] == "/lifecycle") ns.push_back(j["data"]["n"].get<int>());
    }
    return ns;
  };
  SECTION("bytes") {
    MonitorServer server(MonitorServerOptions{.token = kToken, .history = 100, .max_history_bytes = 3 * per});
    const auto life = server.advertise("/lifecycle", "tripodal.LifecycleEntry", "{}", Delivery::event);
    server.start();
    for (int n = 1; n <= 3; ++n) server.publish(life, 1.0, body(n));
    REQUIRE(wait_for([&] { return server.stats().history_entries == 3; }));
    CHECK(server.stats().history_bytes == 3 * per);  // at the limit: all kept
    server.publish(life, 1.0, body(4));              // one past it
    server.publish(life, 1.0, R"({"n":9})");
    REQUIRE(wait_for([&] { return server.stats().history_bytes < 3 * per; }));  // both taken
    CHECK(server.stats().history_entries == 3);
    CHECK(replay(server) == std::vector<int>{3, 4, 9});
    CHECK(server.stats().history_bytes <= 3 * per);
  }
  SECTION("count") {
    MonitorServer server(MonitorServerOptions{.token = kToken, .history = 3});
    const auto life = server.advertise("/lifecycle", "tripodal.LifecycleEntry", "{}", Delivery::event);
    server.start();
    for (int n = 1; n <= 3; ++n) server.publish(life, 1.0, body(n));
    REQUIRE(wait_for([&] { return server.stats().history_entries == 3; }));
    server.publish(life, 1.0, R"({"n":9})");
    REQUIRE(wait_for([&] { return server.stats().history_bytes < 3 * per; }));
    CHECK(server.stats().history_entries == 3);
    CHECK(replay(server) == std::vector<int>{2, 3, 9});
  }
  SECTION("a message longer than the whole budget is sent but not kept") {
    MonitorServer server(MonitorServerOptions{.token = kToken, .max_history_bytes = per - 1});
    const auto life = server.advertise("/lifecycle", "tripodal.LifecycleEntry", "{}", Delivery::event);
    server.start();
    server.publish(life, 1.0, body(1));
    server.publish(life, 1.0, R"({"n":9})");
    REQUIRE(wait_for([&] { return server.stats().history_not_kept == 1 && server.stats().history_entries == 1; }));
    CHECK(replay(server) == std::vector<int>{9});
  }
  SECTION("a budget the queue of a joining client could not hold is refused") {
    REQUIRE_THROWS_WITH(MonitorServer(MonitorServerOptions{.max_event_bytes = 1000, .max_history_bytes = 501}),
                        Catch::Contains("max_history_bytes 501: expected at most half of max_event_bytes (1000)"));
    REQUIRE_THROWS_WITH(MonitorServer(MonitorServerOptions{.header_timeout_s = 0.0}), Catch::Contains("header_timeout_s"));
    REQUIRE_THROWS_WITH(MonitorServer(MonitorServerOptions{.max_unauthenticated = 0}), Catch::Contains("max_unauthenticated"));
  }
}

TEST_CASE("Host names the server: loopback, IP literals and allowed names, and Origin must be the page's own", "[monitor][wire]") {
  const std::vector<std::string> none;
  CHECK(host_allowed("127.0.0.1:8765", none));
  CHECK(host_allowed("127.0.0.1", none));
  CHECK(host_allowed("localhost:8765", none));
  CHECK(host_allowed("LocalHost", none));
  CHECK(host_allowed("[::1]:8765", none));
  CHECK(host_allowed("192.168.1.20:8765", none));  // an address literal cannot be rebound
  CHECK_FALSE(host_allowed("evil.example:8765", none));
  CHECK_FALSE(host_allowed("localhost.evil.example", none));
  CHECK_FALSE(host_allowed("robot.local:8765", none));
  CHECK(host_allowed("Robot.Local:8765", {"robot.local"}));
  CHECK_FALSE(host_allowed("127.0.0.1:port", none));
  CHECK_FALSE(host_allowed("127.0.0.1:", none));
  CHECK_FALSE(host_allowed("", none));
  CHECK_FALSE(host_allowed("[::1", none));
  CHECK_FALSE(host_allowed("[evil]:80", none));

  CHECK(same_origin("http://127.0.0.1:8765", "127.0.0.1:8765"));
  CHECK(same_origin("HTTPS://LOCALHOST:8765", "localhost:8765"));
  CHECK_FALSE(same_origin("http://127.0.0.1:8766", "127.0.0.1:8765"));
  CHECK_FALSE(same_origin("http://127.0.0.1:8765/", "127.0.0.1:8765"));
  CHECK_FALSE(same_origin("null", "127.0.0.1:8765"));
  CHECK_FALSE(same_origin("http://", ""));
  CHECK(media_type("Application/JSON; charset=utf-8") == "application/json");
  CHECK(media_type("text/plain") == "text/plain");
}

TEST_CASE("Requests a page of another site could make are refused: rebound Host, foreign Origin, form posts",
          "[monitor][server][browser][threads]") {
  MonitorServer server(MonitorServerOptions{.token = kToken, .read_without_token = true, .allowed_hosts = {"robot.local"},
                                            .allowed_origins = {"https://app.foxglove.dev"}});
  server.start();
  const std::string port = std::to_string(server.port());
  const std::string own = "Host: 127.0.0.1:" + port + "\r\n";
  const std::string auth = std::string("Authorization: Bearer ") + kToken + "\r\n";
  const std::string json = "Content-Type: application/json\r\n";
  const std::string pause = R"({"op":"pause"})";
  auto send = [&](const std::string& r) {
    Client c(server.port());
    c.send(r);
    return c.read_all();
  };

  // DNS rebinding: a name the operator did not allow, even with the token.
  const std::string rebound = send(request("GET", "/", "Host: evil.example:" + port + "\r\n"));
  CHECK_THAT(rebound, Catch::StartsWith("HTTP/1.1 421 Misdirected Request"));
  CHECK_THAT(send(request("POST", "/api/command", "Host: evil.example:" + port + "\r\n" + auth + json, pause)),
             Catch::StartsWith("HTTP/1.1 421"));
  CHECK_THAT(send(request("GET", "/", "Host: robot.local:" + port + "\r\n")), Catch::StartsWith("HTTP/1.1 200"));
  CHECK_THAT(send(request("GET", "/", "Host: localhost:" + port + "\r\n")), Catch::StartsWith("HTTP/1.1 200"));

  // Commands from another origin, even carrying the token; a form's content types; the token in
  // the address (a form or a simple request could carry it there).
  const std::string foreign = send(request("POST", "/api/command", own + "Origin: http://127.0.0.1:9\r\n" + auth + json, pause));
  CHECK_THAT(foreign, Catch::StartsWith("HTTP/1.1 403 Forbidden"));
  CHECK_THAT(foreign, Catch::Contains("Origin is not this server's page"));
  CHECK_THAT(send(request("POST", "/api/command", own + "Origin: null\r\n" + auth + json, pause)), Catch::StartsWith("HTTP/1.1 403"));
  for (const std::string type : {"text/plain", "application/x-www-form-urlencoded", "multipart/form-data; boundary=x"}) {
    CHECK_THAT(send(request("POST", "/api/command", own + auth + "Content-Type: " + type + "\r\n", pause)),
               Catch::StartsWith("HTTP/1.1 415 Unsupported Media Type"));
  }
  CHECK_THAT(send(request("POST", std::string("/api/command?token=") + kToken, own + json, pause)), Catch::StartsWith("HTTP/1.1 401"));
  CHECK(server.take_requests().empty());  // nothing reached the robot

  // The page's own origin, and a client that is not a browser (no Origin), are served.
  for (const std::string& extra : {"Origin: http://127.0.0.1:" + port + "\r\n", std::string()}) {
    Client c(server.port());
    c.send(request("POST", "/api/command", own + extra + auth + json, pause));
    std::vector<OperatorRequest> got;
    REQUIRE(wait_for([&] {
      got = server.take_requests();
      return !got.empty();
    }));
    server.answer(got[0].id, 200, R"({"paused":true})");
    CHECK_THAT(c.read_all(), Catch::StartsWith("HTTP/1.1 200"));
  }

  // Streams: read-open lets any non-browser client and the page's own origin watch, never another
  // site's page (with or without the token).
  auto stream = [&](const std::string& origin, const std::string& path) {
    Client c(server.port());
    std::string up = ws_upgrade(path);
    const std::string loopback = "Host: 127.0.0.1\r\n";
    up.replace(up.find(loopback), loopback.size(), own);  // with the port: the Origin is compared with it
    if (!origin.empty()) up.insert(up.size() - 2, "Origin: " + origin + "\r\n");
    c.send(up);
    return upgrade_answer(c);
  };
  CHECK_THAT(stream("http://evil.example", "/ws"), Catch::StartsWith("HTTP/1.1 403"));
  CHECK_THAT(stream("http://evil.example", std::string("/ws?token=") + kToken), Catch::StartsWith("HTTP/1.1 403"));
  CHECK_THAT(stream("http://127.0.0.1:" + port, "/ws"), Catch::StartsWith("HTTP/1.1 101"));
  CHECK_THAT(stream("", "/ws"), Catch::StartsWith("HTTP/1.1 101"));
  CHECK_THAT(stream("https://app.foxglove.dev", "/ws"), Catch::StartsWith("HTTP/1.1 101"));
  CHECK(server.stats().refused_origin == 4);
  CHECK(server.stats().refused_host == 2);
}

TEST_CASE("Foxglove's sessionId tells nothing of the token", "[monitor][server][foxglove][threads]") {
  std::vector<std::string> ids;
  for (int i = 0; i < 2; ++i) {
    MonitorServer server(MonitorServerOptions{.token = kToken, .read_without_token = true});
    server.start();
    Client c(server.port());
    c.send(ws_upgrade("/ws", "foxglove.websocket.v1"));  // read-open: no token needed to see it
    const std::string got = upgrade_answer(c);
    const auto frames = server_frames(after_head(got));
    REQUIRE(!frames.empty());
    const std::string id = nlohmann::json::parse(frames[0].payload)["sessionId"];
    CHECK(id.size() == 16);
    for (std::size_t k = 0; k + 4 <= std::string(kToken).size(); ++k) CHECK(id.find(std::string(kToken).substr(k, 4)) == std::string::npos);
    ids.push_back(id);
  }
  CHECK(ids[0] != ids[1]);
}

TEST_CASE("Malformed or wrong-typed Foxglove client messages get an error status, never a crash", "[monitor][server][foxglove][threads]") {
  MonitorServer server(MonitorServerOptions{.token = kToken});
  const auto pose = server.advertise("/pose", "foxglove.PoseInFrame", "{}", Delivery::bulk);
  server.start();
  Client c(server.port());
  c.send(ws_upgrade(std::string("/?token=") + kToken, "foxglove.websocket.v1"));
  std::string got = c.read_until([](const std::string& b) { return server_frames(after_head(b)).size() >= 2; });
  REQUIRE(server_frames(after_head(got)).size() == 2);
  c.consume(got.size());

  // Every JSON type; `good` says which are right where a value is expected.
  const std::vector<std::string> values = {"null", "true", "false", "-1", "1.5", "4294967296", "\"7\"", "[]", "[1]", "{}", R"({"id":1})"};
  std::vector<std::string> bad;
  auto wrong = [&](const std::string& tmpl, const std::function<bool(const std::string&)>& good) {
    for (const std::string& v : values) {
      if (!good(v)) bad.push_back(std::regex_replace(tmpl, std::regex("@"), v));
    }
  };
  const auto never = [](const std::string&) { return false; };
  const auto u32 = [](const std::string&) { return false; };  // none of `values` is a whole number below 2^32
  const auto array = [](const std::string& v) { return v.starts_with('['); };
  const auto object = [](const std::string& v) { return v.starts_with('{'); };
  wrong("@", object);  // the message itself
  wrong(R"({"op":@})", never);
  wrong(R"({"op":"subscribe","subscriptions":@})", array);
  wrong(R"({"op":"subscribe","subscriptions":[@]})", object);
  wrong(R"({"op":"subscribe","subscriptions":[{"id":@,"channelId":1}]})", u32);
  wrong(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":@}]})", u32);
  wrong(R"({"op":"unsubscribe","subscriptionIds":@})", array);
  wrong(R"({"op":"unsubscribe","subscriptionIds":[@]})", u32);
  for (const std::string op : {"advertise", "unadvertise", "getParameters", "setParameters", "subscribeParameterUpdates",
                               "unsubscribeParameterUpdates", "callService", "subscribeConnectionGraph", "unsubscribeConnectionGraph",
                               "fetchAsset", "no-such-op"}) {
    wrong(R"({"op":")" + op + R"(","channels":@,"parameters":@,"names":@,"id":@})", never);
  }
  bad.push_back("{");
  bad.push_back(R"({"op":"subscribe"})");
  bad.push_back(R"({"op":"subscribe","subscriptions":[{"channelId":1}]})");
  bad.push_back(R"({"op":"subscribe","subscriptions":[{"id":1}]})");
  bad.push_back(R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":4294967297}]})");  // not channel 1 cut to 32 bits
  bad.push_back(R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":99}]})");
  bad.push_back(R"({"op":"unsubscribe"})");
  for (const std::string& m : bad) c.send(ws_client_frame(WsOpcode::text, m));
  c.send(ws_client_frame(WsOpcode::binary, std::string("\x01\x00\x00\x00\x00", 5)));
  const std::size_t expected = bad.size() + 1;
  std::size_t statuses = 0;
  got = c.read_until([&](const std::string& b) {
    statuses = 0;
    for (const WsFrame& f : server_frames(b)) statuses += f.payload.find(R"("op":"status")") != std::string::npos ? 1 : 0;
    return statuses >= expected;
  });
  CHECK(statuses == expected);
  for (const WsFrame& f : server_frames(got)) {
    const auto j = nlohmann::json::parse(f.payload);
    CHECK(j["op"] == "status");
    CHECK(j["level"] == 2);
    CHECK(!j["message"].get<std::string>().empty());
  }
  CHECK_THAT(got, Catch::Contains(R"(subscriptions[0].channelId: expected a whole number 0..4294967295, got a number over 4294967295)"));
  CHECK_THAT(got, Catch::Contains("op 'advertise' is not offered"));
  CHECK(server.stats().client_errors == expected);
  c.consume(got.size());

  // Still served: a good subscription receives the pose, and nothing leaked to subscription 5.
  c.send(ws_client_frame(WsOpcode::text, R"({"op":"subscribe","subscriptions":[{"id":3,"channelId":)" + std::to_string(pose) + "}]}"));
  std::string data;
  REQUIRE(wait_for([&] {
    server.publish(pose, 1.0, R"({"x":1})");
    data = c.read_until([](const std::string& b) { return !server_frames(b).empty(); }, std::chrono::milliseconds(50));
    return !server_frames(data).empty();
  }));
  const WsFrame f = server_frames(data).front();
  REQUIRE(f.opcode == WsOpcode::binary);
  CHECK(static_cast<std::uint8_t>(f.payload[1]) == 3);
  c.consume(data.size());

  // A control frame over 125 bytes is a protocol error: closed with 1002.
  c.send(ws_client_frame(WsOpcode::ping, std::string(126, 'p')));
  got = c.read_all();
  CHECK(c.closed());
  CHECK_THAT(got, Catch::Contains("control frame"));
}

TEST_CASE("Bytes that are not UTF-8 in a request are quoted in the refusal without bringing the server down", "[monitor][server][threads]") {
  MonitorServer server(MonitorServerOptions{.token = kToken});
  server.start();
  {
    Client c(server.port());
    c.send("\xff\xfe\xfd\r\n\r\n");
    const std::string r = c.read_all();
    CHECK_THAT(r, Catch::StartsWith("HTTP/1.1 400"));
    CHECK(nlohmann::json::parse(after_head(r)).contains("error"));
  }
  {
    Client c(server.port());
    c.send(request("POST", "/api/command", std::string("Content-Type: \xff\xfe\r\nAuthorization: Bearer ") + kToken + "\r\n", "{}"));
    CHECK_THAT(c.read_all(), Catch::StartsWith("HTTP/1.1 415"));
  }
  CHECK_THAT(ping(server.port()), Catch::StartsWith("HTTP/1.1 200"));  // still serving
}
