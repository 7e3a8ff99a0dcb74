#include "eval/align.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/test_support.hpp"

#include "core/error.hpp"
#include "core/rotation.hpp"

namespace driftlab::eval {
namespace {

// Closed-form solutions on exact data: only rounding, amplified by the
// conditioning of a well-spread random point cloud, separates them from the truth.
constexpr double kExactTol = 1e-9;

std::vector<Vec3> random_points(std::mt19937& gen, std::size_t n, double extent) {
  std::uniform_real_distribution<double> u(-extent, extent);
  std::vector<Vec3> p;
  for (std::size_t i = 0; i < n; ++i) p.emplace_back(u(gen), u(gen), u(gen));
  return p;
}

Mat3 random_rotation(std::mt19937& gen) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Quat(n(gen), n(gen), n(gen), n(gen)).normalized().toRotationMatrix();
}

std::vector<Vec3> transform(const std::vector<Vec3>& p, double s, const Mat3& R, const Vec3& t) {
  std::vector<Vec3> out;
  for (const Vec3& x : p) out.push_back(s * (R * x) + t);
  return out;
}

Mat3 rot_z(double a) { return Eigen::AngleAxisd(a, Vec3::UnitZ()).toRotationMatrix(); }

void expect_transform(const SimilarityTransform& T, double s, const Mat3& R, const Vec3& t,
                      double tol = kExactTol) {
  EXPECT_NEAR(T.scale, s, tol);
  EXPECT_LE((T.R - R).cwiseAbs().maxCoeff(), tol) << "R =\n" << T.R << "\nexpected\n" << R;
  EXPECT_LE((T.t - t).cwiseAbs().maxCoeff(), tol) << "t = " << T.t.transpose();
  EXPECT_NEAR(T.R.determinant(), 1.0, tol);
}

class AlignExactTest : public ::testing::Test {
 protected:
  std::mt19937 gen{20240611};
  std::vector<Vec3> est = random_points(gen, 40, 50.0);
  Mat3 R = random_rotation(gen);
  Vec3 t{123.5, -47.25, 8.0};
};

TEST_F(AlignExactTest, HornRecoversKnownRigidTransform) {
  expect_transform(align_horn(est, transform(est, 1.0, R, t)), 1.0, R, t);
}

TEST_F(AlignExactTest, UmeyamaSe3RecoversKnownRigidTransform) {
  expect_transform(align_umeyama(est, transform(est, 1.0, R, t), false), 1.0, R, t);
}

TEST_F(AlignExactTest, HornAndUmeyamaAgreeOnExactData) {
  const std::vector<Vec3> gt = transform(est, 1.0, R, t);
  const SimilarityTransform h = align_horn(est, gt);
  expect_transform(align_umeyama(est, gt, false), 1.0, h.R, h.t);
}

TEST_F(AlignExactTest, UmeyamaSim3RecoversScale) {
  const double s = 0.37;
  expect_transform(align_umeyama(est, transform(est, s, R, t), true), s, R, t);
}

TEST_F(AlignExactTest, Se3AlignmentKeepsUnitScaleWhenScalesDiffer) {
  const SimilarityTransform T = align_umeyama(est, transform(est, 2.0, R, t), false);
  EXPECT_EQ(T.scale, 1.0);
  const SimilarityTransform h = align_horn(est, transform(est, 2.0, R, t));
  EXPECT_EQ(h.scale, 1.0);
  // The best rotation of a scaled copy is still R.
  EXPECT_LE((T.R - R).cwiseAbs().maxCoeff(), kExactTol);
  EXPECT_LE((h.R - R).cwiseAbs().maxCoeff(), kExactTol);
}

TEST_F(AlignExactTest, HalfTurnIsRecovered) {
  // w = 0: the quaternion eigenvector has no real part, a corner case for Horn.
  const Mat3 half =
      Eigen::AngleAxisd(std::numbers::pi, Vec3(1, 2, -0.5).normalized()).toRotationMatrix();
  expect_transform(align_horn(est, transform(est, 1.0, half, t)), 1.0, half, t);
  expect_transform(align_umeyama(est, transform(est, 1.0, half, t), false), 1.0, half, t);
}

TEST_F(AlignExactTest, PosYawRecoversYawAndTranslation) {
  // 2.5 rad is past pi/2, so a wrong atan2 quadrant would show.
  const Mat3 Rz = rot_z(2.5);
  expect_transform(align_pos_yaw(est, transform(est, 1.0, Rz, t)), 1.0, Rz, t);
  const Mat3 Rz_neg = rot_z(-3.0);
  expect_transform(align_pos_yaw(est, transform(est, 1.0, Rz_neg, t)), 1.0, Rz_neg, t);
}

TEST(AlignTest, PosYawWorksWithTwoPoints) {
  const std::vector<Vec3> est{{0, 0, 1}, {2, 0, 3}};
  const Mat3 Rz = rot_z(0.25 * std::numbers::pi);
  const Vec3 t(5, 6, 7);
  expect_transform(align_pos_yaw(est, transform(est, 1.0, Rz, t)), 1.0, Rz, t);
}

TEST(AlignTest, HornEqualsUmeyamaOnNoisyPoints) {
  std::mt19937 gen(7);
  const std::vector<Vec3> est = random_points(gen, 200, 30.0);
  std::vector<Vec3> gt = transform(est, 1.0, random_rotation(gen), Vec3(10, -20, 3));
  std::normal_distribution<double> noise(0.0, 0.5);
  for (Vec3& p : gt) p += Vec3(noise(gen), noise(gen), noise(gen));
  const SimilarityTransform h = align_horn(est, gt);
  expect_transform(align_umeyama(est, gt, false), 1.0, h.R, h.t);
}

double cost(const SimilarityTransform& T, const std::vector<Vec3>& est,
            const std::vector<Vec3>& gt) {
  double c = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) c += (gt[i] - T.apply(est[i])).squaredNorm();
  return c;
}

TEST(AlignTest, PosYawIsStationaryOnNoisyPoints) {
  // An independent check of the closed form: perturbing the yaw or the
  // translation of the optimum can only raise the cost.
  std::mt19937 gen(11);
  const std::vector<Vec3> est = random_points(gen, 100, 20.0);
  std::vector<Vec3> gt = transform(est, 1.0, rot_z(-1.2), Vec3(3, 4, 5));
  std::normal_distribution<double> noise(0.0, 0.3);
  for (Vec3& p : gt) p += Vec3(noise(gen), noise(gen), noise(gen));
  const SimilarityTransform best = align_pos_yaw(est, gt);
  const double c0 = cost(best, est, gt);
  for (double dyaw : {-1e-4, 1e-4}) {
    SimilarityTransform T = best;
    T.R = rot_z(dyaw) * best.R;
    // The best translation for the perturbed yaw, so only the yaw is tested.
    Vec3 sum_est = Vec3::Zero(), sum_gt = Vec3::Zero();
    for (std::size_t i = 0; i < est.size(); ++i) {
      sum_est += est[i];
      sum_gt += gt[i];
    }
    T.t = (sum_gt - T.R * sum_est) / static_cast<double>(est.size());
    EXPECT_GT(cost(T, est, gt), c0);
  }
  for (int axis = 0; axis < 3; ++axis) {
    SimilarityTransform T = best;
    T.t(axis) += 1e-3;
    EXPECT_GT(cost(T, est, gt), c0);
  }
}

TEST(AlignTest, ReflectedCopyGivesAProperRotation) {
  // Umeyama's reflection fix: the mirror image is best matched by a rotation,
  // never by the reflection itself; Horn (quaternions) cannot reflect at all.
  std::mt19937 gen(3);
  const std::vector<Vec3> est = random_points(gen, 30, 10.0);
  std::vector<Vec3> gt = est;
  for (Vec3& p : gt) p.x() = -p.x();
  const SimilarityTransform u = align_umeyama(est, gt, false);
  const SimilarityTransform h = align_horn(est, gt);
  EXPECT_NEAR(u.R.determinant(), 1.0, kExactTol);
  EXPECT_LE((u.R - h.R).cwiseAbs().maxCoeff(), kExactTol);
}

TEST(AlignTest, SimilarityAppliedToPoseRotatesThenScalesTranslation) {
  SimilarityTransform T;
  T.R = rot_z(0.5 * std::numbers::pi);
  T.t = Vec3(1, 2, 3);
  T.scale = 2.0;
  const Quat q_p(Eigen::AngleAxisd(0.5 * std::numbers::pi, Vec3::UnitX()));
  const SE3 p(q_p, Vec3(1, 0, 0));
  const SE3 out = T.apply(p);
  // translation: 2 * Rz(90) (1, 0, 0) + (1, 2, 3) = (0, 2, 0) + (1, 2, 3)
  EXPECT_LE((out.translation() - Vec3(1, 4, 3)).norm(), kExactTol);
  EXPECT_LE((out.rotation() - T.R * q_p.toRotationMatrix()).cwiseAbs().maxCoeff(), kExactTol);
  EXPECT_LE((T.apply(Vec3(1, 0, 0)) - Vec3(1, 4, 3)).norm(), kExactTol);
  const std::vector<SE3> many = T.apply(std::vector<SE3>{p, p});
  ASSERT_EQ(many.size(), 2u);
  EXPECT_TRUE(many[1].is_approx(out));
}

TEST(AlignTest, ComputeAlignmentDispatches) {
  std::mt19937 gen(5);
  const std::vector<Vec3> est = random_points(gen, 20, 10.0);
  const Mat3 R = random_rotation(gen);
  const Vec3 t(1, 2, 3);
  const std::vector<Vec3> gt = transform(est, 1.5, R, t);
  expect_transform(compute_alignment(Alignment::kSim3, est, gt), 1.5, R, t);
  const std::vector<Vec3> gt_rigid = transform(est, 1.0, R, t);
  expect_transform(compute_alignment(Alignment::kHorn, est, gt_rigid), 1.0, R, t);
  expect_transform(compute_alignment(Alignment::kSe3, est, gt_rigid), 1.0, R, t);
  const std::vector<Vec3> gt_yaw = transform(est, 1.0, rot_z(0.3), t);
  expect_transform(compute_alignment(Alignment::kPosYaw, est, gt_yaw), 1.0, rot_z(0.3), t);
}

TEST(AlignTest, NoneIsIdentityWhateverThePoints) {
  const std::vector<Vec3> one{{1, 2, 3}};
  const SimilarityTransform T = compute_alignment(Alignment::kNone, one, {{4, 5, 6}});
  EXPECT_EQ(T.R, Mat3::Identity());
  EXPECT_EQ(T.t, Vec3::Zero());
  EXPECT_EQ(T.scale, 1.0);
}

TEST(AlignTest, FirstNUsesOnlyTheFirstPairs) {
  std::mt19937 gen(9);
  const std::vector<Vec3> est = random_points(gen, 30, 10.0);
  const Mat3 R = random_rotation(gen);
  const Vec3 t(-4, 0.5, 2);
  std::vector<Vec3> gt = transform(est, 1.0, R, t);
  // Pairs past the first 10 are far off: they must not pull the fit.
  for (std::size_t i = 10; i < gt.size(); ++i) gt[i] += Vec3(100, -50, 20);
  expect_transform(compute_alignment(Alignment::kSe3, est, gt, 10), 1.0, R, t);
  expect_transform(compute_alignment(Alignment::kHorn, est, gt, 10), 1.0, R, t);
  // More than there are: all of them, so the fit no longer matches R, t.
  const SimilarityTransform all = compute_alignment(Alignment::kSe3, est, gt, 1000);
  const SimilarityTransform all0 = compute_alignment(Alignment::kSe3, est, gt, 0);
  EXPECT_EQ(all.R, all0.R);
  EXPECT_EQ(all.t, all0.t);
  EXPECT_GT((all.t - t).norm(), 1.0);
}

TEST(AlignTest, BadInputsAreUserErrors) {
  const std::vector<Vec3> two{{0, 0, 0}, {1, 0, 0}};
  driftlab::test::expect_user_error([&] { align_horn(two, two); },
                                    "Horn alignment needs at least 3 associated poses, got 2");
  driftlab::test::expect_user_error(
      [&] { align_umeyama(two, two, false); },
      "SE3 (Umeyama) alignment needs at least 3 associated poses, got 2");
  driftlab::test::expect_user_error(
      [&] { align_umeyama(two, two, true); },
      "Sim3 (Umeyama) alignment needs at least 3 associated poses, got 2");
  driftlab::test::expect_user_error(
      [&] {
        align_pos_yaw({{0, 0, 0}}, {{0, 0, 0}});
      },
      "Position+yaw alignment needs at least 2 associated poses, got 1");
  driftlab::test::expect_user_error([&] { compute_alignment(Alignment::kHorn, two, two, -1); },
                                    "align_first_n must be >= 0, got -1");
  driftlab::test::expect_user_error(
      [&] {
        compute_alignment(Alignment::kSe3, {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}},
                          {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}}, 2);
      },
      "needs at least 3 associated poses, got 2");

  const std::vector<Vec3> spread{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  const std::vector<Vec3> same(4, Vec3(1e5 + 0.1, -3e4, 7.0));
  driftlab::test::expect_user_error(
      [&] { align_horn(same, spread); },
      "Horn alignment is undetermined: all 4 estimate positions coincide");
  driftlab::test::expect_user_error([&] { align_umeyama(spread, same, true); },
                                    "all 4 ground-truth positions coincide");
  const std::vector<Vec3> vertical{{2, 3, 0}, {2, 3, 1}, {2, 3, 5}, {2, 3, -4}};
  driftlab::test::expect_user_error([&] { align_pos_yaw(vertical, spread); },
                                    "all 4 estimate positions coincide in the horizontal plane");

  std::vector<Vec3> bad = spread;
  bad[2].y() = std::numeric_limits<double>::quiet_NaN();
  driftlab::test::expect_user_error([&] { align_horn(bad, spread); },
                                    "estimate position 2 is not finite");
  driftlab::test::expect_user_error([&] { align_pos_yaw(spread, bad); },
                                    "ground-truth position 2 is not finite");
}

TEST(AlignTest, CollinearPointsStillAlignPositions) {
  // A straight run: the roll about the line is unobservable, but the aligned
  // positions are still exact.
  std::vector<Vec3> est;
  for (int i = 0; i < 10; ++i) est.emplace_back(i, 0.5 * i, 0.0);
  std::mt19937 gen(1);
  const Mat3 R = random_rotation(gen);
  const std::vector<Vec3> gt = transform(est, 1.0, R, Vec3(1, 1, 1));
  for (const SimilarityTransform& T : {align_horn(est, gt), align_umeyama(est, gt, false)}) {
    EXPECT_NEAR(T.R.determinant(), 1.0, kExactTol);
    for (std::size_t i = 0; i < est.size(); ++i)
      EXPECT_LE((T.apply(est[i]) - gt[i]).norm(), kExactTol);
  }
}

}  // namespace
}  // namespace driftlab::eval
