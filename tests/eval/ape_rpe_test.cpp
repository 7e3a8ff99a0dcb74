#include "eval/ape_rpe.hpp"

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/test_support.hpp"

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "eval/align.hpp"

namespace driftlab::eval {
namespace {

// Compositions of a few dozen poses: rounding only.
constexpr double kTol = 1e-9;

using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;

Quat axis_angle(double angle_rad, const Vec3& axis) {
  return Quat(Eigen::AngleAxisd(angle_rad, axis.normalized()));
}

// A wandering trajectory with every translation a multiple of 1/4, so that
// adding a dyadic offset is exact.
std::vector<SE3> dyadic_trajectory(std::size_t n) {
  std::mt19937 gen(42);
  std::uniform_int_distribution<int> step(-8, 8);
  std::normal_distribution<double> angle(0.0, 1.0);
  std::vector<SE3> poses;
  Vec3 t(100.0, -20.0, 3.0);
  for (std::size_t i = 0; i < n; ++i) {
    t += 0.25 * Vec3(step(gen), step(gen), step(gen));
    poses.emplace_back(axis_angle(angle(gen), Vec3(angle(gen), angle(gen), angle(gen))), t);
  }
  return poses;
}

// Poses along x at the given positions, identity rotation.
std::vector<SE3> along_x(const std::vector<double>& xs) {
  std::vector<SE3> poses;
  for (double x : xs) poses.push_back(SE3::from_translation(Vec3(x, 0, 0)));
  return poses;
}

std::vector<double> range(int first, int last, double scale = 1.0) {
  std::vector<double> v;
  for (int i = first; i <= last; ++i) v.push_back(scale * i);
  return v;
}

std::vector<Vec3> translations(const std::vector<SE3>& poses) {
  std::vector<Vec3> p;
  for (const SE3& T : poses) p.push_back(T.translation());
  return p;
}

TEST(ApeTest, ConstantOffsetWithoutAlignmentIsThatOffsetExactly) {
  const std::vector<SE3> gt = dyadic_trajectory(50);
  const Vec3 offset(3.0, 4.0, 12.0);  // |offset| = 13
  std::vector<SE3> est;
  for (const SE3& p : gt) est.emplace_back(p.quaternion(), p.translation() + offset);
  const SimilarityTransform none =
      compute_alignment(Alignment::kNone, translations(est), translations(gt));
  const ApeResult r = ape(gt, none.apply(est));
  ASSERT_EQ(r.trans_errors_m.size(), gt.size());
  for (double e : r.trans_errors_m) EXPECT_EQ(e, 13.0);
  EXPECT_EQ(r.trans_m.n, 50u);
  EXPECT_EQ(r.trans_m.mean, 13.0);
  EXPECT_EQ(r.trans_m.rmse, 13.0);
  EXPECT_EQ(r.trans_m.max, 13.0);
  EXPECT_EQ(r.trans_m.std_population, 0.0);
  EXPECT_EQ(r.rot_deg.max, 0.0);
}

TEST(ApeTest, RotationErrorIsTheAngleOfTheRelativeRotation) {
  const std::vector<SE3> gt = dyadic_trajectory(20);
  std::vector<SE3> est;
  const Quat extra = axis_angle(deg2rad(10.0), Vec3(1, -2, 0.5));
  // Left- or right-multiplied, the relative rotation has the same angle.
  for (std::size_t i = 0; i < gt.size(); ++i) {
    const Quat q = i % 2 ? extra * gt[i].quaternion() : gt[i].quaternion() * extra;
    est.emplace_back(q, gt[i].translation());
  }
  const ApeResult r = ape(gt, est);
  EXPECT_NEAR(r.rot_deg.min, 10.0, kTol);
  EXPECT_NEAR(r.rot_deg.max, 10.0, kTol);
  EXPECT_EQ(r.trans_m.max, 0.0);
}

TEST(ApeTest, StatisticsSummariseThePerPoseErrors) {
  const std::vector<SE3> gt = along_x({0, 0, 0, 0});
  const std::vector<SE3> est = along_x({1, -2, 3, 4});
  const ApeResult r = ape(gt, est);
  EXPECT_EQ(r.trans_errors_m, (std::vector<double>{1, 2, 3, 4}));
  EXPECT_DOUBLE_EQ(r.trans_m.mean, 2.5);
  EXPECT_DOUBLE_EQ(r.trans_m.median, 2.5);
  EXPECT_DOUBLE_EQ(r.trans_m.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(r.trans_m.std_population, std::sqrt(1.25));  // evo's std (ddof = 0)
  EXPECT_DOUBLE_EQ(r.trans_m.sse, 30.0);
}

TEST(RpeTest, FrameDeltaOneGivesThePerStepExtraRotation) {
  const std::vector<SE3> gt = dyadic_trajectory(30);
  const SE3 extra = SE3::from_rotation(axis_angle(deg2rad(2.0), Vec3(0.3, 1, -0.2)));
  std::vector<SE3> est{SE3(axis_angle(0.7, Vec3::UnitZ()), Vec3(5, 5, 5))};
  for (std::size_t i = 1; i < gt.size(); ++i)
    est.push_back(est.back() * (gt[i - 1].inverse() * gt[i]) * extra);
  const RpeResult r = rpe(gt, est, RpeOptions{});
  EXPECT_EQ(r.pairs, 29u);
  EXPECT_NEAR(r.rot_deg.min, 2.0, kTol);
  EXPECT_NEAR(r.rot_deg.max, 2.0, kTol);
  EXPECT_LE(r.trans_m.max, kTol);
}

TEST(RpeTest, RelativeErrorIsInverseReferenceMotionTimesEstimatedMotion) {
  // Reference moves 1 m along x; the estimate moves the same 1 m but also
  // turns 90 deg about z. E = dQ^-1 dP = (Rz(90), 0): no translation error.
  // (dP dQ^-1 would give a translation of sqrt(2) m.)
  const std::vector<SE3> gt{SE3(), SE3::from_translation(Vec3(1, 0, 0))};
  const std::vector<SE3> est{SE3(),
                             SE3(axis_angle(0.5 * std::numbers::pi, Vec3::UnitZ()), Vec3(1, 0, 0))};
  const RpeResult r = rpe(gt, est, RpeOptions{});
  EXPECT_EQ(r.pairs, 1u);
  EXPECT_LE(r.trans_m.max, kTol);
  EXPECT_NEAR(r.rot_deg.max, 90.0, kTol);
}

TEST(RpeTest, FramePairsConsecutiveAndAll) {
  const std::vector<SE3> poses(7);
  RpeOptions o;
  o.delta = 2;
  EXPECT_EQ(rpe_pairs(poses, o), (Pairs{{0, 2}, {2, 4}, {4, 6}}));
  o.delta = 3;
  EXPECT_EQ(rpe_pairs(poses, o), (Pairs{{0, 3}, {3, 6}}));
  o.delta = 4;  // ids 0, 4: the trailing poses 5, 6 start nothing
  EXPECT_EQ(rpe_pairs(poses, o), (Pairs{{0, 4}}));
  o.all_pairs = true;
  o.delta = 2;
  EXPECT_EQ(rpe_pairs(poses, o), (Pairs{{0, 2}, {1, 3}, {2, 4}, {3, 5}, {4, 6}}));
  o.delta = 7;
  EXPECT_EQ(rpe_pairs(poses, o), Pairs{});
}

TEST(RpeTest, MetrePairsConsecutiveStartAtTheFirstPoseAtOrPastDelta) {
  const std::vector<SE3> line = along_x(range(0, 10));  // 11 poses, 1 m apart
  RpeOptions o;
  o.unit = DeltaUnit::kMeters;
  o.delta = 2.0;
  // Path 2 is reached at pose 2 (not pose 0), then every 2 m after a reset.
  EXPECT_EQ(rpe_pairs(line, o), (Pairs{{2, 4}, {4, 6}, {6, 8}, {8, 10}}));
  o.delta = 3.0;
  EXPECT_EQ(rpe_pairs(line, o), (Pairs{{3, 6}, {6, 9}}));
  // The 0.5 m overshoot at pose 3 is dropped at the reset, not carried over.
  o.delta = 2.5;
  EXPECT_EQ(rpe_pairs(line, o), (Pairs{{3, 6}, {6, 9}}));
  // The tolerance plays no part in consecutive mode.
  o.tolerance = 0.0;
  EXPECT_EQ(rpe_pairs(line, o), (Pairs{{3, 6}, {6, 9}}));
}

TEST(RpeTest, MetrePairsAllTakeTheNearestPathWithinTolerance) {
  const std::vector<SE3> line = along_x(range(0, 10));
  RpeOptions o;
  o.unit = DeltaUnit::kMeters;
  o.all_pairs = true;
  o.delta = 2.0;
  o.tolerance = 0.1;
  // Pose 9 has only 1 m left: |1 - 2| > 0.2.
  EXPECT_EQ(rpe_pairs(line, o),
            (Pairs{{0, 2}, {1, 3}, {2, 4}, {3, 5}, {4, 6}, {5, 7}, {6, 8}, {7, 9}, {8, 10}}));
  // 2.5 m lies halfway between 2 and 3 m: residual 0.5 > 0.1 * 2.5, no pair.
  o.delta = 2.5;
  EXPECT_EQ(rpe_pairs(line, o), Pairs{});
  // With 0.25 * 2.5 = 0.625 both 2 and 3 m qualify; the tie goes to the
  // nearer index, as numpy's argmin; pose 8 still reaches 2 m, pose 9 does not.
  o.tolerance = 0.25;
  EXPECT_EQ(rpe_pairs(line, o),
            (Pairs{{0, 2}, {1, 3}, {2, 4}, {3, 5}, {4, 6}, {5, 7}, {6, 8}, {7, 9}, {8, 10}}));
}

TEST(RpeTest, MetrePairsAllPickTheFirstPoseOfAStationaryStretch) {
  // The vessel waits at x = 2 for poses 2..4.
  const std::vector<SE3> poses = along_x({0, 1, 2, 2, 2, 3, 4});
  RpeOptions o;
  o.unit = DeltaUnit::kMeters;
  o.all_pairs = true;
  o.delta = 2.4;
  o.tolerance = 0.5;  // 1.2 m
  // From pose 0 the paths are 1, 2, 2, 2, 3, 4: 2 (residual 0.4) beats 3 (0.6),
  // and of the three poses at 2 m the first, pose 2, is taken.
  const Pairs pairs = rpe_pairs(poses, o);
  ASSERT_FALSE(pairs.empty());
  EXPECT_EQ(pairs.front(), (std::pair<std::size_t, std::size_t>{0, 2}));
  // From pose 1: paths 1, 1, 1, 2, 3 -> 2 m at pose 5.
  EXPECT_EQ(pairs[1], (std::pair<std::size_t, std::size_t>{1, 5}));
}

TEST(RpeTest, PairsFromReferenceMeasureThePathAlongGroundTruth) {
  const std::vector<SE3> gt = along_x(range(0, 10));        // 1 m steps
  const std::vector<SE3> est = along_x(range(0, 10, 2.0));  // 2 m steps: scale error
  RpeOptions o;
  o.unit = DeltaUnit::kMeters;
  o.delta = 2.0;
  // Along the estimate 2 m is reached at pose 1 and every pose after:
  // pairs (1, 2) ... (9, 10), each with 2 m estimated against 1 m true.
  const RpeResult along_est = rpe(gt, est, o);
  EXPECT_EQ(along_est.pairs, 9u);
  EXPECT_NEAR(along_est.trans_m.min, 1.0, kTol);
  EXPECT_NEAR(along_est.trans_m.max, 1.0, kTol);
  // Along the ground truth: (2, 4), (4, 6), (6, 8), (8, 10), 4 m against 2 m.
  o.pairs_from_reference = true;
  const RpeResult along_gt = rpe(gt, est, o);
  EXPECT_EQ(along_gt.pairs, 4u);
  EXPECT_NEAR(along_gt.trans_m.min, 2.0, kTol);
  EXPECT_NEAR(along_gt.trans_m.max, 2.0, kTol);
}

TEST(RpeTest, BadOptionsAndEmptySelectionsAreUserErrors) {
  const std::vector<SE3> line = along_x(range(0, 10));
  RpeOptions o;
  o.delta = 0;
  driftlab::test::expect_user_error([&] { rpe(line, line, o); },
                                    "rpe delta must be a finite number > 0, got 0");
  o.delta = 1.5;
  driftlab::test::expect_user_error([&] { rpe(line, line, o); },
                                    "rpe delta in frames must be a whole number, got 1.5");
  o.delta = 1;
  o.tolerance = -0.1;
  driftlab::test::expect_user_error([&] { o.validate(); },
                                    "rpe tolerance must be a finite number >= 0, got -0.1");
  o.tolerance = 0.1;
  o.delta = 11;
  driftlab::test::expect_user_error([&] { rpe(line, line, o); },
                                    "RPE: delta = 11 frames gives no pose pair among 11 poses");
  o.unit = DeltaUnit::kMeters;
  o.delta = 20;
  driftlab::test::expect_user_error(
      [&] { rpe(line, line, o); },
      "RPE: delta = 20 m gives no pose pair among 11 poses (path along the estimate)");
  o.all_pairs = true;
  o.pairs_from_reference = true;
  driftlab::test::expect_user_error(
      [&] { rpe(line, line, o); },
      "(path along the ground truth); try a smaller delta or a larger tolerance");
}

}  // namespace
}  // namespace driftlab::eval
