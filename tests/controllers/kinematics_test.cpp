// Kinematics of the bases: inverse-then-forward round trips, known wheel formulas, exact arcs.
#include "tripodal/controllers/kinematics.hpp"

#include <catch2/catch.hpp>
#include <cmath>
#include <numbers>
#include <random>

#include "tripodal/controllers/controller_config.hpp"
#include "tripodal/controllers/differential_drive_controller.hpp"
#include "tripodal/controllers/holonomic_controller.hpp"
#include "tripodal/controllers/ideal_hardware.hpp"

using namespace tripodal;
using namespace std::chrono_literals;

namespace {
constexpr double kPi = std::numbers::pi;

ControllerConfig holonomic(std::string type, HolonomicConfig h) {
  ControllerConfig c;
  c.type = std::move(type);
  c.period = 10ms;
  c.holonomic = std::move(h);
  return c;
}
}  // namespace

TEST_CASE("Differential kinematics round trip") {
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  for (int i = 0; i < 1000; ++i) {
    const Twist2D t{u(rng), 0.0, u(rng)};
    double l = 0, r = 0;
    differential_inverse(0.45, 0.075, t, l, r);
    const Twist2D back = differential_forward(0.45, 0.075, l, r);
    REQUIRE(back.vx_m_s == Approx(t.vx_m_s).margin(1e-12));
    REQUIRE(back.wz_rad_s == Approx(t.wz_rad_s).margin(1e-12));
    REQUIRE(back.vy_m_s == 0.0);
  }
  double l = 0, r = 0;
  differential_inverse(0.4, 0.1, {0.0, 0.0, 1.0}, l, r);  // spin: rims at +-0.2 m/s
  CHECK(l == Approx(-2.0));
  CHECK(r == Approx(2.0));
}

TEST_CASE("Holonomic kinematics round trip for omni and mecanum bases") {
  const double three[] = {kPi / 2, kPi / 2 + 2 * kPi / 3, kPi / 2 + 4 * kPi / 3};
  const double four[] = {0.0, kPi / 2, kPi, 3 * kPi / 2};
  const double five[] = {0.1, 1.3, 2.2, 3.9, 5.0};
  struct Case {
    const char* label;
    ControllerConfig config;
  };
  const Case cases[] = {{"PSR 3-wheel omni", holonomic("omni", omni_base(0.05, 0.2, three))},
                        {"4-wheel omni", holonomic("omni", omni_base(0.06, 0.25, four))},
                        {"5-wheel irregular omni", holonomic("omni", omni_base(0.04, 0.3, five))},
                        {"mecanum", holonomic("mecanum", mecanum_base(0.05, 0.2, 0.15))}};
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  for (const Case& c : cases) {
    SECTION(c.label) {
      IdealWheelHardware hw(c.config.holonomic.wheels.size(), 10ms);
      HolonomicController ctl(c.config, hw);
      std::array<double, 8> w{};
      const std::span<double> wheels(w.data(), ctl.wheel_count());
      for (int i = 0; i < 1000; ++i) {
        const Twist2D t{u(rng), u(rng), u(rng)};
        ctl.inverse(t, wheels);
        const Twist2D back = ctl.forward(wheels);
        REQUIRE(back.vx_m_s == Approx(t.vx_m_s).margin(1e-12));
        REQUIRE(back.vy_m_s == Approx(t.vy_m_s).margin(1e-12));
        REQUIRE(back.wz_rad_s == Approx(t.wz_rad_s).margin(1e-12));
      }
    }
  }
}

TEST_CASE("Omni wheel speeds match the textbook formula, mecanum matches the X-arrangement formula") {
  const double three[] = {kPi / 2, kPi / 2 + 2 * kPi / 3, kPi / 2 + 4 * kPi / 3};
  IdealWheelHardware hw3(3, 10ms);
  HolonomicController omni(holonomic("omni", omni_base(0.05, 0.2, three)), hw3);
  const Twist2D t{0.3, -0.2, 0.7};
  std::array<double, 3> w{};
  omni.inverse(t, w);
  for (std::size_t i = 0; i < 3; ++i) {
    const double a = three[i];
    CHECK(w[i] == Approx((-std::sin(a) * t.vx_m_s + std::cos(a) * t.vy_m_s + 0.2 * t.wz_rad_s) / 0.05));
  }
  IdealWheelHardware hw4(4, 10ms);
  HolonomicController mec(holonomic("mecanum", mecanum_base(0.05, 0.2, 0.15)), hw4);
  std::array<double, 4> m{};
  mec.inverse(t, m);
  const double k = 0.2 + 0.15;
  CHECK(m[0] == Approx((t.vx_m_s - t.vy_m_s - k * t.wz_rad_s) / 0.05));  // front-left
  CHECK(m[1] == Approx((t.vx_m_s + t.vy_m_s + k * t.wz_rad_s) / 0.05));  // front-right
  CHECK(m[2] == Approx((t.vx_m_s + t.vy_m_s - k * t.wz_rad_s) / 0.05));  // rear-left
  CHECK(m[3] == Approx((t.vx_m_s - t.vy_m_s + k * t.wz_rad_s) / 0.05));  // rear-right
}

TEST_CASE("Exact arc integration: one step equals many small steps") {
  const Pose2D start{1.0, -2.0, 0.3};
  const double dx = 0.8, dy = 0.1, dth = 1.7;
  const Pose2D one = integrate_body_displacement(start, dx, dy, dth);
  Pose2D many = start;
  constexpr int n = 100000;
  for (int i = 0; i < n; ++i) many = integrate_body_displacement(many, dx / n, dy / n, dth / n);
  CHECK(one.x_m == Approx(many.x_m).margin(1e-9));
  CHECK(one.y_m == Approx(many.y_m).margin(1e-9));
  CHECK(one.theta_rad == Approx(many.theta_rad).margin(1e-9));
  // Half a circle of radius 1 driving forward at curvature 1.
  const Pose2D half = integrate_body_displacement({}, kPi, 0.0, kPi);
  CHECK(half.x_m == Approx(0.0).margin(1e-12));
  CHECK(half.y_m == Approx(2.0));
  CHECK(std::abs(half.theta_rad) == Approx(kPi));
  CHECK(wrap_angle(3 * kPi / 2) == Approx(-kPi / 2));
}

TEST_CASE("Odometry of a circle closes (differential and omni)") {
  // One full turn in 10 s at 100 Hz: 1000 periods.
  const double wz = 2 * kPi / 10.0;
  SECTION("differential") {
    ControllerConfig c;
    c.type = "differential";
    c.period = 10ms;
    c.differential = {0.4, 0.1};
    IdealWheelHardware hw(2, c.period);
    DifferentialDriveController ctl(c, hw);
    ctl.set_command({0.5, 0.0, wz}, Time{0ms});
    double max_dist = 0;
    for (int k = 0; k <= 1000; ++k) {
      ctl.update(Time{k * 10ms});
      max_dist = std::max(max_dist, std::hypot(ctl.odometry().pose.x_m, ctl.odometry().pose.y_m));
    }
    const Pose2D p = ctl.odometry().pose;
    CHECK(std::hypot(p.x_m, p.y_m) < 1e-9);
    CHECK(std::abs(wrap_angle(p.theta_rad)) < 1e-9);
    CHECK(max_dist == Approx(2 * 0.5 / wz).epsilon(1e-6));  // the diameter
    CHECK(ctl.odometry().twist.vx_m_s == Approx(0.5));
    CHECK(ctl.odometry().twist.wz_rad_s == Approx(wz));
  }
  SECTION("omni, translating sideways while turning") {
    const double three[] = {kPi / 2, kPi / 2 + 2 * kPi / 3, kPi / 2 + 4 * kPi / 3};
    ControllerConfig c = holonomic("omni", omni_base(0.05, 0.2, three));
    IdealWheelHardware hw(3, c.period);
    HolonomicController ctl(c, hw);
    ctl.reset_odometry({2.0, 1.0, 0.5});
    ctl.set_command({0.3, 0.4, wz}, Time{0ms});
    double max_dist = 0;
    for (int k = 0; k <= 1000; ++k) {
      ctl.update(Time{k * 10ms});
      const Pose2D q = ctl.odometry().pose;
      max_dist = std::max(max_dist, std::hypot(q.x_m - 2.0, q.y_m - 1.0));
    }
    const Pose2D p = ctl.odometry().pose;
    CHECK(std::hypot(p.x_m - 2.0, p.y_m - 1.0) < 1e-9);
    CHECK(std::abs(wrap_angle(p.theta_rad - 0.5)) < 1e-9);
    CHECK(max_dist == Approx(2 * 0.5 / wz).epsilon(1e-6));  // speed 0.5 m/s
  }
}
