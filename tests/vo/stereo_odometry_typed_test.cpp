// One typed suite for every StereoOdometry implementation (Sophus LieGroupTests style): the
// acceptance cases of the VO issue on exactly rendered sequences (tests/vo/vo_test_sequences.hpp),
// whose ground truth is the generator's poses, never anything the VO computed.
//
// Adding an implementation: write a factory like SparseFactory and add it to Implementations.
#include <cmath>
#include <cstring>
#include <memory>
#include <numbers>
#include <vector>

#include <gtest/gtest.h>

#include <algorithm>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "tests/support/test_support.hpp"
#include "tests/vo/vo_test_sequences.hpp"
#include "vo/dense/dense_vo.hpp"
#include "vo/pnp/pnp_vo.hpp"
#include "vo/sparse/sparse_vo.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::vo {
namespace {

using driftlab::test::kDeg;
// Acceptance of the VO issue: per frame at 0.5 m/frame.
constexpr double kMaxTranslationErrorM = 5e-3;
constexpr double kMaxRotationErrorRad = 0.02 * kDeg;
// Zero motion must give the identity within 0.5 mm (and, we add, within the rotation bound).
constexpr double kZeroMotionTolM = 0.5e-3;
constexpr double kStepM = 0.5;
constexpr double kYawDegPerFrame = 2.0;
constexpr int kFrames = 6;  // 5 motions per sequence

struct SparseFactory {
  static std::unique_ptr<StereoOdometry> make(const StereoRig& rig) {
    return std::make_unique<SparseStereoOdometry>(rig, SparseVoOptions{},
                                                  RngStreams(2015).stream("vo.sparse"));
  }
};

struct SparseKfFactory {  // sparse_kf: keyframes with their shipped thresholds
  static std::unique_ptr<StereoOdometry> make(const StereoRig& rig) {
    SparseVoOptions o;
    o.keyframes = true;
    return std::make_unique<SparseStereoOdometry>(rig, o, RngStreams(2015).stream("vo.sparse_kf"));
  }
};

struct PnpFactory {
  static std::unique_ptr<StereoOdometry> make(const StereoRig& rig) {
    return std::make_unique<PnpStereoOdometry>(rig, PnpVoOptions{},
                                               RngStreams(2015).stream("vo.pnp"));
  }
};

struct DenseFactory {
  static std::unique_ptr<StereoOdometry> make(const StereoRig& rig) {
    return std::make_unique<DenseStereoOdometry>(rig, DenseVoOptions{},
                                                 RngStreams(2015).stream("vo.dense"));
  }
};

using Implementations = ::testing::Types<SparseFactory, SparseKfFactory, PnpFactory, DenseFactory>;

// Rendering dominates the suite's run time: each sequence is rendered once per process.
const test::Sequence& straight_640() {
  static const test::Sequence s = test::make_sequence(
      test::river_bank_scene_640(), test::rig_640x480(), test::straight_poses(kFrames, kStepM));
  return s;
}
const test::Sequence& straight_kitti() {
  static const test::Sequence s = test::make_sequence(
      test::river_bank_scene_kitti(), test::kitti_rig(), test::straight_poses(kFrames, kStepM));
  return s;
}
const test::Sequence& turn_640() {
  static const test::Sequence s =
      test::make_sequence(test::river_bank_scene_640(), test::rig_640x480(),
                          test::turning_poses(kFrames, kStepM, kYawDegPerFrame));
  return s;
}
const test::Sequence& turn_kitti() {
  static const test::Sequence s =
      test::make_sequence(test::river_bank_scene_kitti(), test::kitti_rig(),
                          test::turning_poses(kFrames, kStepM, kYawDegPerFrame));
  return s;
}

StereoFrame uniform_frame(const StereoRig& rig, std::uint8_t grey, TimeNs t_ns) {
  StereoFrame f;
  f.t_ns = t_ns;
  f.left = cv::Mat(rig.camera.height, rig.camera.width, CV_8UC1, cv::Scalar(grey));
  f.right = f.left.clone();
  return f;
}

StereoFrame noise_frame(const StereoRig& rig, std::uint64_t seed, TimeNs t_ns) {
  Rng rng(seed);
  StereoFrame f;
  f.t_ns = t_ns;
  for (cv::Mat* m : {&f.left, &f.right}) {
    *m = cv::Mat(rig.camera.height, rig.camera.width, CV_8UC1);
    for (int v = 0; v < m->rows; ++v)
      for (int u = 0; u < m->cols; ++u)
        m->at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(rng.uniform_int(256));
  }
  return f;
}

// Nothing but water, filling the view 5 m ahead: low ripples that move between frames.
StereoFrame water_frame(const StereoRig& rig, int k) {
  return test::render_stereo(test::water_scene(0.7 * k), rig, SE3(), k * 100'000'000);
}

// Exact equality (SE3::is_approx is strict, so a zero tolerance never holds).
bool same_pose(const SE3& a, const SE3& b) {
  return a.quaternion().coeffs() == b.quaternion().coeffs() && a.translation() == b.translation();
}

void expect_finite(const VoResult& r) {
  EXPECT_TRUE(r.T_prev_curr.translation().allFinite());
  EXPECT_TRUE(r.T_prev_curr.quaternion().coeffs().allFinite());
  EXPECT_TRUE(std::isfinite(r.mean_inlier_depth_m));
  for (const double t :
       {r.times.detect_ms, r.times.match_ms, r.times.estimate_ms, r.times.total_ms})
    EXPECT_TRUE(std::isfinite(t) && t >= 0.0);
  EXPECT_GE(r.matches, 0);
  EXPECT_GE(r.inliers, 0);
  EXPECT_LE(r.inliers, r.matches);
}

void expect_invalid_identity(const VoResult& r) {
  EXPECT_FALSE(r.valid);
  EXPECT_FALSE(r.reason.empty());
  EXPECT_TRUE(same_pose(r.T_prev_curr, SE3())) << "invalid results carry the identity";
  expect_finite(r);
}

// Runs the sequence and checks every frame after the first against the true motion.
void expect_tracks(StereoOdometry* vo, const test::Sequence& seq, double max_t_m,
                   double max_r_rad) {
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    const VoResult r = vo->process(seq.frames[k]);
    expect_finite(r);
    if (k == 0) continue;
    ASSERT_TRUE(r.valid) << "frame " << k << ": " << r.reason;
    const auto e = test::motion_error(r.T_prev_curr, seq.T_prev_curr(k));
    EXPECT_LT(e.translation_m, max_t_m) << "frame " << k << ": " << r.brief();
    EXPECT_LT(e.rotation_rad, max_r_rad) << "frame " << k << ": " << r.brief();
  }
}

template <class Factory>
class StereoOdometryTest : public ::testing::Test {};
TYPED_TEST_SUITE(StereoOdometryTest, Implementations);

TYPED_TEST(StereoOdometryTest, HasAName) {
  EXPECT_FALSE(TypeParam::make(test::rig_640x480())->name().empty());
}

TYPED_TEST(StereoOdometryTest, FirstFrameIsInvalidWithReasonAndIdentity) {
  auto vo = TypeParam::make(test::rig_640x480());
  const VoResult r = vo->process(straight_640().frames[0]);
  expect_invalid_identity(r);
  EXPECT_EQ(r.reason, "first frame");
}

TYPED_TEST(StereoOdometryTest, TracksStraightMotion640x480) {
  auto vo = TypeParam::make(straight_640().rig);
  expect_tracks(vo.get(), straight_640(), kMaxTranslationErrorM, kMaxRotationErrorRad);
}

TYPED_TEST(StereoOdometryTest, TracksStraightMotionKittiRig) {
  auto vo = TypeParam::make(straight_kitti().rig);
  expect_tracks(vo.get(), straight_kitti(), kMaxTranslationErrorM, kMaxRotationErrorRad);
}

TYPED_TEST(StereoOdometryTest, TracksTwoDegreePerFrameYawTurn640x480) {
  auto vo = TypeParam::make(turn_640().rig);
  expect_tracks(vo.get(), turn_640(), kMaxTranslationErrorM, kMaxRotationErrorRad);
}

TYPED_TEST(StereoOdometryTest, TracksTwoDegreePerFrameYawTurnKittiRig) {
  auto vo = TypeParam::make(turn_kitti().rig);
  expect_tracks(vo.get(), turn_kitti(), kMaxTranslationErrorM, kMaxRotationErrorRad);
}

TYPED_TEST(StereoOdometryTest, ZeroMotionGivesIdentity) {
  const test::Sequence& seq = straight_640();
  auto vo = TypeParam::make(seq.rig);
  vo->process(seq.frames[2]);
  StereoFrame again = seq.frames[2];
  again.t_ns += 100'000'000;
  const VoResult r = vo->process(again);
  ASSERT_TRUE(r.valid) << r.reason;
  EXPECT_LT(r.T_prev_curr.translation().norm(), kZeroMotionTolM) << r.brief();
  EXPECT_LT(angle_between(r.T_prev_curr.quaternion(), Quat::Identity()), kMaxRotationErrorRad);
}

TYPED_TEST(StereoOdometryTest, GlobalPoseByEq3FollowsTheTrajectory) {
  // Eq. (3): H_hat <- H_hat H; per-frame errors add up at most linearly.
  const test::Sequence& seq = turn_640();
  auto vo = TypeParam::make(seq.rig);
  SE3 T_world_cam = seq.T_scene_cam[0];
  for (std::size_t k = 0; k < seq.frames.size(); ++k)
    T_world_cam = accumulate_pose(T_world_cam, vo->process(seq.frames[k]));
  const auto e = test::motion_error(T_world_cam, seq.T_scene_cam.back());
  const double motions = static_cast<double>(seq.frames.size() - 1);
  // A rotation error also swings the later steps: allow the lever arm of the path.
  EXPECT_LT(e.translation_m,
            motions * kMaxTranslationErrorM + motions * kMaxRotationErrorRad * motions * kStepM);
  EXPECT_LT(e.rotation_rad, motions * kMaxRotationErrorRad);
}

TYPED_TEST(StereoOdometryTest, AccumulatePoseIgnoresInvalidResults) {
  VoResult invalid;
  invalid.T_prev_curr = SE3::from_translation(Vec3(1.0, 2.0, 3.0));  // must not be applied
  const SE3 T = SE3::from_translation(Vec3(0.5, 0.0, 0.0));
  EXPECT_TRUE(same_pose(accumulate_pose(T, invalid), T));
}

TYPED_TEST(StereoOdometryTest, StatisticsAreConsistent) {
  const test::Sequence& seq = straight_640();
  auto vo = TypeParam::make(seq.rig);
  vo->process(seq.frames[0]);
  const VoResult r = vo->process(seq.frames[1]);
  ASSERT_TRUE(r.valid) << r.reason;
  EXPECT_GT(r.inliers, 20);
  EXPECT_GE(r.matches, r.inliers);
  // The scene's visible depths: the ground from 3.1 m, the backdrop at 40 m.
  EXPECT_GT(r.mean_inlier_depth_m, 3.0);
  EXPECT_LT(r.mean_inlier_depth_m, 40.0);
  // Matching and estimation may overlap (VoStageTimes), detection comes before both.
  EXPECT_GE(r.times.total_ms, r.times.detect_ms + std::max(r.times.match_ms, r.times.estimate_ms));
  EXPECT_GT(r.times.match_ms, 0.0);
  EXPECT_GT(r.times.estimate_ms, 0.0);
  EXPECT_NE(r.brief().find("valid"), std::string::npos);
}

// The result carries its own covariate f (river paper Table 4): pixels with depth for a VO that
// reports a depth map, the inliers otherwise; a VO that reports its matches flags as many
// inliers as it counts.
TYPED_TEST(StereoOdometryTest, CarriesItsOwnCovariateFAndMatches) {
  const test::Sequence& seq = straight_640();
  auto vo = TypeParam::make(seq.rig);
  vo->process(seq.frames[0]);
  const VoResult r = vo->process(seq.frames[1]);
  ASSERT_TRUE(r.valid) << r.reason;
  EXPECT_EQ(r.feature_count(), r.valid_depth_pixels > 0 ? r.valid_depth_pixels : r.inliers);
  EXPECT_GT(r.feature_count(), 20);
  const auto matches = vo->last_matches();
  if (!matches.empty()) {
    const auto flagged =
        std::count_if(matches.begin(), matches.end(), [](const MatchInfo& m) { return m.inlier; });
    EXPECT_EQ(flagged, r.inliers);
  }
}

TYPED_TEST(StereoOdometryTest, BlackFrameIsInvalidWithReason) {
  const test::Sequence& seq = straight_640();
  auto vo = TypeParam::make(seq.rig);
  vo->process(seq.frames[0]);
  expect_invalid_identity(vo->process(uniform_frame(seq.rig, 0, 100'000'000)));
  expect_invalid_identity(vo->process(uniform_frame(seq.rig, 0, 200'000'000)));
}

TYPED_TEST(StereoOdometryTest, FlatFrameIsInvalidWithReason) {
  const test::Sequence& seq = straight_640();
  auto vo = TypeParam::make(seq.rig);
  vo->process(seq.frames[0]);
  expect_invalid_identity(vo->process(uniform_frame(seq.rig, 128, 100'000'000)));
  expect_invalid_identity(vo->process(uniform_frame(seq.rig, 255, 200'000'000)));
}

TYPED_TEST(StereoOdometryTest, WaterFramesAreInvalidWithReason) {
  const StereoRig rig = test::rig_640x480();
  auto vo = TypeParam::make(rig);
  expect_invalid_identity(vo->process(water_frame(rig, 0)));
  for (int k = 1; k < 3; ++k) expect_invalid_identity(vo->process(water_frame(rig, k)));
}

TYPED_TEST(StereoOdometryTest, RecoversAfterAnInvalidFrame) {
  // The VO always advances: after a failure the next pair is measured against the failed one.
  const test::Sequence& seq = straight_640();
  auto vo = TypeParam::make(seq.rig);
  vo->process(seq.frames[0]);
  expect_invalid_identity(vo->process(uniform_frame(seq.rig, 0, 50'000'000)));
  expect_invalid_identity(vo->process(seq.frames[1]));  // measured against the black frame
  const VoResult r = vo->process(seq.frames[2]);
  ASSERT_TRUE(r.valid) << r.reason;
  const auto e = test::motion_error(r.T_prev_curr, seq.T_prev_curr(2));
  EXPECT_LT(e.translation_m, kMaxTranslationErrorM);
  EXPECT_LT(e.rotation_rad, kMaxRotationErrorRad);
}

TYPED_TEST(StereoOdometryTest, NoNanFromNoiseOrUnrelatedFrames) {
  const test::Sequence& seq = straight_640();
  auto vo = TypeParam::make(seq.rig);
  // Scene, noise, noise, scene after noise, water: whatever the verdicts, nothing non-finite.
  expect_finite(vo->process(seq.frames[0]));
  for (std::uint64_t k = 1; k <= 2; ++k) {
    const VoResult r = vo->process(noise_frame(seq.rig, k, static_cast<TimeNs>(k)));
    expect_finite(r);
    EXPECT_EQ(r.valid, r.reason.empty());
  }
  expect_finite(vo->process(seq.frames[3]));
  const VoResult water = vo->process(water_frame(seq.rig, 1));
  expect_finite(water);
  EXPECT_FALSE(water.valid);
}

TYPED_TEST(StereoOdometryTest, ResetStartsOverAndRepeatsTheResults) {
  const test::Sequence& seq = straight_640();
  auto vo = TypeParam::make(seq.rig);
  std::vector<VoResult> first, second;
  for (int k = 0; k < 3; ++k) first.push_back(vo->process(seq.frames[static_cast<std::size_t>(k)]));
  vo->reset();
  for (int k = 0; k < 3; ++k)
    second.push_back(vo->process(seq.frames[static_cast<std::size_t>(k)]));
  EXPECT_EQ(second[0].reason, "first frame");
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(first[k].valid, second[k].valid);
    EXPECT_EQ(first[k].inliers, second[k].inliers);
    EXPECT_TRUE(same_pose(first[k].T_prev_curr, second[k].T_prev_curr));
  }
}

TYPED_TEST(StereoOdometryTest, SameInputGivesTheSameOutputBytes) {
  // Determinism (MuJoCo's PipelineTest style): two instances, same frames, identical bytes of
  // everything but the stage times.
  const test::Sequence& seq = turn_640();
  auto a = TypeParam::make(seq.rig);
  auto b = TypeParam::make(seq.rig);
  for (const StereoFrame& f : seq.frames) {
    const VoResult ra = a->process(f);
    const VoResult rb = b->process(f);
    EXPECT_EQ(ra.valid, rb.valid);
    EXPECT_EQ(ra.reason, rb.reason);
    EXPECT_EQ(ra.matches, rb.matches);
    EXPECT_EQ(ra.inliers, rb.inliers);
    EXPECT_EQ(std::memcmp(ra.T_prev_curr.quaternion().coeffs().data(),
                          rb.T_prev_curr.quaternion().coeffs().data(), 4 * sizeof(double)),
              0);
    EXPECT_EQ(std::memcmp(ra.T_prev_curr.translation().data(), rb.T_prev_curr.translation().data(),
                          3 * sizeof(double)),
              0);
    EXPECT_EQ(std::memcmp(&ra.mean_inlier_depth_m, &rb.mean_inlier_depth_m, sizeof(double)), 0);
  }
}

TYPED_TEST(StereoOdometryTest, RejectsImagesThatDoNotFitTheRig) {
  const StereoRig rig = test::rig_640x480();
  auto vo = TypeParam::make(rig);
  StereoFrame wrong_size = uniform_frame(rig, 100, 0);
  wrong_size.right = cv::Mat(240, 320, CV_8UC1, cv::Scalar(100));
  EXPECT_THROW(vo->process(wrong_size), UserError);
  StereoFrame wrong_type = uniform_frame(rig, 100, 0);
  wrong_type.left = cv::Mat(rig.camera.height, rig.camera.width, CV_32FC1, cv::Scalar(0.5));
  EXPECT_THROW(vo->process(wrong_type), UserError);
  EXPECT_THROW(vo->process(StereoFrame{}), UserError);
  // A rejected frame is not a frame: the next good one is still the first.
  EXPECT_EQ(vo->process(straight_640().frames[0]).reason, "first frame");
}

}  // namespace
}  // namespace driftlab::vo
