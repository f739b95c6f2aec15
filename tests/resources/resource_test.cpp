// Resources: timestamped readings, fresh vs stale on the injected clock, typed lookup.
#include "tripodal/resources/resource.hpp"

#include <catch2/catch.hpp>

#include "tripodal/core/clock.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {
// A driver that publishes what a device delivered since the last poll.
class FakeBumperDriver final : public TypedResource<BumperReading> {
 public:
  FakeBumperDriver() : TypedResource<BumperReading>("bumpers", 50ms) {}
  std::uint32_t device_mask = 0;
  bool device_has_data = false;

 protected:
  void on_poll(Time now) noexcept override {
    if (!device_has_data) return;
    BumperReading r;
    r.stamp = now;
    r.count = 4;
    r.pressed_mask = device_mask;
    publish(r);
    device_has_data = false;
  }
};
}  // namespace

TEST_CASE("A reading is fresh until it is older than max_age") {
  SimClock clock;
  LaserResource laser("front_laser", 100ms);
  CHECK_FALSE(laser.has_reading());
  CHECK(laser.is_stale(clock.now()));
  LaserScan s;
  s.stamp = Time{10ms};
  s.ranges_m = {1.0f, 2.0f};
  laser.publish(s);
  CHECK(laser.has_reading());
  CHECK(laser.stamp() == Time{10ms});
  CHECK(laser.sequence() == 1);
  clock.set(Time{110ms});
  CHECK(laser.is_fresh(clock.now()));
  clock.set(Time{111ms});
  CHECK(laser.is_stale(clock.now()));
  CHECK(laser.latest().ranges_m.size() == 2);
  // A reading stamped after now (driver clock ahead) is fresh.
  CHECK(laser.is_fresh(Time{5ms}));
  // max_age 0: never stale once a reading exists.
  laser.set_max_age(0ms);
  CHECK(laser.is_fresh(Time{1000s}));
}

TEST_CASE("Publishing a reading of the same size reuses storage") {
  LaserResource laser("laser");
  LaserScan s;
  s.ranges_m.assign(720, 1.0f);
  laser.publish(s);
  const float* storage = laser.latest().ranges_m.data();
  s.ranges_m.assign(720, 2.0f);
  s.stamp = Time{1ms};
  laser.publish(s);
  CHECK(laser.latest().ranges_m.data() == storage);
  CHECK(laser.latest().ranges_m[5] == 2.0f);
  // Drivers may fill in place.
  laser.edit().ranges_m[0] = 7.0f;
  laser.edit().stamp = Time{2ms};
  laser.commit();
  CHECK(laser.stamp() == Time{2ms});
  CHECK(laser.sequence() == 3);
}

TEST_CASE("Drivers publish from poll(), the table finds resources by name and reading type") {
  FakeBumperDriver bumpers;
  OdometryResource odom("odom");
  BatteryResource battery("battery", 1s);
  ResourceTable table;
  table.add(bumpers);
  table.add(odom);
  table.add(battery);
  CHECK_THROWS_WITH(table.add(odom), Catch::Contains("a resource named 'odom' is already in the table"));
  CHECK(table.size() == 3);
  CHECK(table.find<BumperReading>("bumpers") == &bumpers);
  CHECK(table.find<LaserScan>("bumpers") == nullptr);  // wrong type
  CHECK(table.find<OdometryReading>("odometry") == nullptr);
  CHECK(table.first<BatteryReading>() == &battery);
  CHECK(table.first<GyroReading>() == nullptr);
  CHECK(table.find("odom") == &odom);

  table.poll_all(Time{5ms});
  CHECK_FALSE(bumpers.has_reading());
  bumpers.device_mask = 0b0101;
  bumpers.device_has_data = true;
  table.poll_all(Time{6ms});
  CHECK(bumpers.latest().any());
  CHECK(bumpers.latest().pressed_mask == 5);
  CHECK(bumpers.stamp() == Time{6ms});
  CHECK(bumpers.is_fresh(Time{56ms}));
  CHECK(bumpers.is_stale(Time{57ms}));
}

TEST_CASE("Every reading kind has a resource manifest naming what it provides") {
  const std::pair<const ModuleManifest*, const char*> all[] = {
      {&resource_manifest<OdometryReading>(), "odometry"}, {&resource_manifest<LaserScan>(), "laser_scan"},
      {&resource_manifest<SonarReading>(), "sonar"},       {&resource_manifest<InfraredReading>(), "infrared"},
      {&resource_manifest<BumperReading>(), "bumpers"},    {&resource_manifest<BatteryReading>(), "battery"},
      {&resource_manifest<GyroReading>(), "gyro"}};
  for (const auto& [m, out] : all) {
    CHECK(m->kind == ModuleKind::resource);
    CHECK(m->layer == Layer::reactive);
    REQUIRE(m->outputs.size() == 1);
    CHECK(m->outputs[0] == out);
  }
  GyroResource gyro("gyro");
  CHECK(gyro.manifest().name == "GyroResource");
  CHECK(gyro.reading_type() == typeid(GyroReading));
}
