#include "core/camera.hpp"

#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab {
namespace {

using driftlab::test::kEps;
// Pixel and metre quantities of order 1e2-1e3 after a handful of operations.
constexpr double kPxTol = 1e-10;
constexpr double kMetreTol = 1e-10;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

PinholeCamera non_square_camera() {
  PinholeCamera c;
  c.fx = 500.0;
  c.fy = 400.0;
  c.cx = 320.0;
  c.cy = 240.0;
  return c;
}

TEST(CameraTest, DefaultsAreValidAndCentred) {
  const PinholeCamera c;
  EXPECT_EQ(validate(c), "");
  EXPECT_EQ(c.width, 640);
  EXPECT_EQ(c.height, 480);
  // OpenCV convention: pixel centres at integers, so the image centre is ((w-1)/2, (h-1)/2).
  EXPECT_EQ(c.project(Vec3(0, 0, 5)), Eigen::Vector2d(319.5, 239.5));
  EXPECT_EQ(validate(StereoRig{}), "");
  EXPECT_EQ(StereoRig{}.baseline_m, 0.12);
}

TEST(CameraTest, HandComputedProjection) {
  // u = 500 * 1 / 10 + 320 = 370; v = 400 * (-0.5) / 10 + 240 = 220.
  const Eigen::Vector2d px = non_square_camera().project(Vec3(1.0, -0.5, 10.0));
  EXPECT_NEAR(px.x(), 370.0, kPxTol);
  EXPECT_NEAR(px.y(), 220.0, kPxTol);
}

TEST(CameraTest, ProjectUnprojectRoundTrip) {
  const PinholeCamera c = non_square_camera();
  std::mt19937 gen(2015);
  std::uniform_real_distribution<double> xy(-20.0, 20.0);
  std::uniform_real_distribution<double> z(0.5, 200.0);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 p(xy(gen), xy(gen), z(gen));
    const Vec3 back = c.unproject(c.project(p), p.z());
    EXPECT_TRUE(back.isApprox(p, 1e3 * kEps)) << p.transpose() << " -> " << back.transpose();
  }
}

TEST(CameraTest, ProjectRequiresPointInFront) {
  const PinholeCamera c;
  EXPECT_THROW(c.project(Vec3(0, 0, 0)), InternalError);
  EXPECT_THROW(c.project(Vec3(1, 1, -2)), InternalError);
  EXPECT_THROW(c.project(Vec3(0, 0, kNaN)), InternalError);
  EXPECT_THROW(c.unproject(Eigen::Vector2d(1, 1), 0.0), InternalError);
}

TEST(CameraTest, InImageUsesHalfPixelBorders) {
  const PinholeCamera c;  // 640 x 480
  EXPECT_TRUE(c.in_image({-0.5, -0.5}));
  EXPECT_TRUE(c.in_image({639.4999, 479.4999}));
  EXPECT_TRUE(c.in_image({319.5, 239.5}));
  EXPECT_FALSE(c.in_image({639.5, 100.0}));
  EXPECT_FALSE(c.in_image({100.0, 479.5}));
  EXPECT_FALSE(c.in_image({-0.5001, 100.0}));
  EXPECT_FALSE(c.in_image({100.0, -0.5001}));
  EXPECT_FALSE(c.in_image({kNaN, 100.0}));
}

TEST(CameraTest, IntrinsicMatrix) {
  Eigen::Matrix3d expected;
  expected << 500, 0, 320,  //
      0, 400, 240,          //
      0, 0, 1;
  const PinholeCamera c = non_square_camera();
  EXPECT_EQ(c.K(), expected);
  // K p / z is the projection.
  const Vec3 p(2.0, 3.0, 7.0);
  EXPECT_TRUE((c.K() * p).hnormalized().isApprox(c.project(p), kPxTol));
}

TEST(StereoTest, DisparityMatchesEq1ByHand) {
  StereoRig rig;
  rig.camera.fx = 500.0;
  rig.baseline_m = 0.12;
  // Eq. (1): D = f B / Z = 500 * 0.12 / 20 = 3 px.
  EXPECT_NEAR(rig.disparity_from_depth(20.0), 3.0, kPxTol);
  EXPECT_NEAR(rig.depth_from_disparity(3.0), 20.0, kMetreTol);
  EXPECT_NEAR(rig.depth_from_disparity(60.0), 1.0, kMetreTol);
  EXPECT_EQ(rig.depth_from_disparity(0.0), kInf);
  EXPECT_EQ(rig.depth_from_disparity(-1.0), kInf);
  EXPECT_THROW(rig.disparity_from_depth(0.0), InternalError);
}

TEST(StereoTest, ProjectRightShiftsByEq1Disparity) {
  StereoRig rig;
  rig.camera = non_square_camera();
  rig.baseline_m = 0.3;
  const Vec3 p(1.5, -2.0, 12.0);
  const Eigen::Vector2d l = rig.camera.project(p);
  const Eigen::Vector2d r = rig.project_right(p);
  // Rectified: same row, right image shifted left by f B / Z = 500 * 0.3 / 12 = 12.5 px.
  EXPECT_NEAR(r.y(), l.y(), kPxTol);
  EXPECT_NEAR(l.x() - r.x(), 12.5, kPxTol);
}

TEST(StereoTest, TriangulateRecoversProjectedPoints) {
  StereoRig rig;
  rig.camera = non_square_camera();
  rig.baseline_m = 0.25;
  std::mt19937 gen(77);
  std::uniform_real_distribution<double> xy(-10.0, 10.0);
  std::uniform_real_distribution<double> z(1.0, 100.0);
  for (int i = 0; i < 1000; ++i) {
    const Vec3 p(xy(gen), xy(gen), z(gen));
    const Eigen::Vector2d l = rig.camera.project(p);
    const Eigen::Vector2d r = rig.project_right(p);
    const Vec3 back = rig.triangulate(l, l.x() - r.x());
    EXPECT_TRUE(back.isApprox(p, 1e-9)) << p.transpose() << " -> " << back.transpose();
  }
  EXPECT_THROW(rig.triangulate({1.0, 1.0}, 0.0), InternalError);
}

TEST(StereoTest, TLeftRightIsBaselineAlongOpticalX) {
  StereoRig rig;
  rig.baseline_m = 0.5;
  const SE3 T = rig.T_left_right();
  EXPECT_EQ(T.translation(), Vec3(0.5, 0.0, 0.0));
  EXPECT_EQ(T.quaternion().coeffs(), Quat::Identity().coeffs());
  // project_right must agree with moving the point into the right frame explicitly.
  const Vec3 p_left(0.7, 0.2, 9.0);
  const Vec3 p_right = T.inverse() * p_left;
  EXPECT_TRUE(rig.project_right(p_left).isApprox(rig.camera.project(p_right), kPxTol));
}

TEST(CameraValidateTest, NamesTheFieldTheValueAndTheExpectation) {
  PinholeCamera c;
  c.fx = -1.0;
  EXPECT_EQ(validate(c), "fx: got -1, expected a finite value > 0");

  c = PinholeCamera{};
  c.fy = kNaN;
  EXPECT_EQ(validate(c), "fy: got nan, expected a finite value > 0");

  c = PinholeCamera{};
  c.fx = kInf;
  EXPECT_EQ(validate(c), "fx: got inf, expected a finite value > 0");

  c = PinholeCamera{};
  c.width = 0;
  EXPECT_EQ(validate(c), "width: got 0, expected > 0");

  c = PinholeCamera{};
  c.height = -3;
  EXPECT_EQ(validate(c), "height: got -3, expected > 0");

  c = PinholeCamera{};
  c.cx = 640.0;
  EXPECT_EQ(validate(c), "cx: got 640, expected in [0, 640)");

  c = PinholeCamera{};
  c.cy = -0.25;
  EXPECT_EQ(validate(c), "cy: got -0.25, expected in [0, 480)");
}

TEST(CameraValidateTest, ReportsEveryBadField) {
  PinholeCamera c;
  c.fx = 0.0;
  c.cy = 1000.0;
  EXPECT_EQ(validate(c),
            "fx: got 0, expected a finite value > 0; cy: got 1000, expected in [0, 480)");
}

TEST(CameraValidateTest, StereoRigPrefixesCameraFieldsAndChecksBaseline) {
  StereoRig rig;
  rig.baseline_m = 0.0;
  EXPECT_EQ(validate(rig), "baseline_m: got 0, expected a finite value > 0");
  rig.baseline_m = -0.12;
  EXPECT_EQ(validate(rig), "baseline_m: got -0.12, expected a finite value > 0");
  rig = StereoRig{};
  rig.camera.fx = -500.0;
  EXPECT_EQ(validate(rig), "camera.fx: got -500, expected a finite value > 0");
}

}  // namespace
}  // namespace driftlab
