// The monitor area: wire formats (HTTP, WebSocket handshake and frames), the server over loopback
// (page, token, limits, per-client queues) and a robot on simulated time with a client that does
// not read.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <catch2/catch.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <memory>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <thread>

#include "../navi/navi_test_util.hpp"
#include "loopback_client.hpp"
#include "test_hri_module.hpp"
#include "tripodal/board/actuator_behaviors.hpp"
#include "tripodal/board/board_monitor.hpp"
#include "tripodal/builtin/register_all.hpp"
#include "tripodal/monitor/monitor_server.hpp"
#include "tripodal/monitor/robot_monitor.hpp"
#include "tripodal/navi/map_io.hpp"
#include "tripodal/robot/robot.hpp"
#include "tripodal/sim/sim_board.hpp"
#include "tripodal/sim/sim_hardware.hpp"
#include "tripodal_monitor_internal/operator_request.hpp"
#include "tripodal_monitor_internal/wire.hpp"

using namespace tripodal;
using namespace tripodal::monitor;
using namespace tripodal::monitor::test;

// Under LeakSanitizer: the caches Graphviz (libgvc) and fontconfig keep until the process ends are
// theirs, not leaks of the monitor (their stacks end in those libraries).
extern "C" const char* __lsan_default_suppressions();
extern "C" const char* __lsan_default_suppressions() { return "leak:libgvc.so\nleak:libfontconfig.so\n"; }

namespace {

std::string hex(const std::array<std::uint8_t, 20>& d) {
  std::string out;
  static constexpr char kHex[] = "0123456789abcdef";
  for (const auto b : d) {
    out += kHex[b >> 4];
    out += kHex[b & 0xF];
  }
  return out;
}

// The PSR-2 demo robot on the simulator, in the workspace world.
struct Psr2 {
  RobotPlugins plugins;  // the robot keeps using them
  SimClock clock;
  std::unique_ptr<Robot> robot;
  Psr2() {
    const std::filesystem::path configs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";
    register_all(plugins, std::make_shared<sim::World>(sim::load_world(configs / "worlds/workspace.yaml")));
    robot = Robot::assemble(load_robot_profile(configs / "robots/psr2.yaml"), plugins, clock);
  }
};

// An operator's command (with the test token unless `auth` says otherwise); the robot's thread
// (here: the test's, through watch.update(), after `between`) answers between periods. Returns
// the whole HTTP answer.
std::string post_command(MonitorServer& server, RobotMonitor& watch, const std::string& body,
                         const std::string& auth = "Authorization: Bearer t0ken-for-tests\r\n",
                         const std::function<void()>& between = {}) {
  Client c(server.port());
  c.send("POST /api/command HTTP/1.1\r\n" + auth + "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body);
  std::string answer;
  REQUIRE(wait_for([&] {
    if (between) between();
    watch.update();
    answer = c.read_until([](const std::string& b) { return b.find("\r\n\r\n{") != std::string::npos && b.back() == '}'; },
                          std::chrono::milliseconds(20));
    return !answer.empty() && answer.back() == '}';
  }));
  return answer;
}

}  // namespace

TEST_CASE("SHA-1, base64 and the WebSocket accept key follow their standards", "[monitor][wire]") {
  CHECK(hex(sha1("abc")) == "a9993e364706816aba3e25717850c26c9cd0d89d");
  CHECK(hex(sha1("")) == "da39a3ee5e6b4b0d3255bfef95601890afd80709");
  CHECK(hex(sha1(std::string(1000, 'a'))) == "291e9a6c66994949b57ba5e650361e98fc36b1ba");
  CHECK(base64("foob") == "Zm9vYg==");
  CHECK(base64("fooba") == "Zm9vYmE=");
  // RFC 6455 section 1.3.
  CHECK(websocket_accept("dGhlIHNhbXBsZSBub25jZQ==") == "s3pPLMBiTxaQ9kYGzzhZRbK+xOo=");
  CHECK(constant_time_equal("abc", "abc"));
  CHECK_FALSE(constant_time_equal("abc", "abd"));
  CHECK_FALSE(constant_time_equal("abc", "abcd"));
}

TEST_CASE("HTTP requests are read with limits and located errors", "[monitor][wire]") {
  const std::string req = "POST /api/command?token=ab HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 4\r\nX-A:  v \r\n\r\nbody";
  CHECK(parse_http_request(req.substr(0, 20)).status == HttpParse::Status::incomplete);
  CHECK(parse_http_request(req.substr(0, req.size() - 1)).status == HttpParse::Status::incomplete);
  const HttpParse p = parse_http_request(req);
  REQUIRE(p.status == HttpParse::Status::complete);
  CHECK(p.consumed == req.size());
  CHECK(p.request.method == "POST");
  CHECK(p.request.path == "/api/command");
  CHECK(p.request.query("token") == std::optional<std::string_view>("ab"));
  CHECK(p.request.header("x-a") == std::optional<std::string_view>("v"));
  CHECK(p.request.body == "body");

  HttpLimits small{.max_header_bytes = 64, .max_body_bytes = 3};
  CHECK(parse_http_request(req, small).status == HttpParse::Status::headers_too_large);
  CHECK(parse_http_request(std::string(100, 'x'), small).status == HttpParse::Status::headers_too_large);
  CHECK(parse_http_request(req, HttpLimits{.max_header_bytes = 1024, .max_body_bytes = 3}).status == HttpParse::Status::body_too_large);

  const HttpParse bad = parse_http_request("GARBAGE\r\n\r\n");
  CHECK(bad.status == HttpParse::Status::bad_request);
  CHECK_THAT(bad.error, Catch::Contains("request line 'GARBAGE': expected METHOD TARGET HTTP/1.x"));
  CHECK_THAT(parse_http_request("GET /x HTTP/1.1\r\nContent-Length: -1\r\n\r\n").error,
             Catch::Contains("Content-Length '-1': expected a decimal byte count"));
  CHECK_THAT(parse_http_request("GET x HTTP/1.1\r\n\r\n").error, Catch::Contains("target 'x': expected an absolute path"));
  CHECK_THAT(parse_http_request("GET /x HTTP/1.1\r\nno colon\r\n\r\n").error, Catch::Contains("header 'no colon': expected NAME: VALUE"));
}

TEST_CASE("WebSocket frames: client frames must be masked and fit the limit", "[monitor][wire]") {
  for (const std::size_t n : {std::size_t{5}, std::size_t{300}, std::size_t{70000}}) {
    const std::string payload(n, 'q');
    const std::string f = ws_client_frame(WsOpcode::text, payload);
    CHECK(parse_ws_frame(f.substr(0, f.size() - 1), 100000).status == WsParse::Status::incomplete);
    const WsParse p = parse_ws_frame(f, 100000);
    REQUIRE(p.status == WsParse::Status::complete);
    CHECK(p.consumed == f.size());
    CHECK(p.frame.payload == payload);
  }
  const WsParse unmasked = parse_ws_frame(ws_frame(WsOpcode::text, "hi"));
  CHECK(unmasked.status == WsParse::Status::error);
  CHECK_THAT(unmasked.error, Catch::Contains("client frame not masked"));
  const WsParse big = parse_ws_frame(ws_client_frame(WsOpcode::binary, std::string(2000, 'x')), 1000);
  CHECK_THAT(big.error, Catch::Contains("frame of 2000 bytes: the limit is 1000"));
}

TEST_CASE("server_options reads PORT or ADDR:PORT and the token file", "[monitor]") {
  CHECK(server_options("8765").address == "127.0.0.1");
  CHECK(server_options("8765").port == 8765);
  CHECK(server_options("0.0.0.0:80").address == "0.0.0.0");
  REQUIRE_THROWS_WITH(server_options("http"), Catch::Contains("monitor port 'http' in 'http': expected [ADDR:]PORT"));
  REQUIRE_THROWS_WITH(server_options("99999"), Catch::Contains("PORT in 0..65535"));
  REQUIRE_THROWS_WITH(server_options("localhost:80"), Catch::Contains("monitor address 'localhost': expected an IPv4 address"));
  const auto dir = std::filesystem::temp_directory_path() / "tripodal_monitor_test";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "short") << "abc\n";
  REQUIRE_THROWS_WITH(server_options("0", dir / "short"), Catch::Contains("short:1:1: monitor token: expected at least 8 printable"));
  std::ofstream(dir / "good") << "s3cret-token-42\n";
  CHECK(server_options("0", dir / "good").token == "s3cret-token-42");
  REQUIRE_THROWS_WITH(server_options("0", dir / "missing"), Catch::Contains("missing': cannot be read"));
}

TEST_CASE("The server serves the page, refuses without the token and hands commands to the robot's thread", "[monitor][server][threads]") {
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  server.start();
  REQUIRE(server.port() != 0);
  CHECK(server.url() == "http://127.0.0.1:" + std::to_string(server.port()) + "/?token=t0ken-for-tests");

  {  // the page
    Client c(server.port());
    c.send("GET / HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    const std::string r = c.read_all();
    CHECK_THAT(r, Catch::StartsWith("HTTP/1.1 200 OK"));
    CHECK_THAT(r, Catch::Contains("<title>tripodal monitor</title>"));
    CHECK_THAT(r, !Catch::Contains("src=\"http"));  // nothing from the network
  }
  {  // no file serving
    Client c(server.port());
    c.send("GET /../../etc/passwd HTTP/1.1\r\n\r\n");
    CHECK_THAT(c.read_all(), Catch::StartsWith("HTTP/1.1 404"));
  }
  const std::string body = R"({"op":"task","text":"clean the room 3211"})";
  auto post = [&](const std::string& auth, const std::string& b) {
    return "POST /api/command HTTP/1.1\r\nContent-Type: application/json\r\n" + auth + "Content-Length: " + std::to_string(b.size()) +
           "\r\n\r\n" + b;
  };
  for (const std::string& auth : {std::string{}, std::string("Authorization: Bearer wrong\r\n")}) {
    Client c(server.port());
    c.send(post(auth, body));
    const std::string r = c.read_all();
    CHECK_THAT(r, Catch::StartsWith("HTTP/1.1 401 Unauthorized"));
    CHECK_THAT(r, Catch::Contains("missing or wrong token"));
  }
  CHECK(server.take_requests().empty());  // nothing reached the robot
  CHECK(server.stats().unauthorized == 2);
  {
    Client c(server.port());
    c.send(post("Authorization: Bearer t0ken-for-tests\r\n", std::string(70000, ' ')));
    CHECK_THAT(c.read_all(), Catch::StartsWith("HTTP/1.1 413"));
  }
  {
    Client c(server.port());
    c.send(post("Authorization: Bearer t0ken-for-tests\r\n", "[1,2]"));
    CHECK_THAT(c.read_all(), Catch::Contains("expected a JSON object with a string \\\"op\\\""));
  }
  {  // accepted: the robot's thread answers it
    Client c(server.port());
    c.send(post("Authorization: Bearer t0ken-for-tests\r\n", body));
    std::vector<OperatorRequest> requests;
    REQUIRE(wait_for([&] {
      auto r = server.take_requests();
      requests.insert(requests.end(), r.begin(), r.end());
      return !requests.empty();
    }));
    REQUIRE(requests.size() == 1);
    CHECK(requests[0].body == body);
    server.answer(requests[0].id, 200, R"({"accepted":true,"text":"ok"})");
    const std::string r = c.read_all();
    CHECK_THAT(r, Catch::StartsWith("HTTP/1.1 200 OK"));
    CHECK_THAT(r, Catch::EndsWith(R"({"accepted":true,"text":"ok"})"));
  }
  {  // the stream needs the token too (unless opened read-only by the operator)
    Client c(server.port());
    c.send(ws_upgrade("/ws"));
    CHECK_THAT(c.read_all(), Catch::StartsWith("HTTP/1.1 401"));
  }
}

TEST_CASE("Foxglove clients get serverInfo, advertise and binary messageData of their subscriptions", "[monitor][server][foxglove][threads]") {
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  const auto pose = server.advertise("/pose", "foxglove.PoseInFrame", R"({"type":"object"})", Delivery::bulk);
  server.advertise("/lifecycle", "tripodal.LifecycleEntry", R"({"type":"object"})", Delivery::event);
  server.start();
  Client c(server.port());
  c.send(ws_upgrade("/?token=t0ken-for-tests", "foxglove.websocket.v1"));
  std::string got = c.read_until([](const std::string& b) { return b.find("\"advertise\"") != std::string::npos && b.find("jsonschema\"}]}") != std::string::npos; });
  const std::size_t head = got.find("\r\n\r\n");
  REQUIRE(head != std::string::npos);
  CHECK_THAT(got.substr(0, head), Catch::Contains("Sec-WebSocket-Protocol: foxglove.websocket.v1"));
  CHECK_THAT(got.substr(0, head), Catch::Contains("Sec-WebSocket-Accept: s3pPLMBiTxaQ9kYGzzhZRbK+xOo="));
  auto frames = server_frames(std::string_view(got).substr(head + 4));
  REQUIRE(frames.size() == 2);
  const auto info = nlohmann::json::parse(frames[0].payload);
  CHECK(info["op"] == "serverInfo");
  CHECK(info["supportedEncodings"][0] == "json");
  const auto adv = nlohmann::json::parse(frames[1].payload);
  CHECK(adv["op"] == "advertise");
  REQUIRE(adv["channels"].size() == 2);
  CHECK(adv["channels"][0]["topic"] == "/pose");
  CHECK(adv["channels"][0]["schemaEncoding"] == "jsonschema");
  c.consume(got.size());

  c.send(ws_client_frame(WsOpcode::text, R"({"op":"subscribe","subscriptions":[{"id":7,"channelId":)" + std::to_string(pose) + "}]}"));
  // The subscription arrives on the server thread; publish until a message reaches the client.
  std::string data;
  REQUIRE(wait_for([&] {
    server.publish(pose, 1.5, R"({"x":1})");
    data = c.read_until([](const std::string& b) { return b.size() >= 2 + 13 + 7; }, std::chrono::milliseconds(50));
    return data.size() >= 2 + 13 + 7;
  }));
  const auto f = server_frames(data);
  REQUIRE(!f.empty());
  CHECK(f[0].opcode == WsOpcode::binary);
  REQUIRE(f[0].payload.size() == 13 + 7);
  CHECK(f[0].payload[0] == 0x01);                  // messageData
  CHECK(static_cast<std::uint8_t>(f[0].payload[1]) == 7);  // subscription id, little endian
  std::uint64_t ns = 0;
  for (int i = 7; i >= 0; --i) ns = (ns << 8) | static_cast<std::uint8_t>(f[0].payload[5 + static_cast<std::size_t>(i)]);
  CHECK(ns == 1'500'000'000U);
  CHECK(f[0].payload.substr(13) == R"({"x":1})");
}

TEST_CASE("A client that stops reading loses old bulk frames, and is let go rather than lose an event", "[monitor][server][threads]") {
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests", .max_bulk_frames = 4, .max_event_bytes = 1U << 20U, .send_buffer_bytes = 16384, .max_history_bytes = 256U << 10U});
  const auto scan = server.advertise("/laser", "foxglove.LaserScan", "{}", Delivery::bulk);
  const auto life = server.advertise("/lifecycle", "tripodal.LifecycleEntry", "{}", Delivery::event);
  server.start();
  Client sleeper(server.port(), 4096);
  sleeper.send(ws_upgrade("/ws?token=t0ken-for-tests"));
  REQUIRE(wait_for([&] { return server.stats().clients == 1; }));
  // Bulk: 4000 scans of 16 KiB, far more than the socket buffers hold. publish() only appends.
  const std::string payload = "\"" + std::string(16 * 1024, 's') + "\"";
  for (int i = 0; i < 4000; ++i) server.publish(scan, i, payload);
  REQUIRE(wait_for([&] { return server.stats().bulk_shed > 0; }));
  CHECK(server.stats().clients == 1);  // still connected: only bulk data was shed
  CHECK(server.stats().slow_disconnects == 0);
  // Events: they may not be dropped, so past 1 MiB queued the client goes.
  for (int i = 0; i < 200; ++i) server.publish(life, i, payload);
  REQUIRE(wait_for([&] { return server.stats().slow_disconnects == 1; }));
  CHECK(wait_for([&] { return server.stats().clients == 0; }));
}

TEST_CASE("A robot on simulated time runs the same with a monitor whose client does not read", "[monitor][robot][threads]") {
  auto run = [&](bool with_monitor, MonitorStats* stats) {
    Psr2 psr2;
    SimClock& clock = psr2.clock;
    Robot* robot = psr2.robot.get();
    std::unique_ptr<MonitorServer> server;
    std::unique_ptr<RobotMonitor> watch;
    std::unique_ptr<Client> sleeper;
    if (with_monitor) {
      server = std::make_unique<MonitorServer>(MonitorServerOptions{.token = "t0ken-for-tests", .max_bulk_frames = 4, .send_buffer_bytes = 16384});
      watch = std::make_unique<RobotMonitor>(*robot, clock, *server, RobotMonitorOptions{.min_interval_s = 0.0, .cleaned_interval_s = 0.0});
      server->start();
      sleeper = std::make_unique<Client>(server->port(), 4096);
      sleeper->send(ws_upgrade("/ws?token=t0ken-for-tests"));
      REQUIRE(wait_for([&] { return server->stats().clients == 1; }));
    }
    REQUIRE(robot->command("clean the room 3211").accepted);
    for (int i = 0; i < 600; ++i) {  // 60 s of simulated time, the monitor updated every 100 ms
      robot->run_for(std::chrono::milliseconds(100));
      if (watch) watch->update();
    }
    if (stats != nullptr) {
      REQUIRE(wait_for([&] { return server->stats().bulk_shed > 0; }));
      *stats = server->stats();
    }
    return std::make_pair(robot->behavior_loop().cycles(), robot->navigation().map_from_base);
  };
  MonitorStats stats;
  const auto plain = run(false, nullptr);
  const auto watched = run(true, &stats);
  CHECK(watched.first == plain.first);      // every reactive cycle ran
  CHECK(watched.second == plain.second);    // to the same pose: the monitor changed nothing
  CHECK(stats.bulk_shed > 0);               // the client fell behind and lost old bulk frames
  CHECK(stats.slow_disconnects == 0);
  CHECK(stats.published >= 600 * 3 + 60 * 5);  // pose, markings, status at every update; each new scan
}

TEST_CASE("A server that is not running keeps a bounded outbox of bulk messages", "[monitor][server][threads]") {
  MonitorServer server;
  const auto pose = server.advertise("/pose", "foxglove.PoseInFrame", "{}", Delivery::bulk);
  for (int i = 0; i < 10000; ++i) server.publish(pose, i, "{}");
  CHECK(server.stats().published == 10000);
  CHECK(server.stats().bulk_shed == 10000 - 4096);  // the oldest went, 4096 wait
}

TEST_CASE("Manual drive goes through the coordinator, masks the task's motion and stops at the dead-man timeout", "[monitor][robot]") {
  Psr2 psr2;
  SimClock& clock = psr2.clock;
  Robot* robot = psr2.robot.get();
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*robot, clock, server, RobotMonitorOptions{.min_interval_s = 0.0, .drive_deadman_s = 0.05});
  server.start();
  auto post = [&](const std::string& body) { return post_command(server, watch, body); };
  REQUIRE(robot->command("clean the room 3211").accepted);
  robot->run_for(std::chrono::seconds(5));
  CHECK(robot->behavior_active("BhCleaning"));

  CHECK_THAT(post(R"({"op":"drive","vx":"fast"})"), Catch::Contains(R"(field 'vx' of op 'drive': expected a number, got a string)"));
  CHECK_THAT(post(R"({"op":"drive","vx":0.0,"wz":1.0})"), Catch::Contains(R"("driving":true)"));
  const Pose2D before = robot->navigation().map_from_base;
  robot->run_for(std::chrono::seconds(1));
  const CycleReport& cycle = robot->behavior_loop().last_cycle();
  CHECK(cycle.coordinator.locked);
  CHECK(cycle.coordinator.lock == "operator");
  CHECK(cycle.coordinator.command.wz_rad_s > 0.5);  // turning on the spot as told, nothing of the cleaning path
  CHECK(std::abs(cycle.coordinator.command.vx_m_s) < 1e-9);
  CHECK(std::abs(robot->navigation().map_from_base.theta_rad - before.theta_rad) > 0.3);

  // No further command: the dead-man switch ends the drive at the next update, the task moves on.
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  watch.update();
  robot->run_for(std::chrono::seconds(1));
  CHECK_FALSE(robot->behavior_loop().last_cycle().coordinator.locked);
  CHECK(robot->behavior_active("BhCleaning"));
  CHECK(robot->planner().busy());
}

TEST_CASE("Read-only streams may be opened without the token where the operator says so, commands may not", "[monitor][server][threads]") {
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests", .read_without_token = true});
  server.start();
  {
    Client c(server.port());
    c.send(ws_upgrade("/ws"));
    const std::string got = c.read_until([](const std::string& b) { return b.find("\"read_only\":true") != std::string::npos; });
    CHECK_THAT(got, Catch::StartsWith("HTTP/1.1 101 Switching Protocols"));
    CHECK_THAT(got, Catch::Contains(R"("read_only":true)"));
  }
  Client c(server.port());
  c.send("POST /api/command HTTP/1.1\r\nContent-Length: 14\r\n\r\n{\"op\":\"pause\"}");
  CHECK_THAT(c.read_all(), Catch::StartsWith("HTTP/1.1 401"));
  CHECK(server.take_requests().empty());
}

namespace {

nlohmann::json answer_json(const std::string& http) { return nlohmann::json::parse(http.substr(http.find("\r\n\r\n") + 4)); }

// The next /status a page client receives (the monitor publishes at every update()).
nlohmann::json next_status(MonitorServer& server, RobotMonitor& watch) {
  Client c(server.port());
  c.send(ws_upgrade("/ws?token=t0ken-for-tests"));
  nlohmann::json status;
  // Whether `bytes` hold a whole /status frame (kept in `status`).
  auto complete = [&](const std::string& bytes) {
    const std::size_t body = bytes.find("\r\n\r\n");
    if (body == std::string::npos) return false;
    for (const WsFrame& f : server_frames(std::string_view(bytes).substr(body + 4))) {
      // only /status is parsed: the map and net frames are large, and parsing them again at every
      // read costs seconds in the sanitizer tree (tests at -O0)
      if (f.payload.find(R"("topic":"/status")") == std::string::npos) continue;
      const auto j = nlohmann::json::parse(f.payload, nullptr, false);
      if (j.is_object() && j.value("topic", "") == "/status") status = j["data"];
    }
    return status.is_object();
  };
  REQUIRE(wait_for([&] {
    watch.update();
    c.read_until(complete, std::chrono::milliseconds(20));
    return status.is_object();
  }));
  return status;
}

std::string cleaning_run(Robot& robot) {
  for (const std::string& run : robot.supervisor().running_runs()) {
    if (const CProcess* p = robot.supervisor().process(run); p != nullptr && p->name() == "PrCleaning") return run;
  }
  return {};
}

}  // namespace

TEST_CASE("The console reloads an edited net at a quiet marking, and refuses one that does not load with its diagnostics", "[monitor][robot][reload]") {
  Psr2 psr2;
  Robot* robot = psr2.robot.get();
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0, .reload_wait_s = 0.5});
  server.start();
  REQUIRE(robot->command("clean the room 3211").accepted);
  robot->run_for(std::chrono::seconds(5));
  const std::string run = cleaning_run(*robot);
  REQUIRE_FALSE(run.empty());
  REQUIRE(robot->behavior_active("BhCleaning"));
  const Engine* running = robot->supervisor().engine(run);
  const std::vector<Tokens> marking(running->marking().begin(), running->marking().end());

  // The page fetches the running net's text to edit it.
  const nlohmann::json net = answer_json(post_command(server, watch, nlohmann::json{{"op", "net"}, {"run", run}}.dump()));
  REQUIRE(net.value("process", "") == "PrCleaning");
  const std::string xml = net["xml"];
  REQUIRE(xml.find("<net") != std::string::npos);
  CHECK_THAT(post_command(server, watch, R"({"op":"net","run":"task"})"), Catch::Contains("409"));

  // Without the token nothing reaches the supervisor.
  const std::string edited = std::regex_replace(xml, std::regex("</net>"), "  <place id=\"P99\" description=\"operator's note\"/>\n</net>");
  const std::string reload = nlohmann::json{{"op", "reload"}, {"run", run}, {"xml", edited}}.dump();
  CHECK_THAT(post_command(server, watch, reload, ""), Catch::StartsWith("HTTP/1.1 401"));
  CHECK(robot->supervisor().engine(run) == running);

  SECTION("a net that does not load is refused with located diagnostics, nothing changed") {
    std::string broken = xml;
    broken.erase(broken.find("</place>"), 8);
    const nlohmann::json a = answer_json(post_command(server, watch, nlohmann::json{{"op", "reload"}, {"run", run}, {"xml", broken}}.dump()));
    CHECK_FALSE(a["accepted"].get<bool>());
    REQUIRE_FALSE(a["diagnostics"].empty());
    CHECK(std::regex_search(a["diagnostics"][0]["text"].get<std::string>(), std::regex(R"(^PrCleaning\.edited\.xml:\d+:\d+: error: )")));
    CHECK(a["diagnostics"][0]["severity"] == "error");
    CHECK(robot->supervisor().engine(run) == running);
  }
  SECTION("a net missing a marked place is refused naming it") {
    const std::string renamed = std::regex_replace(xml, std::regex("\"P3\""), "\"P3b\"");
    const nlohmann::json a = answer_json(post_command(server, watch, nlohmann::json{{"op", "reload"}, {"run", run}, {"xml", renamed}}.dump()));
    CHECK_FALSE(a["accepted"].get<bool>());
    CHECK_THAT(a["diagnostics"].dump(), Catch::Contains("place P3 holds 1 token in the running net"));
    CHECK(robot->supervisor().engine(run) == running);
  }
  SECTION("not quiet: the reload waits for the next quiet point, or is refused with the reasons when none comes in time") {
    robot->supervisor().post_event("localizer.lost");  // P3 -> P4: t5 times its 10 s
    robot->run_for(std::chrono::milliseconds(100));
    REQUIRE_FALSE(robot->supervisor().why_not_quiet(run).empty());
    running = robot->supervisor().engine(run);
    // The robot stands still (only update() runs): no quiet point within reload_wait_s.
    const auto t0 = std::chrono::steady_clock::now();
    const nlohmann::json refused = answer_json(post_command(server, watch, reload));
    CHECK(std::chrono::steady_clock::now() - t0 >= std::chrono::milliseconds(500));
    CHECK_FALSE(refused["accepted"].get<bool>());
    CHECK_THAT(refused["diagnostics"].dump(), Catch::Contains("is not at a quiet marking: transition t5 is timing its delay of 10 s"));
    CHECK(robot->supervisor().engine(run) == running);
    // Localization comes back while the request waits: the next period is quiet, the reload goes through.
    int periods = 0;
    const nlohmann::json accepted = answer_json(post_command(server, watch, reload, "Authorization: Bearer t0ken-for-tests\r\n", [&] {
      if (++periods == 3) robot->supervisor().post_event("localizer.ok");
      robot->run_for(std::chrono::milliseconds(10));
    }));
    INFO(accepted.dump());
    CHECK(accepted["accepted"].get<bool>());
    CHECK(periods >= 3);
    CHECK(robot->supervisor().engine(run)->net().find_place("P99").has_value());
  }
  SECTION("an edited net that loads replaces the running one, marking carried over, the task goes on") {
    const nlohmann::json a = answer_json(post_command(server, watch, reload));
    INFO(a.dump());
    REQUIRE(a["accepted"].get<bool>());
    const Engine* now = robot->supervisor().engine(run);
    REQUIRE(now != nullptr);
    CHECK(now->net().find_place("P99").has_value());
    CHECK(std::vector<Tokens>(now->marking().begin(), now->marking().begin() + static_cast<std::ptrdiff_t>(marking.size())) == marking);
    CHECK(robot->supervisor().process(run)->net().where.file.str() == "PrCleaning.edited.xml");
    // The loader's warning about the unreachable place travels with the acceptance.
    CHECK_THAT(a["diagnostics"].dump(), Catch::Contains("P99"));
    CHECK(robot->behavior_active("BhCleaning"));
    robot->run_for(std::chrono::seconds(2));
    CHECK(robot->planner().busy());
    CHECK(robot->behavior_active("BhCleaning"));
  }
}

TEST_CASE("The status carries the control board's link for a board robot and nothing of it for the simulated PSR-2", "[monitor][robot][board]") {
  SECTION("PSR-2 on the simulator: no board section") {
    Psr2 psr2;
    MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
    RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
    server.start();
    psr2.robot->run_for(std::chrono::seconds(1));
    const nlohmann::json status = next_status(server, watch);
    CHECK(status.contains("task_state"));
    CHECK_FALSE(status.contains("board"));
  }
  SECTION("the disinfection robot on the simulated board: the link as the host sees it") {
    const std::filesystem::path configs = std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs";
    RobotPlugins plugins;
    SimClock clock;
    register_all(plugins, std::make_shared<const sim::World>(sim::load_world(configs / "worlds/workspace.yaml")));
    const auto robot = Robot::assemble(load_robot_profile(configs / "robots/disinfection.yaml"), plugins, clock);
    MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
    RobotMonitor watch(*robot, clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
    server.start();
    robot->run_for(std::chrono::seconds(4));  // SYNC, DRIVE every period, the battery (3 s) and the tank (1 s) polled
    // The loop runs a cycle more after the sequencing layer's last period: the link has moved on,
    // the status shows the "board_link" snapshot the sequencing layer read (on the robot's own
    // threads the loop's thread runs the link: the monitor must not read it).
    robot->behavior_loop().step(clock.now());
    const board::LinkStats& link = dynamic_cast<board::BoardHost&>(*robot->hardware()).board().link().stats();
    const auto* seen = robot->sequencing_resources().find<board::BoardLinkReading>("board_link");
    REQUIRE(seen != nullptr);
    const board::LinkStats& snapshot = seen->latest().stats;
    REQUIRE(snapshot.requests < link.requests);
    const nlohmann::json status = next_status(server, watch);
    REQUIRE(status.contains("board"));
    const nlohmann::json& b = status["board"];
    INFO(b.dump());
    CHECK(b["connected"].get<bool>());
    CHECK(b["requests"].get<std::uint64_t>() == snapshot.requests);
    CHECK(b["requests"].get<std::uint64_t>() > 300);  // a DRIVE each 10 ms period, and the polls
    CHECK(b["missed"].get<std::uint64_t>() == 0);
    CHECK(b["decoder_errors"].get<std::uint64_t>() == 0);
    CHECK(b["watchdog_trips"].get<std::uint64_t>() == 0);
    CHECK(b["bytes_sent"].get<std::uint64_t>() == snapshot.bytes_sent);
    CHECK(b["bytes_sent"].get<std::uint64_t>() > 0);
    CHECK(b["bytes_received"].get<std::uint64_t>() > 0);
    CHECK(b["round_trip_ms"]["max"].get<double>() > 0.0);
    CHECK(b["round_trip_ms"]["max"].get<double>() <= 10.0);  // within the response timeout
    REQUIRE(b["battery"].is_object());
    CHECK(b["battery"]["percent"].get<int>() > 0);
    REQUIRE(b["tank"].is_object());
    CHECK(b["tank"]["percent"].get<int>() > 0);
    REQUIRE(b["status"].is_object());
    CHECK_FALSE(b["status"]["uv_lamp"].get<bool>());  // no task: the lamp is off
    CHECK(b["status"]["age_s"].get<double>() >= 0.0);
    CHECK(b["pending_actuator_commands"].get<std::size_t>() == seen->latest().pending_actuator_commands);
  }
}

TEST_CASE("Live mapping from the console: begin, drive by hand, save a map that lines up with the world", "[monitor][robot][mapping]") {
  Psr2 psr2;
  Robot* robot = psr2.robot.get();
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "tripodal_monitor_mapping";
  std::filesystem::remove_all(dir);
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0, .drive_deadman_s = 5.0, .map_dir = dir});
  server.start();
  auto post = [&](const std::string& body) { return post_command(server, watch, body); };
  robot->run_for(std::chrono::seconds(1));  // the first scans: the localizer settles
  CHECK_THAT(post(R"({"op":"map","action":"save","name":"early"})"), Catch::Contains("no map to save yet"));
  CHECK_THAT(post(R"({"op":"map","action":"begin"})"), Catch::Contains(R"("mapping":true)"));
  // a slow curve through section A, as an operator would drive it with the console's joystick
  for (int k = 0; k < 12; ++k) {
    CHECK_THAT(post(R"({"op":"drive","vx":0.3,"wz":)" + std::string(k < 6 ? "0.15" : "-0.15") + "}"), Catch::Contains(R"("driving":true)"));
    robot->run_for(std::chrono::seconds(2));
  }
  CHECK_THAT(post(R"({"op":"drive","stop":true})"), Catch::Contains(R"("driving":false)"));
  const std::string status = post(R"({"op":"map","action":"status"})");
  CHECK_THAT(status, Catch::Contains(R"("mapping":true)"));
  CHECK_THAT(post(R"({"op":"map","action":"save","name":"../escape"})"), Catch::Contains("expected \\\"name\\\""));
  CHECK_THAT(post(R"({"op":"map","action":"fly"})"), Catch::Contains("expected \\\"action\\\": begin, end, status or save"));
  CHECK_THAT(post(R"({"op":"map","action":"save","name":"hall-1"})"), Catch::Contains(R"("saved")"));
  CHECK_THAT(post(R"({"op":"map","action":"end"})"), Catch::Contains(R"("mapping":false)"));

  const navi::MapFile built = navi::load_map(dir / "hall-1.yaml");
  const navi::MapFile truth =
      navi::load_map(std::filesystem::path(TRIPODAL_SOURCE_DIR) / "configs" / "worlds" / "workspace_map.yaml");
  const navi::test::WallAgreement walls = navi::test::wall_agreement(built.grid, truth.grid);
  INFO(walls.marked << " occupied cells, " << walls.on_wall << " on a wall of the world");
  REQUIRE(walls.marked > 300);
  CHECK(walls.fraction() > 0.9);
  std::filesystem::remove_all(dir);
}

TEST_CASE("Map requests without a map folder or a MapBuilder are refused", "[monitor][robot][mapping]") {
  Psr2 psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  CHECK_THAT(post_command(server, watch, R"({"op":"map","action":"save","name":"x"})"),
             Catch::Contains("403") && Catch::Contains("saving is off"));
}

namespace {

// The PSR-2 with an HRI module (TestHri) on a copy of Jinny's knowledge in a fresh folder: the
// monitor finds the knowledge through the robot's modules.
struct Psr2WithHri {
  std::filesystem::path dir;
  std::filesystem::path file;
  RobotPlugins plugins;
  SimClock clock;
  std::unique_ptr<Robot> robot;
  // `prepare` may write files beside the knowledge (its history) before the robot loads it.
  explicit Psr2WithHri(const std::function<void(const std::filesystem::path& knowledge)>& prepare = {}) {
    const std::filesystem::path source = TRIPODAL_SOURCE_DIR;
    dir = std::filesystem::temp_directory_path() / ("tripodal_rkms_monitor_" + std::to_string(::getpid()));
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    file = dir / "jinny.xml";
    std::filesystem::copy_file(source / "configs/hri/jinny.xml", file);
    if (prepare) prepare(file);
    plugins.modules.add<testing_hri::TestHri>();
    register_all(plugins, std::make_shared<sim::World>(sim::load_world(source / "configs/worlds/workspace.yaml")));
    RobotProfile profile = load_robot_profile(source / "configs/robots/psr2.yaml");
    testing_hri::add_test_hri(profile, file, source);
    robot = Robot::assemble(profile, plugins, clock);
  }
  ~Psr2WithHri() {
    robot.reset();
    std::error_code ec;
    std::filesystem::remove_all(dir, ec);
  }
  Psr2WithHri(const Psr2WithHri&) = delete;
  Psr2WithHri& operator=(const Psr2WithHri&) = delete;
};

struct JsonAnswer {
  int status = 0;
  nlohmann::json body;
};

JsonAnswer json_command(MonitorServer& server, RobotMonitor& watch, const nlohmann::json& body,
                        const std::string& auth = "Authorization: Bearer t0ken-for-tests\r\n") {
  const std::string a = post_command(server, watch, body.dump(), auth);
  JsonAnswer out;
  out.status = std::stoi(a.substr(9, 3));
  out.body = nlohmann::json::parse(a.substr(a.find("\r\n\r\n") + 4));
  return out;
}

std::string file_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

}  // namespace

TEST_CASE("RKMS administration: list, add, edit, delete and history through the robot's HRI module", "[monitor][robot][rkms]") {
  Psr2WithHri psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();

  JsonAnswer r = json_command(server, watch, {{"op", "rkms.list"}});
  REQUIRE(r.status == 200);
  CHECK(r.body["version"] == 1);
  CHECK(r.body["file"] == "jinny.xml");
  CHECK(r.body["entries"].size() == 25);
  r = json_command(server, watch, {{"op", "rkms.list"}, {"query", "umbrella"}});
  REQUIRE(r.body["entries"].size() == 1);
  CHECK(r.body["entries"][0]["id"] == "weather");
  CHECK(r.body["entries"][0]["version"] == 1);

  const nlohmann::json parking{{"id", "parking"},
                               {"topic", "the parking"},
                               {"keywords", {"parking", "car"}},
                               {"questions", {"Where can I park my car?"}},
                               {"answer", "The car park is behind the hall."}};
  CHECK(json_command(server, watch, {{"op", "ask"}, {"text", "where can I park my car"}}).body["kind"] == "not_understood");
  r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", parking}, {"author", "alice"}});
  REQUIRE(r.status == 200);
  CHECK(r.body["version"] == 2);
  CHECK(r.body["entry_version"] == 2);
  // Answered at once, from the file's next version.
  r = json_command(server, watch, {{"op", "ask"}, {"text", "where can I park my car"}});
  CHECK(r.body["kind"] == "answered");
  CHECK(r.body["entry"] == "parking");
  CHECK(r.body["text"] == "The car park is behind the hall.");
  CHECK(KnowledgeBase::load(psr2.file).find("parking") != nullptr);

  nlohmann::json edited = parking;
  edited["answer"] = "Behind the hall, entrance B.";
  r = json_command(server, watch, {{"op", "rkms.edit"}, {"id", "parking"}, {"version", 2}, {"entry", edited}, {"author", "bob"}});
  REQUIRE(r.status == 200);
  CHECK(r.body["version"] == 3);
  // A second editor who read version 2: refused, and nothing changes.
  const std::string before = file_text(psr2.file);
  nlohmann::json other = parking;
  other["answer"] = "Nowhere.";
  r = json_command(server, watch, {{"op", "rkms.edit"}, {"id", "parking"}, {"version", 2}, {"entry", other}, {"author", "carol"}});
  CHECK(r.status == 409);
  CHECK(r.body["status"] == "stale");
  CHECK(r.body["entry_version"] == 3);
  CHECK(r.body["current"]["answer"] == "Behind the hall, entrance B.");
  CHECK_THAT(r.body["error"].get<std::string>(), Catch::Contains("was changed since you read it"));
  CHECK(json_command(server, watch, {{"op", "rkms.delete"}, {"id", "parking"}, {"version", 2}}).status == 409);
  CHECK(file_text(psr2.file) == before);

  // Invalid: the field is named.
  nlohmann::json bad = parking;
  bad["id"] = "car park";
  bad["answer"] = "It is {time";
  r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", bad}});
  CHECK(r.status == 400);
  CHECK(r.body["errors"][0]["field"] == "id");
  CHECK(r.body["errors"][1]["field"] == "answer");
  CHECK_THAT(r.body["errors"][1]["message"].get<std::string>(), Catch::Contains("unclosed '{' at byte 6"));
  bad = parking;
  bad["keywords"] = nlohmann::json::array({"car", 7});
  r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", bad}});
  CHECK(r.status == 400);
  CHECK(r.body["errors"][0]["field"] == "keywords[1]");
  // Oversize and binary fields: a polite refusal.
  bad = parking;
  bad["id"] = "big";
  bad["answer"] = std::string(5000, 'a');
  r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", bad}});
  CHECK(r.status == 400);
  CHECK(r.body["errors"][0]["message"] == "answer is 5000 bytes long; expected at most 4000");
  bad["answer"] = std::string("bell\x07", 5);
  r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", bad}});
  CHECK(r.status == 400);
  CHECK(r.body["errors"][0]["field"] == "answer");
  CHECK_THAT(r.body["errors"][0]["message"].get<std::string>(), Catch::Contains("not text: U+0007 at character 4 (byte 4)"));
  CHECK(file_text(psr2.file) == before);

  r = json_command(server, watch, {{"op", "rkms.delete"}, {"id", "parking"}, {"version", 3}, {"author", "dave"}});
  REQUIRE(r.status == 200);
  CHECK(r.body["version"] == 4);
  CHECK(json_command(server, watch, {{"op", "rkms.get"}, {"id", "parking"}}).status == 404);

  r = json_command(server, watch, {{"op", "rkms.history"}});
  REQUIRE(r.status == 200);
  REQUIRE(r.body["changes"].size() == 3);
  CHECK(r.body["changes"][0]["op"] == "add");
  CHECK(r.body["changes"][0]["author"] == "alice");
  CHECK(r.body["changes"][1]["op"] == "edit");
  CHECK(r.body["changes"][1]["before"]["answer"] == "The car park is behind the hall.");
  CHECK(r.body["changes"][1]["after"]["answer"] == "Behind the hall, entrance B.");
  CHECK(r.body["changes"][2]["op"] == "delete");
  CHECK(r.body["changes"][2]["after"].is_null());
  CHECK(json_command(server, watch, {{"op", "rkms.history"}, {"limit", 1}}).body["changes"].size() == 1);
  server.stop();
}

TEST_CASE("RKMS administration needs the token: refused without it and nothing changes", "[monitor][robot][rkms]") {
  Psr2WithHri psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  const std::string before = file_text(psr2.file);
  const nlohmann::json add{{"op", "rkms.add"},
                           {"entry", {{"id", "x"}, {"topic", "x"}, {"keywords", {"x"}}, {"answer", "x"}}}};
  for (const std::string auth : {"", "Authorization: Bearer wrong-token\r\n", "X-Tripodal-Token: t0ken\r\n"}) {
    Client c(server.port());
    const std::string body = add.dump();
    c.send("POST /api/command HTTP/1.1\r\n" + auth + "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body);
    const std::string a = c.read_all();
    CHECK(a.starts_with("HTTP/1.1 401"));
    watch.update();
  }
  const nlohmann::json del{{"op", "rkms.delete"}, {"id", "weather"}, {"version", 1}};
  Client c(server.port());
  c.send("POST /api/command HTTP/1.1\r\nContent-Length: " + std::to_string(del.dump().size()) + "\r\n\r\n" + del.dump());
  CHECK(c.read_all().starts_with("HTTP/1.1 401"));
  watch.update();
  CHECK(file_text(psr2.file) == before);
  CHECK_FALSE(std::filesystem::exists(psr2.file.string() + ".history"));
  CHECK(json_command(server, watch, {{"op", "rkms.list"}}).body["entries"].size() == 25);
  server.stop();
}

TEST_CASE("The RKMS and touch pages are served, and the touch screen's questions are answered by the HRI", "[monitor][robot][rkms]") {
  Psr2WithHri psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  for (const auto& [path, marker] : {std::pair{"/rkms", "RKMS: the robot's knowledge"}, std::pair{"/touch", "Type your question here"}}) {
    Client c(server.port());
    c.send(std::string("GET ") + path + " HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n");
    const std::string page = c.read_all();
    CHECK(page.starts_with("HTTP/1.1 200"));
    CHECK(page.find(marker) != std::string::npos);
  }
  JsonAnswer r = json_command(server, watch, {{"op", "touch"}});
  REQUIRE(r.status == 200);
  CHECK(r.body["robot"] == "jinny");
  CHECK(r.body["voice"] == voice_available());
  REQUIRE(r.body["questions"].size() == 8);
  CHECK(r.body["questions"][0] == "Introduce yourself.");
  r = json_command(server, watch, {{"op", "ask"}, {"text", "Introduce yourself."}, {"speak", true}});
  CHECK(r.body["kind"] == "answered");
  CHECK(r.body["entry"] == "introduce");
  if (voice_available()) {
    // A RIFF WAVE of the spoken answer: a second or more at espeak-ng's 22,050 Hz.
    REQUIRE(r.body.contains("audio"));
    const std::string b64 = r.body["audio"];
    CHECK(b64.starts_with(base64("RIFF").substr(0, 4)));
    CHECK(b64.size() * 3 / 4 > 44 + 22050 * 2);
  } else {
    CHECK_FALSE(r.body.contains("audio"));
  }
  r = json_command(server, watch, {{"op", "ask"}, {"text", std::string(600, 'a')}});
  CHECK(r.body["kind"] == "refused_input");
  server.stop();
}

TEST_CASE("/status carries what the HRI displays: the internal state and the last input with its answer", "[monitor][robot][rkms][display]") {
  Psr2WithHri psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  nlohmann::json status = next_status(server, watch);
  REQUIRE(status["hri"].is_object());
  CHECK(status["hri"]["status"] == "idle | no process | no fault");
  CHECK(status["hri"]["task"] == "");
  CHECK(status["hri"]["last"].is_null());
  REQUIRE(json_command(server, watch, {{"op", "ask"}, {"text", "How is the weather today?"}}).status == 200);
  status = next_status(server, watch);
  const nlohmann::json& last = status["hri"]["last"];
  CHECK(last["source"] == "typed");
  CHECK(last["input"] == "How is the weather today?");
  CHECK(last["kind"] == "answered");
  CHECK(last["entry"] == "weather");
  CHECK(last["reply"] == "The weather today: sunny, 27 degrees.");
  // A command the planner refuses: the refusal in plain words.
  REQUIRE(json_command(server, watch, {{"op", "ask"}, {"text", "dance for us"}}).status == 200);
  status = next_status(server, watch);
  CHECK(status["hri"]["last"]["kind"] == "task_refused");
  CHECK(status["hri"]["last"]["reply"] == "Sorry, I cannot start the dance task now: this test robot runs no guide tasks.");
  server.stop();
}

TEST_CASE("/status of a robot without an HRI has hri null", "[monitor][robot][display]") {
  Psr2 psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  const nlohmann::json status = next_status(server, watch);
  REQUIRE(status.contains("hri"));
  CHECK(status["hri"].is_null());
  server.stop();
}

// An operator with one monitor page per robot of a fleet sees which robot each is: its name and
// how the fleet reaches it (the DDS domain, namespace and security identity); null off DDS.
TEST_CASE("/status says which robot the monitor shows and its DDS identity", "[monitor][robot][display]") {
  Psr2 psr2;
  SECTION("a robot of a secured fleet") {
    MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
    RobotMonitor watch(*psr2.robot, psr2.clock, server,
                       RobotMonitorOptions{.min_interval_s = 0.0,
                                           .robot_name = "robot3",
                                           .identity = "DDS domain 78, namespace 'robot3', secured as 'robot3' (keys /k)"});
    server.start();
    const nlohmann::json status = next_status(server, watch);
    CHECK(status["robot"] == "robot3");
    CHECK(status["identity"] == "DDS domain 78, namespace 'robot3', secured as 'robot3' (keys /k)");
    server.stop();
  }
  SECTION("a robot off DDS") {
    MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
    RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0, .robot_name = "psr2"});
    server.start();
    const nlohmann::json status = next_status(server, watch);
    CHECK(status["robot"] == "psr2");
    CHECK(status["identity"].is_null());
    server.stop();
  }
}

TEST_CASE("RKMS ops on a robot without an HRI module are refused with 404", "[monitor][robot][rkms]") {
  Psr2 psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  const JsonAnswer r = json_command(server, watch, {{"op", "rkms.list"}});
  CHECK(r.status == 404);
  CHECK_THAT(r.body["error"].get<std::string>(), Catch::Contains("this robot has no HRI knowledge store"));
  server.stop();
}

TEST_CASE("An HRI built by the application outside the robot's modules is given to the monitor with set_hri", "[monitor][robot][rkms]") {
  Psr2WithHri with;  // only for its knowledge file and Jinny's tasks
  Psr2 psr2;         // a robot without an HRI module
  KnowledgeStore store(with.file);
  const TaskLibrary tasks = TaskLibrary::load(TRIPODAL_SOURCE_DIR "/configs/tasks/jinny_guide.yaml");
  const testing_hri::NoNodes nodes;
  AnswerProviders providers;
  providers.add("time", std::make_unique<FixedProvider>("14:05"));
  providers.add("battery", std::make_unique<FixedProvider>("82 percent"));
  providers.add("weather", std::make_unique<FixedProvider>("rain"));
  StoreBackedHri hri(store, tasks, nodes, providers, [](const Understanding&) { return std::string("no"); });
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  CHECK(json_command(server, watch, {{"op", "ask"}, {"text", "will it rain"}}).status == 404);
  watch.set_hri(&hri);
  const JsonAnswer r = json_command(server, watch, {{"op", "ask"}, {"text", "will it rain"}});
  CHECK(r.status == 200);
  CHECK(r.body["entry"] == "weather");
  CHECK(r.body["text"] == "The weather today: rain.");
  watch.set_hri(nullptr);
  server.stop();
}

// --- the operator request layer (src/monitor/operator_request.hpp) --------------------------------

namespace {

// A value of the field's own type that the schema accepts.
nlohmann::json valid_value(const FieldSpec& f) {
  switch (f.type) {
    case FieldType::boolean: return true;
    case FieldType::number: return std::clamp(0.0, f.min, f.max);
    case FieldType::count: return static_cast<std::uint64_t>(std::max(f.min, 1.0));
    case FieldType::text: return f.choices.empty() ? std::string("x") : std::string(f.choices.front());
    case FieldType::text_list: return nlohmann::json::array({"x"});
    case FieldType::object: {
      nlohmann::json o = nlohmann::json::object();
      for (const FieldSpec& m : f.members) o[std::string(m.name)] = valid_value(m);
      return o;
    }
  }
  return nullptr;
}

// The op's required fields, each valid.
nlohmann::json valid_body(const OpSpec& op) {
  nlohmann::json body{{"op", op.op}};
  for (const FieldSpec& f : op.fields) {
    if (f.required) body[std::string(f.name)] = valid_value(f);
  }
  return body;
}

// One value of each JSON type.
const std::vector<std::pair<std::string, nlohmann::json>>& json_kinds() {
  static const std::vector<std::pair<std::string, nlohmann::json>> kinds = {
      {"null", nullptr}, {"boolean", true}, {"number", 7}, {"string", "seven"}, {"array", nlohmann::json::array({1})}, {"object", {{"a", 1}}}};
  return kinds;
}

bool right_kind(FieldType type, const std::string& kind) {
  switch (type) {
    case FieldType::boolean: return kind == "boolean";
    case FieldType::number:
    case FieldType::count: return kind == "number";
    case FieldType::text: return kind == "string";
    case FieldType::text_list: return kind == "array";
    case FieldType::object: return kind == "object";
  }
  return false;
}

// Every (body, field path) of the schema with one field of a wrong JSON type; fields of an object
// field (an RKMS entry) and the items of a list field included.
std::vector<std::pair<nlohmann::json, std::string>> wrong_type_requests() {
  std::vector<std::pair<nlohmann::json, std::string>> out;
  for (const OpSpec& op : request_schema()) {
    const nlohmann::json base = valid_body(op);
    for (const FieldSpec& f : op.fields) {
      const std::string name(f.name);
      for (const auto& [kind, value] : json_kinds()) {
        if (right_kind(f.type, kind)) continue;
        nlohmann::json body = base;
        body[name] = value;
        out.emplace_back(body, name);
      }
      if (f.type == FieldType::text_list) {
        for (const auto& [kind, value] : json_kinds()) {
          if (kind == "string") continue;
          nlohmann::json body = base;
          body[name] = nlohmann::json::array({"x", value});
          out.emplace_back(body, name + "[1]");
        }
      }
      for (const FieldSpec& m : f.members) {
        const std::string member(m.name);
        for (const auto& [kind, value] : json_kinds()) {
          nlohmann::json body = base;
          body[name] = valid_value(f);
          if (!right_kind(m.type, kind)) {
            body[name][member] = value;
            out.emplace_back(body, name + "." + member);
          }
          if (m.type == FieldType::text_list && kind != "string") {
            body[name][member] = nlohmann::json::array({"x", value});
            out.emplace_back(body, name + "." + member + "[1]");
          }
        }
      }
    }
  }
  return out;
}

}  // namespace

TEST_CASE("Every field of every op sent with every wrong JSON type is refused with 400 naming it, and the robot goes on",
          "[monitor][robot][requests]") {
  Psr2WithHri psr2;
  const std::filesystem::path maps = psr2.dir / "maps";
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0, .map_dir = maps});
  server.start();
  REQUIRE(psr2.robot->command("clean the room 3211").accepted);
  const auto requests = wrong_type_requests();
  REQUIRE(requests.size() > 150);  // 18 ops; a schema that lost its fields would pass vacuously
  std::size_t sent = 0;
  for (const auto& [body, field] : requests) {
    INFO(body.dump());
    const JsonAnswer r = json_command(server, watch, body);
    CHECK(r.status == 400);
    CHECK(r.body["field"] == field);
    CHECK_THAT(r.body["error"].get<std::string>(),
               Catch::StartsWith("field '" + field + "' of op '" + body["op"].get<std::string>() + "': expected "));
    // The robot keeps running between requests.
    if (++sent % 25 == 0) psr2.robot->run_for(std::chrono::milliseconds(200));
  }
  // The issue's examples, by name.
  JsonAnswer r = json_command(server, watch, {{"op", "drive"}, {"stop", "yes"}});
  CHECK(r.status == 400);
  CHECK(r.body["error"] == "field 'stop' of op 'drive': expected a boolean, got a string");
  CHECK(json_command(server, watch, {{"op", "net"}, {"run", 5}}).body["error"] == "field 'run' of op 'net': expected a string, got a number");
  CHECK(json_command(server, watch, {{"op", "breakpoint"}, {"place", "P1"}, {"on", "no"}}).body["field"] == "on");
  CHECK(json_command(server, watch, {{"op", "map"}, {"action", 1}}).body["field"] == "action");
  // Unknown fields are refused with their name; nothing happened.
  r = json_command(server, watch, {{"op", "pause"}, {"now", true}});
  CHECK(r.status == 400);
  CHECK(r.body["error"] == "field 'now' of op 'pause': unknown; op 'pause' takes no fields");
  r = json_command(server, watch, {{"op", "drive"}, {"vx", 0.1}, {"vz", 0.1}});
  CHECK(r.body["error"] == "field 'vz' of op 'drive': unknown; expected stop, vx, vy, wz");
  CHECK_FALSE(watch.paused());
  // Ranges: a joystick's bounds, not clamped silently.
  r = json_command(server, watch, {{"op", "drive"}, {"vx", 5.0}});
  CHECK(r.body["error"] == "field 'vx' of op 'drive': expected a number from -1 to 1, got 5.0");
  // The robot kept running and answers: a later valid request is served.
  psr2.robot->run_for(std::chrono::seconds(1));
  CHECK(psr2.robot->planner().busy());
  r = json_command(server, watch, {{"op", "pause"}});
  CHECK(r.status == 200);
  CHECK(watch.paused());
  CHECK(json_command(server, watch, {{"op", "rkms.list"}}).body["entries"].size() == 25);
  server.stop();
}

TEST_CASE("The request layer: every text field's length is refused one past its limit, not at it, and texts must be XML's",
          "[monitor][requests]") {
  std::size_t checked = 0;
  for (const OpSpec& op : request_schema()) {
    for (const FieldSpec& f : op.fields) {
      if (f.type != FieldType::text || f.max_bytes == 0 || !f.choices.empty()) continue;
      nlohmann::json body = valid_body(op);
      body[std::string(f.name)] = std::string(f.max_bytes, 'a');
      if (op.op == "map") body["action"] = "save";
      INFO(body.dump().substr(0, 200));
      const ParsedRequest at = parse_operator_request(body.dump());
      CHECK(at.command.has_value());
      body[std::string(f.name)] = std::string(f.max_bytes + 1, 'a');
      const ParsedRequest past = parse_operator_request(body.dump());
      REQUIRE_FALSE(past.command.has_value());
      CHECK(past.errors.front().field == f.name);
      CHECK_THAT(past.errors.front().message, Catch::Contains(std::to_string(f.max_bytes + 1) + " bytes; expected at most " + std::to_string(f.max_bytes)));
      ++checked;
    }
  }
  CHECK(checked >= 14);
  // Text XML cannot hold, in any string: refused at its character.
  ParsedRequest p = parse_operator_request(R"({"op":"task","text":"clean \uFFFE room"})");
  REQUIRE(p.errors.size() == 1);
  CHECK(p.errors[0].message == "field 'text' of op 'task': not text: U+FFFE at character 6 (byte 6) is not a character XML allows");
  p = parse_operator_request(R"({"op":"ack","text":"done\u0000"})");
  CHECK(p.errors.at(0).message == "field 'text' of op 'ack': not text: U+0000 at character 4 (byte 4) is not a character XML allows");
  // Log lines stay lines.
  p = parse_operator_request(R"({"op":"ack","text":"ok\nmonitor: resumed"})");
  CHECK(p.errors.at(0).message == "field 'text' of op 'ack': holds a line break or a tab at byte 2; expected one line");
  // Not an object, no op, an unknown op, counts that are not whole.
  CHECK(parse_operator_request("[1]").errors.at(0).message == "body: expected a JSON object with a string \"op\"");
  CHECK(parse_operator_request(R"({"op":7})").errors.at(0).field == "op");
  CHECK_THAT(parse_operator_request(R"({"op":"warp"})").errors.at(0).message, Catch::StartsWith("unknown op 'warp': expected task, pause,"));
  CHECK(parse_operator_request(R"({"op":"rkms.history","limit":2.5})").errors.at(0).message ==
        "field 'limit' of op 'rkms.history': expected a whole number from 1 to 200, got 2.5");
  CHECK(parse_operator_request(R"({"op":"rkms.delete","id":"a","version":-1})").errors.at(0).field == "version");
  // Unknown field names are quoted only when they are a short line of text (fuzz finding: an empty
  // name was reported as the body's).
  p = parse_operator_request(R"({"op":"task","text":"x","":1})");
  CHECK(p.errors.at(0).field == "(empty name)");
  CHECK(p.errors.at(0).message == "field '(empty name)' of op 'task': unknown; expected text");
  p = parse_operator_request(nlohmann::json{{"op", "pause"}, {std::string(70, 'k'), 1}}.dump());
  CHECK(p.errors.at(0).field == "(a name of 70 bytes)");
  CHECK(parse_operator_request(R"({"op":"task\n"})").errors.at(0).message.starts_with("unknown op '(a name of 5 bytes)'"));
  // Every error of a request, in order.
  p = parse_operator_request(R"({"op":"drive","stop":1,"vx":"a"})");
  REQUIRE(p.errors.size() == 2);
  CHECK(p.errors[1].field == "vx");
}

TEST_CASE("Budgets: breakpoints, ack notes and task text at their limit and one past it", "[monitor][robot][requests][budgets]") {
  Psr2 psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  using B = OperatorBudgets;
  // Breakpoints: names of at most 256 bytes, at most 64 of them.
  JsonAnswer r = json_command(server, watch, {{"op", "breakpoint"}, {"place", std::string(B::kMaxBreakpointBytes, 'p')}});
  CHECK(r.status == 200);
  r = json_command(server, watch, {{"op", "breakpoint"}, {"place", std::string(B::kMaxBreakpointBytes + 1, 'p')}});
  CHECK(r.status == 400);
  CHECK(r.body["error"] == "field 'place' of op 'breakpoint': 257 bytes; expected at most 256");
  for (std::size_t i = 1; i < B::kMaxBreakpoints; ++i) watch.set_breakpoint("P" + std::to_string(i), true);
  REQUIRE(watch.breakpoints().size() == B::kMaxBreakpoints);
  r = json_command(server, watch, {{"op", "breakpoint"}, {"place", "one-too-many"}});
  CHECK(r.status == 409);
  CHECK(r.body["error"] == "breakpoint: 64 breakpoints are set, the most the monitor keeps; clear one first");
  CHECK_THROWS_WITH(watch.set_breakpoint("one-too-many", true), Catch::Contains("64 breakpoints are set"));
  CHECK(json_command(server, watch, {{"op", "breakpoint"}, {"place", "P1"}, {"on", true}}).status == 200);  // set already: no new one
  CHECK(json_command(server, watch, {{"op", "breakpoint"}, {"place", "P1"}, {"on", false}}).status == 200);
  CHECK(json_command(server, watch, {{"op", "breakpoint"}, {"place", "one-too-many"}}).status == 200);
  CHECK(watch.breakpoints().size() == B::kMaxBreakpoints);

  // Task text: 500 bytes reach the planner (which refuses nonsense), 501 do not.
  r = json_command(server, watch, {{"op", "task"}, {"text", std::string(B::kMaxTaskTextBytes, 'a')}});
  CHECK(r.status == 200);
  CHECK(r.body["accepted"] == false);
  r = json_command(server, watch, {{"op", "task"}, {"text", std::string(B::kMaxTaskTextBytes + 1, 'a')}});
  CHECK(r.status == 400);
  CHECK(r.body["field"] == "text");

  // Ack notes: 500 bytes each; the first 100 kept; an acknowledgement itself is never refused.
  CHECK(json_command(server, watch, {{"op", "ack"}, {"text", std::string(B::kMaxAckTextBytes + 1, 'n')}}).status == 400);
  for (std::size_t i = 0; i < B::kMaxAckNotesKept; ++i) {
    r = json_command(server, watch, {{"op", "ack"}, {"text", std::string(B::kMaxAckTextBytes, 'n')}});
    REQUIRE(r.status == 200);
    REQUIRE(r.body["note_kept"] == true);
  }
  r = json_command(server, watch, {{"op", "ack"}, {"text", std::string(B::kMaxAckTextBytes, 'n')}});
  CHECK(r.status == 200);
  CHECK(r.body["acknowledged"] == true);
  CHECK(r.body["note_kept"] == false);
  CHECK(json_command(server, watch, {{"op", "ack"}}).body["acknowledged"] == true);
  server.stop();
}

namespace {

// A history line of the knowledge store, as it appends them.
std::string history_line(std::uint64_t version, const nlohmann::json& entry) {
  return nlohmann::json{{"version", version}, {"time", "2026-11-27T12:00:00Z"}, {"author", "h"}, {"op", "edit"}, {"id", "weather"},
                        {"before", entry}, {"after", entry}}
             .dump() +
         "\n";
}

}  // namespace

TEST_CASE("Budgets: rkms.history sends 50 changes by default, at most 200, and never more than its byte budget", "[monitor][robot][rkms][budgets]") {
  using B = OperatorBudgets;
  {
    Psr2WithHri psr2([](const std::filesystem::path& knowledge) {
      std::ofstream out(knowledge.string() + ".history");
      for (std::uint64_t v = 2; v <= 251; ++v) out << history_line(v, {{"id", "weather"}, {"topic", "t"}, {"answer", "a"}});
    });
    MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
    RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
    server.start();
    JsonAnswer r = json_command(server, watch, {{"op", "rkms.history"}});
    REQUIRE(r.status == 200);
    REQUIRE(r.body["changes"].size() == B::kDefaultHistoryLimit);
    CHECK(r.body["changes"].back()["version"] == 251);  // the newest
    CHECK(r.body["omitted"] == 0);
    CHECK(json_command(server, watch, {{"op", "rkms.history"}, {"limit", B::kMaxHistoryLimit}}).body["changes"].size() == B::kMaxHistoryLimit);
    r = json_command(server, watch, {{"op", "rkms.history"}, {"limit", B::kMaxHistoryLimit + 1}});
    CHECK(r.status == 400);
    CHECK(r.body["error"] == "field 'limit' of op 'rkms.history': expected a whole number from 1 to 200, got 201");
    CHECK(json_command(server, watch, {{"op", "rkms.history"}, {"limit", 0}}).status == 400);
    server.stop();
  }
  // Changes as large as the store allows (two entries of ~40 KB each): the newest that fit in the
  // byte budget are sent, the answer says how many were left out, and the answer arrives.
  Psr2WithHri psr2([](const std::filesystem::path& knowledge) {
    const nlohmann::json big{{"id", "weather"}, {"topic", "t"}, {"answer", std::string(4000, 'a')},
                             {"questions", std::vector<std::string>(64, std::string(500, 'q'))}};
    std::ofstream out(knowledge.string() + ".history");
    for (std::uint64_t v = 2; v <= 81; ++v) out << history_line(v, big);
  });
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  const std::string http = post_command(server, watch, R"({"op":"rkms.history","limit":200})");
  CHECK(http.size() < B::kMaxHistoryAnswerBytes + 4096);
  const nlohmann::json j = answer_json(http);
  const std::size_t sent = j["changes"].size();
  CHECK(sent > 10);
  CHECK(sent < 80);
  CHECK(j["omitted"] == 80 - sent);
  CHECK(j["changes"].back()["version"] == 81);
  server.stop();
}

TEST_CASE("Budgets: knowledge entry fields at the store's limits are saved, one past them refused naming the field", "[monitor][robot][rkms][budgets]") {
  Psr2WithHri psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  const KnowledgeLimits limits;
  int n = 0;
  const auto entry = [&] {
    return nlohmann::json{{"id", "e" + std::to_string(++n)}, {"topic", "t"}, {"keywords", {"k"}}, {"questions", {"Q?"}}, {"answer", "A."}};
  };
  const auto numbered = [](const std::string& stem, std::size_t count) {
    std::vector<std::string> out;
    for (std::size_t i = 0; i < count; ++i) out.push_back(stem + std::to_string(i));
    return out;
  };
  struct Case {
    std::string field;
    nlohmann::json at, past;
  };
  const std::vector<Case> cases = {
      {"id", std::string(limits.max_id_bytes, 'i'), std::string(limits.max_id_bytes + 1, 'i')},
      {"topic", std::string(limits.max_topic_bytes, 't'), std::string(limits.max_topic_bytes + 1, 't')},
      {"answer", std::string(limits.max_answer_bytes, 'a'), std::string(limits.max_answer_bytes + 1, 'a')},
      {"keywords", numbered("k", limits.max_keywords), numbered("k", limits.max_keywords + 1)},
      {"keywords", std::vector<std::string>{std::string(limits.max_keyword_bytes, 'k')},
       std::vector<std::string>{std::string(limits.max_keyword_bytes + 1, 'k')}},
      {"questions", numbered("Q", limits.max_questions), numbered("Q", limits.max_questions + 1)},
      {"questions", std::vector<std::string>{std::string(limits.max_question_bytes, 'q')},
       std::vector<std::string>{std::string(limits.max_question_bytes + 1, 'q')}},
  };
  for (const Case& c : cases) {
    INFO(c.field);
    nlohmann::json e = entry();
    e[c.field] = c.at;
    JsonAnswer r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", e}});
    CHECK(r.status == 200);
    e = entry();
    e[c.field] = c.past;
    r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", e}});
    CHECK(r.status == 400);
    CHECK_THAT(r.body["errors"][0]["field"].get<std::string>(), Catch::StartsWith(c.field));
  }
  // The action's limit (what an action says is the planner's to judge).
  nlohmann::json e = entry();
  e["action"] = std::string(limits.max_action_bytes + 1, 'a');
  JsonAnswer r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", e}});
  CHECK(r.status == 400);
  CHECK(r.body["errors"][0]["message"] == "action is 501 bytes long; expected at most 500");
  server.stop();
}

TEST_CASE("An RKMS entry with U+FFFE is refused at its character, and later saves succeed and Jinny's knowledge still loads",
          "[monitor][robot][rkms][xml]") {
  Psr2WithHri psr2;
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  server.start();
  const std::string before = file_text(psr2.file);
  nlohmann::json entry{{"id", "parking"}, {"topic", "the parking"}, {"keywords", {"parking"}}, {"answer", "Behind the hall \xEF\xBF\xBE B."}};
  JsonAnswer r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", entry}});
  CHECK(r.status == 400);
  CHECK(r.body["field"] == "entry.answer");
  CHECK(r.body["error"] == "field 'entry.answer' of op 'rkms.add': not text: U+FFFE at character 16 (byte 16) is not a character XML allows");
  CHECK(r.body["errors"][0]["field"] == "answer");
  entry["answer"] = "Behind the hall \xEF\xBF\xBF B.";
  CHECK(json_command(server, watch, {{"op", "rkms.add"}, {"entry", entry}}).status == 400);
  CHECK(file_text(psr2.file) == before);
  entry["answer"] = "Behind the hall, entrance B.";
  r = json_command(server, watch, {{"op", "rkms.add"}, {"entry", entry}});
  CHECK(r.status == 200);
  const KnowledgeBase reloaded = KnowledgeBase::load(psr2.file);
  CHECK(reloaded.version() == 2);
  CHECK(reloaded.find("parking") != nullptr);
  CHECK(reloaded.entries().size() == 26);
  server.stop();
}

namespace {

// An HRI that fails inside an op: what the last-resort catch of RobotMonitor::update() is for.
class FailingHri final : public HriService {
 public:
  explicit FailingHri(const std::filesystem::path& knowledge) : store_(knowledge) {}
  KnowledgeStore& knowledge_store() override { return store_; }
  HriReply ask(std::string_view) override { throw std::runtime_error("the recognizer's index is gone"); }
  SpeechSynthesizer* voice() noexcept override { return nullptr; }
  HriDisplay display() override { return {}; }

 private:
  KnowledgeStore store_;
};

}  // namespace

TEST_CASE("An exception inside an op is answered 500 and logged, and the robot's thread goes on", "[monitor][robot][requests]") {
  Psr2WithHri psr2;
  FailingHri failing(psr2.file);
  MonitorServer server(MonitorServerOptions{.token = "t0ken-for-tests"});
  RobotMonitor watch(*psr2.robot, psr2.clock, server, RobotMonitorOptions{.min_interval_s = 0.0});
  watch.set_hri(&failing);
  server.start();
  const JsonAnswer r = json_command(server, watch, {{"op", "ask"}, {"text", "hello"}});
  CHECK(r.status == 500);
  CHECK(r.body["error"] == "the request failed on the robot: the recognizer's index is gone");
  CHECK(json_command(server, watch, {{"op", "pause"}}).status == 200);
  CHECK(watch.paused());
  watch.set_hri(nullptr);
  server.stop();
}
