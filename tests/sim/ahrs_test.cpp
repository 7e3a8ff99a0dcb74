// AHRS (the river paper's x-IMU) against closed forms: Madgwick's filter converges to the true
// orientation from a wrong one, and under a steady horizontal acceleration settles where the
// apparent gravity points, atan(a / g) away from level; the simulator reports at its rate.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <string>

#include "core/error.hpp"
#include "core/file_io.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "sim/sensors/ahrs.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim::ahrs_test {
namespace {

constexpr double kG = 9.80665;  // standard gravity, the test's own constant
using driftlab::test::kDeg;

Quat zyx(double roll, double pitch, double yaw) {
  return Quat(Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
              Eigen::AngleAxisd(roll, Vec3::UnitX()));
}

double angle_between(const Quat& a, const Quat& b) { return a.angularDistance(b); }

// A field of 49000 nT, 66.5 deg dip, towards north.
const Vec3 kField_W(49000 * std::cos(66.5 * kDeg), 0.0, 49000 * std::sin(66.5 * kDeg));

TEST(Ahrs, MadgwickConvergesToTheTrueOrientationFromAWrongOne) {
  const Quat truth = zyx(20 * kDeg, -10 * kDeg, 60 * kDeg);
  const Vec3 accel_S = truth.conjugate() * Vec3(0, 0, -kG);  // at rest
  const Vec3 mag_S = truth.conjugate() * kField_W;
  Quat q = Quat::Identity();
  const double beta = 0.1, dt = 1.0 / 512;
  const double start = angle_between(q, truth);
  for (int k = 0; k < 512 * 60; ++k)
    q = madgwick_marg_update(q, Vec3::Zero(), accel_S, mag_S, beta, dt);
  EXPECT_GT(start, 60 * kDeg);
  EXPECT_LT(angle_between(q, truth), 0.01 * kDeg);
}

TEST(Ahrs, SteadyHorizontalAccelerationTiltsTheEstimateByAtanAOverG) {
  // Level, heading north, accelerating forward at a: the accelerometer reads (a, 0, -g) and
  // the filter settles nose up by atan(a / g), where that specific force is "down".
  const double a = 0.5;
  const Vec3 accel_S(a, 0.0, -kG);
  const Vec3 mag_S = kField_W;
  Quat q = Quat::Identity();
  for (int k = 0; k < 512 * 120; ++k)
    q = madgwick_marg_update(q, Vec3::Zero(), accel_S, mag_S, 0.1, 1.0 / 512);
  // The normalised gradient moves the quaternion by beta dt every update, however close it is,
  // a rotation of 2 beta dt: the estimate settles within that step of the closed form.
  const double step = 2 * 0.1 / 512;
  const EulerZYX e = euler_zyx_from_quat(q);
  EXPECT_NEAR(e.pitch_rad, std::atan(a / kG), step);
  EXPECT_NEAR(e.roll_rad, 0.0, step);
  EXPECT_NEAR(e.yaw_rad, 0.0, step);
}

TEST(Ahrs, ASteadyTurnRollsTheReferenceByTheCentripetalTilt) {
  // The hull turns at r rad/s at v m/s: the centripetal acceleration r v points to starboard
  // (+y for a turn to starboard); an ideal unit's estimate settles where that specific force
  // and gravity together point "down": a roll of -atan(r v / g) in FRD.
  AhrsOptions o;
  o.enabled = true;
  o.imu_preset = ImuPreset::kIdeal;
  o.magnetometer_noise_nt = 0.0;
  const double r = 0.2, v = 0.5;
  AhrsSimulator ahrs(o, kField_W, RngStreams(3));
  const int updates = 512 * 120;
  std::optional<AhrsSample> last;
  for (int k = 0; k < updates; ++k) {
    BodySample b;
    b.t_ns = static_cast<TimeNs>(std::llround(k * 1e9 / 512));
    b.state.q_W_B = zyx(0, 0, r * k / 512.0);
    b.state.v_B = Vec3(v, 0, 0);
    b.state.w_B = Vec3(0, 0, r);
    if (auto s = ahrs.update(b)) last = s;
  }
  ASSERT_TRUE(last.has_value());
  const double step = 2 * o.beta_rad_s / o.update_rate_hz;  // as in the test above
  EXPECT_NEAR(last->euler.roll_rad - last->true_euler.roll_rad, -std::atan(r * v / kG), step);
  EXPECT_NEAR(last->euler.pitch_rad - last->true_euler.pitch_rad, 0.0, step);
}

TEST(Ahrs, ReportsEveryFourthUpdateAtTheDefaultRates) {
  AhrsOptions o;
  o.enabled = true;
  AhrsSimulator ahrs(o, kField_W, RngStreams(4));
  int reported = 0;
  for (int k = 0; k < 10; ++k) {
    BodySample b;
    b.t_ns = static_cast<TimeNs>(std::llround(k * 1e9 / 512));
    if (const auto s = ahrs.update(b)) {
      ++reported;
      EXPECT_EQ(k % 4, 0);
      // At rest and level, the unit starts at the truth and its gradient moves it by at most
      // 2 beta dt an update (its gyroscope's noise adds far less: 0.01 deg/s/sqrt(Hz)).
      EXPECT_LE(std::abs(s->euler.roll_rad), 2 * k * o.beta_rad_s / o.update_rate_hz + 1e-5);
    }
  }
  EXPECT_EQ(reported, 3);  // updates 0, 4 and 8
}

TEST(Ahrs, UpdateRateMustBeAWholeMultipleOfTheReportedRate) {
  AhrsOptions o;
  o.update_rate_hz = 500;
  try {
    AhrsSimulator ahrs(o, kField_W, RngStreams(5));
    FAIL() << "expected a UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("sensors.ahrs.update_rate_hz"), std::string::npos)
        << e.what();
  }
}

TEST(Ahrs, CsvHasTheHeaderAndOneRowPerSampleInDegrees) {
  const auto path = std::filesystem::temp_directory_path() / "driftlab_ahrs_test.csv";
  AhrsCsvWriter w(path);
  w.write({1000, {0.1, -0.2, 3.0}, {}});
  w.write({2000, {0.0, 0.0, -1.0}, {}});
  w.commit();
  const std::string text = read_text_file(path);
  std::filesystem::remove(path);
  // The first row's angles, back in radians, are the sample's.
  const std::size_t row = text.find('\n') + 1;
  EXPECT_EQ(text.substr(0, row - 1), "t_ns,roll_deg,pitch_deg,yaw_deg");
  double t = 0, roll = 0, pitch = 0, yaw = 0;
  ASSERT_EQ(std::sscanf(text.c_str() + row, "%lf,%lf,%lf,%lf", &t, &roll, &pitch, &yaw), 4);
  EXPECT_EQ(t, 1000);
  EXPECT_NEAR(roll * kDeg, 0.1, 1e-15);
  EXPECT_NEAR(pitch * kDeg, -0.2, 1e-15);
  EXPECT_NEAR(yaw * kDeg, 3.0, 1e-15);
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 3);
}

}  // namespace
}  // namespace driftlab::sim::ahrs_test
