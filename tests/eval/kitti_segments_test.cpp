#include "eval/kitti_segments.hpp"

#include <cmath>
#include <functional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "tests/support/test_support.hpp"

#include "core/error.hpp"
#include "core/rotation.hpp"

namespace driftlab::eval {
namespace {

// Relative errors of ~1e-2 built from sums of exact integers and one product
// by 1.01: rounding only.
constexpr double kSegmentsTol = 1e-9;

// Poses 1 m apart along x, 0 .. 1000 m (1001 poses), so every path length is
// an exact integer.
std::vector<SE3> straight_1000m(double scale = 1.0, double yaw_per_frame_rad = 0.0) {
  std::vector<SE3> poses;
  for (int i = 0; i <= 1000; ++i) {
    poses.emplace_back(Quat(Eigen::AngleAxisd(yaw_per_frame_rad * i, Vec3::UnitZ())),
                       Vec3(scale * i, 0, 0));
  }
  return poses;
}

// Segments of L m start at frames 0, 10, 20, ...; with 1 m frames the
// segment ends at the first frame strictly more than L m on, f + L + 1, which
// must exist (<= 1000): f <= 999 - L.
std::size_t expected_count(double L) { return static_cast<std::size_t>((999 - L) / 10) + 1; }

TEST(KittiSegmentsTest, OnePercentScaleErrorOnEveryLength) {
  const std::vector<SE3> gt = straight_1000m();
  const std::vector<SE3> est = straight_1000m(1.01);
  const KittiErrors r = kitti_errors(gt, est);
  ASSERT_EQ(r.per_length.size(), 8u);
  double sum = 0.0;
  std::size_t total = 0;
  for (std::size_t k = 0; k < 8; ++k) {
    const KittiSegmentResult& s = r.per_length[k];
    const double L = 100.0 * static_cast<double>(k + 1);
    EXPECT_EQ(s.length_m, L);
    EXPECT_EQ(s.count, expected_count(L)) << L;
    // Each segment spans L + 1 m of ground truth (the end frame is strictly
    // past L), so the 1 % scale error gives 0.01 (L + 1) m, divided by the
    // nominal L as the devkit does.
    EXPECT_NEAR(s.trans_err_pct, (L + 1) / L, kSegmentsTol) << L;
    EXPECT_NEAR(s.rot_err_deg_per_100m, 0.0, kSegmentsTol);
    sum += static_cast<double>(s.count) * (L + 1) / L;
    total += s.count;
  }
  EXPECT_EQ(r.per_length.front().count, 90u);  // f = 0 .. 890
  EXPECT_EQ(r.per_length.back().count, 20u);   // f = 0 .. 190
  // The overall figure averages every segment, not the eight length means.
  EXPECT_EQ(r.overall.length_m, 0.0);
  EXPECT_EQ(r.overall.count, total);
  EXPECT_NEAR(r.overall.trans_err_pct, sum / static_cast<double>(total), kSegmentsTol);
  // The vector form returns the same per-length entries.
  const std::vector<KittiSegmentResult> v = kitti_segment_errors(gt, est);
  ASSERT_EQ(v.size(), 8u);
  EXPECT_EQ(v[3].count, r.per_length[3].count);
  EXPECT_EQ(v[3].trans_err_pct, r.per_length[3].trans_err_pct);
}

TEST(KittiSegmentsTest, RotationDriftPerFrameIsReportedPerHundredMetres) {
  const double alpha = 1e-4;  // rad per frame, about z
  const std::vector<SE3> gt = straight_1000m();
  const std::vector<SE3> est = straight_1000m(1.0, alpha);
  const std::vector<KittiSegmentResult> r = kitti_segment_errors(gt, est);
  ASSERT_EQ(r.size(), 8u);
  for (const KittiSegmentResult& s : r) {
    // L + 1 frames of alpha each, per nominal metre, as degrees per 100 m.
    const double expected = rad2deg(alpha * (s.length_m + 1) / s.length_m) * 100.0;
    EXPECT_NEAR(s.rot_err_deg_per_100m, expected, kSegmentsTol) << s.length_m;
  }
}

TEST(KittiSegmentsTest, CustomLengthsAndStep) {
  std::vector<SE3> gt, est;
  for (int i = 0; i <= 30; ++i) {
    gt.push_back(SE3::from_translation(Vec3(0, i, 0)));
    est.push_back(SE3::from_translation(Vec3(0, 1.01 * i, 0)));
  }
  // 10 m from f ends at f + 11 <= 30: f = 0 .. 19, one start per frame.
  const std::vector<KittiSegmentResult> r = kitti_segment_errors(gt, est, {10.0}, 1);
  ASSERT_EQ(r.size(), 1u);
  EXPECT_EQ(r[0].count, 20u);
  EXPECT_NEAR(r[0].trans_err_pct, 1.1, kSegmentsTol);
  // With step 4: f = 0, 4, 8, 12, 16.
  EXPECT_EQ(kitti_segment_errors(gt, est, {10.0}, 4)[0].count, 5u);
}

TEST(KittiSegmentsTest, LengthsWithoutASegmentAreLeftOut) {
  const std::vector<SE3> gt = straight_1000m();
  const KittiErrors r = kitti_errors(gt, gt, {2000.0, 500.0, 1000.0});
  // 1000 m needs a frame > 1000 m on: there is none.
  ASSERT_EQ(r.per_length.size(), 1u);
  EXPECT_EQ(r.per_length[0].length_m, 500.0);
  EXPECT_EQ(r.per_length[0].trans_err_pct, 0.0);

  const std::vector<SE3> short_gt(gt.begin(), gt.begin() + 50);
  const KittiErrors none = kitti_errors(short_gt, short_gt);
  EXPECT_TRUE(none.per_length.empty());
  EXPECT_EQ(none.overall.count, 0u);
  EXPECT_TRUE(kitti_errors({}, {}).per_length.empty());
}

TEST(KittiSegmentsTest, BadOptionsAreUserErrors) {
  const std::vector<SE3> gt = straight_1000m();
  EXPECT_EQ(driftlab::test::user_error_of([&] {
              kitti_errors(gt, gt, {100.0, -5.0});
            }),
            "KITTI segment length 1 must be a finite number > 0 m, got -5");
  EXPECT_EQ(driftlab::test::user_error_of([&] { kitti_errors(gt, gt, {std::nan("")}); }),
            "KITTI segment length 0 must be a finite number > 0 m, got nan");
  EXPECT_EQ(driftlab::test::user_error_of([&] { kitti_errors(gt, gt, kKittiLengthsM, 0); }),
            "KITTI segment step must be >= 1 frame, got 0");
}

}  // namespace
}  // namespace driftlab::eval
