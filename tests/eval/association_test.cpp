#include "eval/association.hpp"

#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/test_support.hpp"

#include "core/error.hpp"

namespace driftlab::eval {
namespace {

constexpr TimeNs kMs = 1'000'000;

Trajectory at_stamps(const std::vector<TimeNs>& stamps) {
  Trajectory t;
  for (TimeNs s : stamps) t.push_back({s, SE3::from_translation(Vec3(0.001 * s, 0, 0))});
  return t;
}

using Ids = std::vector<std::size_t>;

TEST(AssociationTest, JitteredStampsPairWithTheirNearestGroundTruth) {
  // Ground truth at 10 Hz; the estimate has every other frame, stamped up to
  // 4 ms early or late, and three frames 30 ms off (no partner within 10 ms).
  std::vector<TimeNs> gt_stamps, est_stamps;
  for (int i = 0; i < 100; ++i) gt_stamps.push_back(1'700'000'000'000'000'000 + i * 100 * kMs);
  Ids expected_gt;
  for (int i = 0; i < 100; i += 2) {
    const TimeNs jitter = ((i * 7) % 9 - 4) * kMs;  // -4 .. 4 ms
    const bool far = i == 10 || i == 50 || i == 98;
    est_stamps.push_back(gt_stamps[i] + (far ? 30 * kMs : jitter));
    if (!far) expected_gt.push_back(i);
  }
  const Association a = associate(at_stamps(gt_stamps), at_stamps(est_stamps), 10 * kMs);
  EXPECT_EQ(a.gt, expected_gt);
  ASSERT_EQ(a.size(), 47u);
  for (std::size_t k = 0; k < a.size(); ++k) EXPECT_EQ(a.gt[k], 2 * a.est[k]);
}

TEST(AssociationTest, ToleranceIsInclusiveToTheNanosecond) {
  const Trajectory gt = at_stamps({0, 100 * kMs, 200 * kMs});
  const Trajectory est = at_stamps({120 * kMs});
  EXPECT_EQ(associate(gt, est, 20 * kMs).gt, Ids{1});
  EXPECT_NE(driftlab::test::user_error_of([&] {
              associate(gt, est, 20 * kMs - 1);
            }).find("no pose of estimate"),
            std::string::npos);
  // Zero tolerance: equal stamps only.
  EXPECT_EQ(associate(gt, at_stamps({100 * kMs}), 0).gt, Ids{1});
}

TEST(AssociationTest, EquallyNearStampsGoToTheEarlier) {
  const Association a =
      associate(at_stamps({0, 10 * kMs, 20 * kMs}), at_stamps({5 * kMs}), kMs * 5);
  EXPECT_EQ(a.gt, Ids{0});
  EXPECT_EQ(a.est, Ids{0});
}

TEST(AssociationTest, EachGroundTruthPoseIsUsedOnceByTheNearestEstimate) {
  // Both estimate poses are nearest to gt 1; evo would pair it twice. Here
  // the nearer (105 ms) keeps it and the 90 ms pose stays unpaired, although
  // gt 0 lies within the tolerance of it.
  const Association a =
      associate(at_stamps({0, 100 * kMs, 200 * kMs}), at_stamps({90 * kMs, 105 * kMs}), 100 * kMs);
  EXPECT_EQ(a.gt, Ids{1});
  EXPECT_EQ(a.est, Ids{1});
  // On an exact tie the earlier estimate keeps it.
  const Association tie =
      associate(at_stamps({0, 100 * kMs, 400 * kMs}), at_stamps({95 * kMs, 105 * kMs}), 10 * kMs);
  EXPECT_EQ(tie.gt, Ids{1});
  EXPECT_EQ(tie.est, Ids{0});
}

TEST(AssociationTest, ALongerEstimateIsMatchedFromTheGroundTruthSide) {
  // evo lets the shorter trajectory drive. Each gt pose takes its nearest
  // estimate: gt 0 (0 s) -> est 0 (0.6 s), gt 1 (1 s) -> est 1 (0.9 s).
  // Driven from the estimate side, est 0 would have gone to gt 1 instead and
  // lost it to est 1, leaving one pair.
  const Trajectory gt = at_stamps({0, 1000 * kMs});
  const Trajectory est = at_stamps({600 * kMs, 900 * kMs, 3000 * kMs});
  const Association a = associate(gt, est, 700 * kMs);
  EXPECT_EQ(a.gt, (Ids{0, 1}));
  EXPECT_EQ(a.est, (Ids{0, 1}));
  // The driven side is de-duplicated too: both gt poses are nearest to est 0;
  // gt 1 (20 ms away) keeps it.
  const Association b = associate(at_stamps({0, 80 * kMs}),
                                  at_stamps({100 * kMs, 1000 * kMs, 2000 * kMs}), 100 * kMs);
  EXPECT_EQ(b.gt, Ids{1});
  EXPECT_EQ(b.est, Ids{0});
}

TEST(AssociationTest, WithEqualSizesTheEstimateDrives) {
  // Same poses as above plus a third gt pose: now est 0 goes to gt 1 and loses it.
  const Association a = associate(at_stamps({0, 1000 * kMs, 5000 * kMs}),
                                  at_stamps({600 * kMs, 900 * kMs, 3000 * kMs}), 700 * kMs);
  EXPECT_EQ(a.gt, Ids{1});
  EXPECT_EQ(a.est, Ids{1});
}

TEST(AssociationTest, BadInputsNameTheTrajectoryAndThePose) {
  const Trajectory good = at_stamps({0, 100 * kMs, 200 * kMs});
  EXPECT_EQ(driftlab::test::user_error_of([&] { associate(good, {}, kMs, "gt.tum", "vo.tum"); }),
            "vo.tum: no poses to evaluate");
  EXPECT_EQ(driftlab::test::user_error_of([&] {
              associate(at_stamps({0, 200 * kMs, 100 * kMs}), good, kMs, "gt.tum");
            }),
            "gt.tum: time stamps must strictly increase, but pose 2 at 0.100000000 s comes before "
            "pose 1 at 0.200000000 s");
  EXPECT_EQ(driftlab::test::user_error_of([&] {
              associate(good, at_stamps({0, 100 * kMs, 100 * kMs}), kMs);
            }),
            "estimate: time stamps must strictly increase, but pose 2 at 0.100000000 s repeats the "
            "stamp of pose 1 at 0.100000000 s");
  Trajectory nan = good;
  nan[1].T_W_C = SE3::from_translation(Vec3(1, std::numeric_limits<double>::quiet_NaN(), 2));
  const std::string msg = driftlab::test::user_error_of([&] { associate(nan, good, kMs); });
  EXPECT_EQ(
      msg.rfind("ground truth: pose 1 at 0.100000000 s is not finite: translation (1, nan, 2)", 0),
      0u)
      << msg;
  EXPECT_EQ(driftlab::test::user_error_of([&] { associate(good, good, -1); }),
            "association tolerance must be >= 0 s, got -0.000000001 s");
}

TEST(AssociationTest, NoOverlapGivesBothStampSpans) {
  const Trajectory gt = at_stamps({10'000 * kMs, 10'100 * kMs, 12'000 * kMs});
  const Trajectory est = at_stamps({20'000 * kMs, 20'500 * kMs});
  EXPECT_EQ(driftlab::test::user_error_of(
                [&] { associate(gt, est, 20 * kMs, "groundtruth.tum", "estimates/vo.tum"); }),
            "no pose of estimates/vo.tum lies within 0.02 s of a pose of groundtruth.tum; the "
            "stamps of estimates/vo.tum span [20.000000000, 20.500000000] s and those of "
            "groundtruth.tum span [10.000000000, 12.000000000] s");
}

}  // namespace
}  // namespace driftlab::eval
