// The hand-over from the reactive loop to the sequencing layer on the wall-clock runtime: a writer
// and a reader thread at full speed, the reader checking that every value it sees was written whole
// (core/snapshot.hpp, ResourceSnapshot). scripts/tsan.sh runs the [threads] ones under TSan.
#include "tripodal/core/snapshot.hpp"

#include <atomic>
#include <catch2/catch.hpp>
#include <thread>

#include "tripodal/resources/resource.hpp"

using namespace tripodal;

namespace {

// A scan whose every beam holds the scan's number: a torn copy mixes numbers.
LaserScan numbered_scan(std::size_t n, std::size_t beams) {
  LaserScan s;
  s.stamp = Time{std::chrono::milliseconds(static_cast<std::int64_t>(n))};
  s.ranges_m.assign(beams, static_cast<float>(n));
  return s;
}

bool whole(const LaserScan& s, std::size_t beams) {
  if (s.ranges_m.size() != beams) return false;
  for (const float r : s.ranges_m) {
    if (r != s.ranges_m.front()) return false;
  }
  return s.stamp == Time{std::chrono::milliseconds(static_cast<std::int64_t>(s.ranges_m.front()))};
}

}  // namespace

TEST_CASE("A triple buffer hands the newest value over and nothing before a publish") {
  TripleBuffer<int> b(0);
  CHECK_FALSE(b.fetch());
  b.back() = 1;
  b.publish();
  b.back() = 2;  // written, not published
  CHECK(b.fetch());
  CHECK(b.front() == 1);
  CHECK_FALSE(b.fetch());
  b.publish();
  b.back() = 3;
  b.publish();
  CHECK(b.fetch());
  CHECK(b.front() == 3);  // the reader skips to the newest
}

TEST_CASE("A triple buffer between two threads never gives a torn or older value", "[threads]") {
  constexpr std::size_t kBeams = 360;
  constexpr std::size_t kScans = 20000;
  TripleBuffer<LaserScan> buffer(numbered_scan(0, kBeams));
  std::atomic<bool> done{false};
  std::thread writer([&] {
    for (std::size_t n = 1; n <= kScans; ++n) {
      LaserScan& s = buffer.back();
      s.stamp = Time{std::chrono::milliseconds(static_cast<std::int64_t>(n))};
      std::fill(s.ranges_m.begin(), s.ranges_m.end(), static_cast<float>(n));
      buffer.publish();
    }
    done.store(true, std::memory_order_release);
  });
  std::size_t torn = 0, backwards = 0, seen = 0;
  float last = 0.0F;
  auto check = [&] {
    const LaserScan& s = buffer.front();
    if (!whole(s, kBeams)) ++torn;
    if (s.ranges_m.front() < last) ++backwards;
    last = s.ranges_m.front();
    ++seen;
  };
  while (!done.load(std::memory_order_acquire)) {
    if (buffer.fetch()) check();
  }
  writer.join();
  if (buffer.fetch()) check();
  CHECK(torn == 0);
  CHECK(backwards == 0);
  CHECK(seen > 0);
  CHECK(last == static_cast<float>(kScans));  // the last one always arrives
}

TEST_CASE("A seqlock value read by two threads while one writes is always whole", "[threads]") {
  SeqlockValue<Pose2D> pose(Pose2D{0.0, 0.0, 0.0});
  std::atomic<bool> done{false};
  std::atomic<int> torn{0};
  auto reader = [&] {
    while (!done.load(std::memory_order_acquire)) {
      const Pose2D p = pose.load();
      if (p.y_m != 2.0 * p.x_m || p.theta_rad != -p.x_m) torn.fetch_add(1);
    }
  };
  std::thread r1(reader), r2(reader);
  for (int i = 1; i <= 200000; ++i) pose.store(Pose2D{i * 1.0, i * 2.0, -i * 1.0});
  done.store(true, std::memory_order_release);
  r1.join();
  r2.join();
  CHECK(torn.load() == 0);
  CHECK(pose.load().x_m == 200000.0);
}

TEST_CASE("A resource snapshot mirrors name, reading, stamp and sequence, and skips resources without a copy") {
  LaserResource laser("front_laser", std::chrono::milliseconds(200));
  OdometryResource odom("odometry");
  ResourceTable table;
  table.add(laser);
  table.add(odom);
  ResourceSnapshot snapshot(table);
  REQUIRE(snapshot.table().size() == 2);
  const auto* copy = snapshot.table().find<LaserScan>("front_laser");
  REQUIRE(copy != nullptr);
  CHECK(copy != &laser);
  CHECK_FALSE(copy->has_reading());
  CHECK(copy->max_age() == std::chrono::milliseconds(200));
  CHECK(&copy->manifest() == &laser.manifest());

  laser.publish(numbered_scan(7, 10));
  laser.publish(numbered_scan(8, 10));
  CHECK(snapshot.refresh() == 0);  // nothing handed over yet: the copy keeps what it had
  snapshot.publish();
  CHECK(snapshot.refresh() == 1);  // only the laser changed
  CHECK(copy->has_reading());
  CHECK(copy->sequence() == 2);
  CHECK(copy->stamp() == Time{std::chrono::milliseconds(8)});
  CHECK(copy->latest().ranges_m == std::vector<float>(10, 8.0F));
  CHECK(snapshot.refresh() == 0);
}

TEST_CASE("A resource snapshot read by the sequencing thread while the loop's thread publishes is consistent", "[threads]") {
  // The writer stands for the behavior loop (publish after each cycle), the reader for the
  // sequencing loop (refresh, then read the mirror): every reading the reader sees is one the
  // writer published whole, its stamp and sequence with it, never going back.
  constexpr std::size_t kBeams = 720;
  constexpr std::size_t kCycles = 20000;
  LaserResource laser("laser");
  OdometryResource odom("odometry");
  ResourceTable table;
  table.add(laser);
  table.add(odom);
  ResourceSnapshot snapshot(table);
  const auto& copy = *snapshot.table().find<LaserScan>("laser");
  const auto& odom_copy = *snapshot.table().find<OdometryReading>("odometry");
  std::atomic<bool> done{false};
  std::thread loop_thread([&] {
    LaserScan scan = numbered_scan(0, kBeams);
    OdometryReading o;
    for (std::size_t n = 1; n <= kCycles; ++n) {
      scan.stamp = Time{std::chrono::milliseconds(static_cast<std::int64_t>(n))};
      std::fill(scan.ranges_m.begin(), scan.ranges_m.end(), static_cast<float>(n));
      laser.publish(scan);
      o.stamp = scan.stamp;
      o.pose = Pose2D{static_cast<double>(n), 0.0, 0.0};
      odom.publish(o);
      snapshot.publish();
    }
    done.store(true, std::memory_order_release);
  });
  std::size_t bad = 0, refreshes = 0;
  std::size_t last_sequence = 0;
  auto check = [&] {
    if (copy.has_reading()) {
      if (!whole(copy.latest(), kBeams)) ++bad;
      if (copy.stamp() != copy.latest().stamp) ++bad;
      if (copy.sequence() != static_cast<std::size_t>(copy.latest().ranges_m.front())) ++bad;
      if (copy.sequence() < last_sequence) ++bad;
      last_sequence = copy.sequence();
    }
    if (odom_copy.has_reading() && odom_copy.latest().pose.x_m != static_cast<double>(odom_copy.sequence())) ++bad;
  };
  while (!done.load(std::memory_order_acquire)) {
    if (snapshot.refresh() > 0) ++refreshes;
    check();
  }
  loop_thread.join();
  snapshot.refresh();
  check();
  CHECK(bad == 0);
  CHECK(refreshes > 0);
  CHECK(copy.sequence() == kCycles);
  CHECK(odom_copy.latest().pose.x_m == static_cast<double>(kCycles));
}
