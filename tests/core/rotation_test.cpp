#include "core/rotation.hpp"

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab {
namespace {

using driftlab::test::kEps;
constexpr double kTightTol = 64 * kEps;
// Angles recovered from a rotation: the extraction loses a few ulps through sin/cos/atan2, and
// next to gimbal lock roll and yaw are individually ill-conditioned by ~1/cos(pitch).
constexpr double kAngleTol = 1e-9;
// Rotations (not angles) must come back to rounding error everywhere, gimbal lock included.
constexpr double kRotationTol = 1e-12;
using driftlab::test::kPi;

// Elementary rotations written out by hand (Fossen 2.18 factors), independent of Eigen::AngleAxis.
Mat3 Rx(double a) {
  Mat3 R;
  R << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);
  return R;
}
Mat3 Ry(double a) {
  Mat3 R;
  R << std::cos(a), 0, std::sin(a), 0, 1, 0, -std::sin(a), 0, std::cos(a);
  return R;
}
Mat3 Rz(double a) {
  Mat3 R;
  R << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return R;
}

TEST(RotationTest, YawNinetyMapsBodyXToWorldY) {
  const Quat q = quat_from_euler_zyx({.roll_rad = 0, .pitch_rad = 0, .yaw_rad = kPi / 2});
  EXPECT_TRUE((q * Vec3::UnitX()).isApprox(Vec3::UnitY(), kTightTol));
}

TEST(RotationTest, PositivePitchRaisesTheBowAndPositiveRollLowersStarboard) {
  // NED: up is -z. Positive pitch puts the bow up; positive roll puts starboard down.
  const Quat pitch = quat_from_euler_zyx({.roll_rad = 0, .pitch_rad = kPi / 2, .yaw_rad = 0});
  EXPECT_TRUE((pitch * Vec3::UnitX()).isApprox(-Vec3::UnitZ(), kTightTol));
  const Quat roll = quat_from_euler_zyx({.roll_rad = kPi / 2, .pitch_rad = 0, .yaw_rad = 0});
  EXPECT_TRUE((roll * Vec3::UnitY()).isApprox(Vec3::UnitZ(), kTightTol));
}

TEST(RotationTest, MatchesProductOfElementaryRotations) {
  const EulerZYX e{.roll_rad = 0.3, .pitch_rad = -0.7, .yaw_rad = 2.1};
  const Mat3 expected = Rz(e.yaw_rad) * Ry(e.pitch_rad) * Rx(e.roll_rad);
  EXPECT_TRUE(quat_from_euler_zyx(e).toRotationMatrix().isApprox(expected, kTightTol));
  EXPECT_NEAR(quat_from_euler_zyx(e).norm(), 1.0, kTightTol);
}

TEST(RotationTest, RoundTripOverGrid) {
  for (double pitch_deg :
       {-89.999, -89.0, -60.0, -30.0, -1e-6, 0.0, 1e-6, 30.0, 60.0, 89.0, 89.999}) {
    for (double roll_deg = -175.0; roll_deg <= 180.0; roll_deg += 25.0) {
      for (double yaw_deg = -180.0 + 1e-9; yaw_deg <= 180.0; yaw_deg += 15.0) {
        const EulerZYX e{deg2rad(roll_deg), deg2rad(pitch_deg), deg2rad(yaw_deg)};
        const Quat q = quat_from_euler_zyx(e);
        const EulerZYX back = euler_zyx_from_quat(q);
        // Away from gimbal lock the angles themselves come back, up to the 2 pi wrap.
        EXPECT_NEAR(wrap_angle_rad(back.roll_rad - e.roll_rad), 0.0, kAngleTol)
            << roll_deg << " " << pitch_deg << " " << yaw_deg;
        EXPECT_NEAR(back.pitch_rad, e.pitch_rad, kAngleTol);
        EXPECT_NEAR(wrap_angle_rad(back.yaw_rad - e.yaw_rad), 0.0, kAngleTol)
            << roll_deg << " " << pitch_deg << " " << yaw_deg;
        EXPECT_LT(angle_between(quat_from_euler_zyx(back), q), kRotationTol);
      }
    }
  }
}

TEST(RotationTest, GimbalLockKeepsTheRotationAndZeroesRoll) {
  for (double pitch : {kPi / 2, -kPi / 2}) {
    for (double roll_deg : {-170.0, -45.0, 0.0, 10.0, 90.0, 180.0}) {
      for (double yaw_deg : {-120.0, 0.0, 33.0, 179.0}) {
        const EulerZYX e{deg2rad(roll_deg), pitch, deg2rad(yaw_deg)};
        const Quat q = quat_from_euler_zyx(e);
        const EulerZYX back = euler_zyx_from_quat(q);
        EXPECT_EQ(back.roll_rad, 0.0) << roll_deg << " " << yaw_deg;
        EXPECT_NEAR(back.pitch_rad, pitch, kAngleTol);
        EXPECT_GE(back.pitch_rad, -kPi / 2);
        EXPECT_LE(back.pitch_rad, kPi / 2);
        // Only yaw -/+ roll is observable at lock: compare rotations, not angles.
        EXPECT_LT(angle_between(quat_from_euler_zyx(back), q), kRotationTol)
            << roll_deg << " " << yaw_deg;
      }
    }
  }
}

TEST(RotationTest, NearGimbalLockRotationIsAccurate) {
  for (double offset : {1e-6, 1e-9, 1e-12, 1e-15}) {
    for (double sign : {1.0, -1.0}) {
      const EulerZYX e{0.8, sign * (kPi / 2 - offset), -2.5};
      const Quat q = quat_from_euler_zyx(e);
      const EulerZYX back = euler_zyx_from_quat(q);
      EXPECT_LT(angle_between(quat_from_euler_zyx(back), q), kRotationTol) << offset;
      EXPECT_LE(std::abs(back.pitch_rad), kPi / 2);
    }
  }
}

TEST(RotationTest, FromMatrixMatchesFromQuatAndAcceptsUnnormalisedQuat) {
  std::mt19937 gen(1234);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    const Quat q(n(gen), n(gen), n(gen), n(gen));
    const EulerZYX a = euler_zyx_from_quat(q);
    const EulerZYX b = euler_zyx_from_matrix(q.normalized().toRotationMatrix());
    EXPECT_NEAR(a.roll_rad, b.roll_rad, kTightTol);
    EXPECT_NEAR(a.pitch_rad, b.pitch_rad, kTightTol);
    EXPECT_NEAR(a.yaw_rad, b.yaw_rad, kTightTol);
    EXPECT_LT(angle_between(quat_from_euler_zyx(a), q.normalized()), kRotationTol);
    EXPECT_LE(std::abs(a.pitch_rad), kPi / 2);
    EXPECT_LE(std::abs(a.roll_rad), kPi);
    EXPECT_LE(std::abs(a.yaw_rad), kPi);
  }
  EXPECT_THROW(euler_zyx_from_quat(Quat(0, 0, 0, 0)), InternalError);
}

TEST(RotationTest, WrapAngleLandsInHalfOpenInterval) {
  EXPECT_EQ(wrap_angle_rad(0.0), 0.0);
  EXPECT_EQ(wrap_angle_rad(kPi), kPi);
  EXPECT_EQ(wrap_angle_rad(-kPi), kPi);  // (-pi, pi]: -pi maps to +pi
  EXPECT_NEAR(wrap_angle_rad(3 * kPi), kPi, kTightTol);
  EXPECT_NEAR(wrap_angle_rad(2 * kPi), 0.0, kTightTol);
  EXPECT_NEAR(wrap_angle_rad(-1.5 * kPi), 0.5 * kPi, kTightTol);
  EXPECT_NEAR(wrap_angle_rad(0.1 + 20 * kPi), 0.1, 1e-13);
  EXPECT_NEAR(wrap_angle_rad(-0.1 - 20 * kPi), -0.1, 1e-13);
  std::mt19937 gen(9);
  std::uniform_real_distribution<double> u(-1e3, 1e3);
  for (int i = 0; i < 1000; ++i) {
    const double a = u(gen);
    const double w = wrap_angle_rad(a);
    EXPECT_GT(w, -kPi);
    EXPECT_LE(w, kPi);
    EXPECT_NEAR(std::remainder(a - w, 2 * kPi), 0.0, 1e-12);
  }
  EXPECT_TRUE(std::isnan(wrap_angle_rad(std::numeric_limits<double>::infinity())));
  EXPECT_TRUE(std::isnan(wrap_angle_rad(std::numeric_limits<double>::quiet_NaN())));
}

TEST(RotationTest, DegreesAndRadians) {
  static_assert(deg2rad(180.0) == std::numbers::pi);
  EXPECT_DOUBLE_EQ(deg2rad(90.0), kPi / 2);
  EXPECT_DOUBLE_EQ(rad2deg(kPi / 4), 45.0);
  EXPECT_DOUBLE_EQ(rad2deg(deg2rad(-33.3)), -33.3);
}

TEST(RotationTest, FrdOpticalMapsCameraAxesOntoTheBody) {
  const Mat3 R = R_frd_optical();
  EXPECT_EQ(R * Vec3::UnitZ(), Vec3::UnitX());  // looking along the bow
  EXPECT_EQ(R * Vec3::UnitX(), Vec3::UnitY());  // image right is starboard
  EXPECT_EQ(R * Vec3::UnitY(), Vec3::UnitZ());  // image down is down
  EXPECT_TRUE((R.transpose() * R).isIdentity(0.0));
  EXPECT_EQ(R.determinant(), 1.0);
  EXPECT_NO_THROW(SE3(R, Vec3::Zero()));
}

}  // namespace
}  // namespace driftlab
