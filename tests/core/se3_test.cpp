#include "core/se3.hpp"

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
// Exact-arithmetic identities evaluated once or twice in double.
constexpr double kSe3TightTol = 64 * kEps;
// Round trips through exp/log, which lose a few digits near |phi| = pi.
constexpr double kRoundTripTol = 1e-9;
// Central finite differences with step kFdStep: truncation ~h^2, rounding ~eps/h.
constexpr double kFdStep = 1e-5;
constexpr double kFdTol = 1e-8;
using driftlab::test::kPi;

Vec3 random_unit(std::mt19937& gen) {
  std::normal_distribution<double> n(0.0, 1.0);
  Vec3 v(n(gen), n(gen), n(gen));
  return v.normalized();
}

Vec3 random_rotation_vector(std::mt19937& gen, double max_angle) {
  std::uniform_real_distribution<double> angle(0.0, max_angle);
  return angle(gen) * random_unit(gen);
}

Vec6 random_twist(std::mt19937& gen, double max_angle) {
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  Vec6 xi;
  xi << u(gen), u(gen), u(gen), random_rotation_vector(gen, max_angle);
  return xi;
}

Mat3 rot_z(double a) {
  Mat3 R;
  R << std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a), 0, 0, 0, 1;
  return R;
}

TEST(So3Test, HatIsCrossProductAndVeeInvertsIt) {
  const Vec3 a(0.3, -1.2, 2.5);
  const Vec3 b(-0.7, 0.4, 1.1);
  EXPECT_TRUE((hat(a) * b).isApprox(a.cross(b), kSe3TightTol));
  EXPECT_TRUE((hat(a) + hat(a).transpose()).isZero(0.0));
  EXPECT_EQ(vee(hat(a)), a);
}

TEST(So3Test, ExpOfQuarterTurnAboutZMatchesHandWrittenMatrix) {
  Mat3 expected;
  expected << 0, -1, 0,  //
      1, 0, 0,           //
      0, 0, 1;
  const Quat q = so3_exp(Vec3(0, 0, kPi / 2));
  EXPECT_TRUE(q.toRotationMatrix().isApprox(expected, kSe3TightTol)) << q.toRotationMatrix();
  EXPECT_NEAR(q.norm(), 1.0, kSe3TightTol);
}

TEST(So3Test, ExpLogRoundTripRandom) {
  std::mt19937 gen(20150101);
  for (int i = 0; i < 2000; ++i) {
    const Vec3 phi = random_rotation_vector(gen, kPi - 1e-6);
    const Vec3 back = so3_log(so3_exp(phi));
    EXPECT_TRUE(back.isApprox(phi, kRoundTripTol)) << phi.transpose() << " -> " << back.transpose();
    EXPECT_LE(back.norm(), kPi);
  }
}

TEST(So3Test, LogOfRandomQuaternionIsWithinPiAndExpsBack) {
  std::mt19937 gen(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const Quat q(n(gen), n(gen), n(gen), n(gen));  // any sign of w, not unit length
    const Vec3 phi = so3_log(q);
    EXPECT_LE(phi.norm(), kPi + kSe3TightTol);
    EXPECT_LT(angle_between(so3_exp(phi), q.normalized()), kRoundTripTol);
  }
}

TEST(So3Test, SmallAngleExpAndLogAreFiniteAndAccurate) {
  for (double angle : {0.0, 1e-300, 1e-12, 1e-8, 1e-4, 0.999e-3, 1.001e-3}) {
    const Vec3 phi = angle * Vec3(1, -2, 3).normalized();
    const Quat q = so3_exp(phi);
    ASSERT_TRUE(q.coeffs().allFinite()) << angle;
    // To first order q = [1, phi/2]; the next term is O(angle^2) relative.
    EXPECT_NEAR(q.w(), 1.0, angle * angle + kSe3TightTol);
    EXPECT_TRUE((2.0 * q.vec()).isApprox(phi, angle * angle + kSe3TightTol) || angle == 0.0);
    const Vec3 back = so3_log(q);
    ASSERT_TRUE(back.allFinite()) << angle;
    EXPECT_LE((back - phi).norm(), kSe3TightTol * std::max(angle, 1e-300)) << angle;
  }
}

TEST(So3Test, LogNearPi) {
  const Vec3 axis = Vec3(2, -1, 0.5).normalized();
  for (double angle : {kPi - 1e-3, kPi - 1e-9, kPi}) {
    const Vec3 phi = angle * axis;
    const Vec3 back = so3_log(so3_exp(phi));
    EXPECT_LE(back.norm(), kPi + kSe3TightTol);
    // At exactly pi, +axis and -axis are the same rotation.
    EXPECT_TRUE(back.isApprox(phi, kRoundTripTol) || back.isApprox(-phi, kRoundTripTol))
        << angle << ": " << back.transpose();
  }
  // Just past pi the log wraps to the short way round, about the opposite axis.
  const Vec3 back = so3_log(so3_exp((kPi + 1e-6) * axis));
  EXPECT_TRUE(back.isApprox(-(kPi - 1e-6) * axis, kRoundTripTol)) << back.transpose();
}

// J_l is defined by exp(phi + d) = exp(J_l(phi) d) exp(phi) to first order in d.
Mat3 left_jacobian_fd(const Vec3& phi) {
  Mat3 J;
  const Quat q_inv = so3_exp(phi).conjugate();
  for (int k = 0; k < 3; ++k) {
    const Vec3 d = kFdStep * Vec3::Unit(k);
    J.col(k) =
        (so3_log(so3_exp(phi + d) * q_inv) - so3_log(so3_exp(phi - d) * q_inv)) / (2.0 * kFdStep);
  }
  return J;
}

TEST(So3Test, LeftJacobianMatchesFiniteDifferences) {
  std::mt19937 gen(3);
  for (int i = 0; i < 200; ++i) {
    const Vec3 phi = random_rotation_vector(gen, kPi - 0.1);
    EXPECT_LT((so3_left_jacobian(phi) - left_jacobian_fd(phi)).cwiseAbs().maxCoeff(), kFdTol)
        << phi.transpose();
  }
  for (double angle : {0.0, 1e-12, 5e-4, 2e-3}) {  // both sides of the series switch
    const Vec3 phi = angle * Vec3(0.2, 0.9, -0.4).normalized();
    EXPECT_LT((so3_left_jacobian(phi) - left_jacobian_fd(phi)).cwiseAbs().maxCoeff(), kFdTol)
        << angle;
  }
}

TEST(So3Test, LeftJacobianIsContinuousAcrossSeriesSwitch) {
  const Vec3 axis = Vec3(1, 2, 2) / 3.0;
  for (double angle : {1e-3, 1e-8}) {  // our switch, and a common alternative choice
    const Vec3 below = angle * (1.0 - 1e-9) * axis;
    const Vec3 above = angle * (1.0 + 1e-9) * axis;
    // Across the tiny step both Jacobians move by +-hat(step)/2 to first order; a seam between
    // the series and the closed form would show up as a jump on top of that.
    const Mat3 first_order = 0.5 * hat(above - below);
    EXPECT_LT(
        (so3_left_jacobian(above) - so3_left_jacobian(below) - first_order).cwiseAbs().maxCoeff(),
        1e-14);
    EXPECT_LT((so3_left_jacobian_inverse(above) - so3_left_jacobian_inverse(below) + first_order)
                  .cwiseAbs()
                  .maxCoeff(),
              1e-14);
  }
}

TEST(So3Test, LeftJacobianInverseInvertsIt) {
  std::mt19937 gen(11);
  for (int i = 0; i < 500; ++i) {
    const Vec3 phi = random_rotation_vector(gen, kPi);
    const Mat3 product = so3_left_jacobian(phi) * so3_left_jacobian_inverse(phi);
    EXPECT_TRUE(product.isApprox(Mat3::Identity(), 1e-12)) << phi.transpose();
  }
  EXPECT_TRUE(so3_left_jacobian_inverse(Vec3(0, 0, kPi)).allFinite());
}

TEST(Se3Test, ExpLogRoundTripRandomTwists) {
  std::mt19937 gen(42);
  for (int i = 0; i < 2000; ++i) {
    const Vec6 xi = random_twist(gen, kPi - 1e-6);
    const Vec6 back = SE3::exp(xi).log();
    EXPECT_TRUE(back.isApprox(xi, kRoundTripTol)) << xi.transpose() << "\n" << back.transpose();
  }
}

TEST(Se3Test, LogExpRoundTripRandomPoses) {
  std::mt19937 gen(43);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int i = 0; i < 2000; ++i) {
    const SE3 T(Quat(n(gen), n(gen), n(gen), n(gen)), 5.0 * Vec3(n(gen), n(gen), n(gen)));
    const SE3 back = SE3::exp(T.log());
    EXPECT_TRUE(back.is_approx(T, 1e-9, 1e-9)) << T.matrix() << "\n" << back.matrix();
  }
}

TEST(Se3Test, ExpOfPureRotationAboutZMatchesHandWrittenMatrix) {
  Vec6 xi;
  xi << 0, 0, 0, 0, 0, kPi / 2;
  Mat4 expected;
  expected << 0, -1, 0, 0,  //
      1, 0, 0, 0,           //
      0, 0, 1, 0,           //
      0, 0, 0, 1;
  EXPECT_TRUE(SE3::exp(xi).matrix().isApprox(expected, kSe3TightTol)) << SE3::exp(xi).matrix();
}

TEST(Se3Test, ExpOfPureTranslationIsThatTranslation) {
  Vec6 xi;
  xi << 1, -2, 3, 0, 0, 0;
  const SE3 T = SE3::exp(xi);
  EXPECT_EQ(T.translation(), Vec3(1, -2, 3));
  EXPECT_EQ(T.quaternion().coeffs(), Quat::Identity().coeffs());
}

TEST(Se3Test, SmallTwistLogExpIsFiniteAndAccurate) {
  Vec6 xi;
  xi << 1e-12, -2e-12, 3e-12, 1e-12, 1e-12, -1e-12;
  const SE3 T = SE3::exp(xi);
  ASSERT_TRUE(T.matrix().allFinite());
  const Vec6 back = T.log();
  ASSERT_TRUE(back.allFinite());
  EXPECT_LT((back - xi).norm(), kSe3TightTol * 1e-12);
  EXPECT_EQ(SE3().log(), Vec6::Zero());
}

TEST(Se3Test, RotationNearPiRoundTrips) {
  const Vec3 axis = Vec3(-1, 3, 1).normalized();
  Vec6 xi;
  xi << 0.5, -1.5, 2.0, (kPi - 1e-9) * axis;
  const SE3 T = SE3::exp(xi);
  EXPECT_TRUE(SE3::exp(T.log()).is_approx(T, 1e-9, 1e-9));
  EXPECT_TRUE(T.log().isApprox(xi, 1e-6));
}

TEST(Se3Test, CompositionMatchesHandComputedMatrixProduct) {
  // A quarter turn about z, then 1 m along x.
  Mat4 A;
  A << 0, -1, 0, 1,  //
      1, 0, 0, 0,    //
      0, 0, 1, 0,    //
      0, 0, 0, 1;
  // A quarter turn about x, then 2 m along y.
  Mat4 B;
  B << 1, 0, 0, 0,  //
      0, 0, -1, 2,  //
      0, 1, 0, 0,   //
      0, 0, 0, 1;
  // Worked by hand: R_A R_B and R_A t_B + t_A.
  Mat4 AB;
  AB << 0, 0, 1, -1,  //
      1, 0, 0, 0,     //
      0, 1, 0, 0,     //
      0, 0, 0, 1;
  ASSERT_TRUE((A * B).isApprox(AB));  // the hand computation itself
  const SE3 a(A);
  const SE3 b(B);
  EXPECT_TRUE((a * b).matrix().isApprox(AB, kSe3TightTol)) << (a * b).matrix();
  const Vec3 p(0.3, -0.7, 1.9);
  EXPECT_TRUE(((a * b) * p).isApprox(a * (b * p), kSe3TightTol));
  EXPECT_TRUE((a * p).isApprox((A * p.homogeneous()).head<3>(), kSe3TightTol));
}

TEST(Se3Test, InverseMatchesHandComputedAndComposesToIdentity) {
  Mat4 A;
  A << 0, -1, 0, 1,  //
      1, 0, 0, 0,    //
      0, 0, 1, 0,    //
      0, 0, 0, 1;
  // By hand: R^T and -R^T t.
  Mat4 A_inv;
  A_inv << 0, 1, 0, 0,  //
      -1, 0, 0, 1,      //
      0, 0, 1, 0,       //
      0, 0, 0, 1;
  const SE3 a(A);
  EXPECT_TRUE(a.inverse().matrix().isApprox(A_inv, kSe3TightTol)) << a.inverse().matrix();

  std::mt19937 gen(5);
  for (int i = 0; i < 100; ++i) {
    const SE3 T = SE3::exp(random_twist(gen, kPi));
    EXPECT_TRUE((T * T.inverse()).is_approx(SE3::identity(), 1e-12, 1e-12));
    EXPECT_TRUE((T.inverse() * T).is_approx(SE3::identity(), 1e-12, 1e-12));
  }
}

TEST(Se3Test, InterpolationMidpointOfQuarterTurn) {
  // b: quarter turn about z with 2 m along x. In the plane that is a pure rotation about
  // c = (1, 1, 0) (solve (I - R) c = t), so the geodesic midpoint is the 45 deg turn about c,
  // t = c - R45 c = (1, 1 - sqrt 2, 0).
  const SE3 a = SE3::identity();
  const SE3 b(rot_z(kPi / 2), Vec3(2, 0, 0));
  const SE3 mid = SE3::interpolate(a, b, 0.5);
  EXPECT_TRUE(mid.is_approx(SE3(rot_z(kPi / 4), Vec3(1, 1 - std::sqrt(2.0), 0)), 1e-12, 1e-12))
      << mid.matrix();
  // Decoupled: slerp to 45 deg and the straight-line midpoint.
  const SE3 mid_dec = SE3::interpolate_decoupled(a, b, 0.5);
  EXPECT_TRUE(mid_dec.is_approx(SE3(rot_z(kPi / 4), Vec3(1, 0, 0)), 1e-12, 1e-12))
      << mid_dec.matrix();
  for (double s : {0.0, 1.0}) {
    const SE3& end = s == 0.0 ? a : b;
    EXPECT_TRUE(SE3::interpolate(a, b, s).is_approx(end, 1e-12, 1e-12));
    EXPECT_TRUE(SE3::interpolate_decoupled(a, b, s).is_approx(end, 1e-12, 1e-12));
  }
}

TEST(Se3Test, DecoupledInterpolationTakesShortWayWhateverTheQuaternionSign) {
  const Quat qa = so3_exp(Vec3(0, 0, 0.1));
  const Quat qb = so3_exp(Vec3(0, 0, 0.3));
  const Quat qb_flipped(-qb.w(), -qb.x(), -qb.y(), -qb.z());
  const SE3 mid =
      SE3::interpolate_decoupled(SE3::from_rotation(qa), SE3::from_rotation(qb_flipped), 0.5);
  EXPECT_LT(angle_between(mid.quaternion(), so3_exp(Vec3(0, 0, 0.2))), 1e-12);
}

TEST(Se3Test, RejectsNonOrthonormalRotation) {
  EXPECT_THROW(SE3(Mat3(1.01 * Mat3::Identity()), Vec3::Zero()), InternalError);
  Mat3 shear = Mat3::Identity();
  shear(0, 1) = 1e-4;
  EXPECT_THROW(SE3(shear, Vec3::Zero()), InternalError);
  const Mat3 reflection = Vec3(1, 1, -1).asDiagonal();
  EXPECT_THROW(SE3(reflection, Vec3::Zero()), InternalError);
  Mat3 nan_R = Mat3::Identity();
  nan_R(1, 1) = std::numeric_limits<double>::quiet_NaN();
  EXPECT_THROW(SE3(nan_R, Vec3::Zero()), InternalError);

  Mat3 nearly = rot_z(0.3);
  nearly(0, 0) += 1e-9;  // well inside the tolerance: accepted and re-orthonormalised
  const SE3 T(nearly, Vec3::Zero());
  EXPECT_NEAR(T.quaternion().norm(), 1.0, kSe3TightTol);

  Mat4 bad_bottom = Mat4::Identity();
  bad_bottom(3, 0) = 1.0;
  EXPECT_THROW(SE3{bad_bottom}, InternalError);
}

TEST(Se3Test, QuaternionIsNormalisedAndZeroRejected) {
  const SE3 T(Quat(2, 0, 0, 0), Vec3(1, 2, 3));
  EXPECT_DOUBLE_EQ(T.quaternion().norm(), 1.0);
  EXPECT_THROW(SE3(Quat(0, 0, 0, 0), Vec3::Zero()), InternalError);

  // A long chain of products stays on the unit sphere.
  const SE3 step = SE3::exp((Vec6() << 0.1, 0.0, 0.0, 0.01, 0.02, -0.03).finished());
  SE3 chain;
  for (int i = 0; i < 100000; ++i) chain = chain * step;
  EXPECT_NEAR(chain.quaternion().norm(), 1.0, kSe3TightTol);
}

TEST(Se3Test, IsApproxAndAngleBetweenIgnoreQuaternionSign) {
  const Quat q = so3_exp(Vec3(0.4, -0.2, 1.0));
  const Quat minus_q(-q.w(), -q.x(), -q.y(), -q.z());
  EXPECT_LT(angle_between(q, minus_q), kSe3TightTol);
  EXPECT_TRUE(SE3(q, Vec3(1, 2, 3)).is_approx(SE3(minus_q, Vec3(1, 2, 3))));
  EXPECT_NEAR(angle_between(Quat::Identity(), so3_exp(Vec3(0, 1e-10, 0))), 1e-10, 1e-20);
  EXPECT_NEAR(angle_between(Quat::Identity(), so3_exp(Vec3(0, 0, 3.0))), 3.0, 1e-12);
  EXPECT_FALSE(SE3().is_approx(SE3::from_translation(Vec3(1e-6, 0, 0))));
}

}  // namespace
}  // namespace driftlab
