// Sparse-VO specifics: options, the filter masks and suppression against brute force, the
// descriptor SAD, the Eq. (2) Jacobian against finite differences, Gauss-Newton and RANSAC on
// synthetic correspondences, bucketing, match accuracy against exact ray-cast correspondences,
// and determinism down to the bytes.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <future>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <set>
#include <vector>

#include <gtest/gtest.h>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/yaml_io.hpp"
#include "tests/support/test_support.hpp"
#include "tests/vo/determinism.hpp"
#include "tests/vo/vo_test_sequences.hpp"
#include "vo/sparse/circle_matcher.hpp"
#include "vo/sparse/features.hpp"
#include "vo/sparse/shared_detection.hpp"
#include "vo/sparse/sparse_options.hpp"
#include "vo/sparse/sparse_vo.hpp"
#include "vo/sparse/stereo_motion.hpp"

namespace driftlab::vo {
namespace {

using sparse::Descriptor;
using sparse::Feature;
using sparse::FeatureDetector;
using sparse::ImageFeatures;
using sparse::StereoMotionEstimator;
using sparse::StereoPointMatch;

using driftlab::test::kDeg;
using driftlab::test::kEps;

const test::Sequence& short_640() {
  static const test::Sequence s = test::make_sequence(
      test::river_bank_scene_640(), test::rig_640x480(), test::turning_poses(3, 0.5, 1.0));
  return s;
}

cv::Mat random_image(int width, int height, std::uint64_t seed) {
  // Smoothed noise: blobs and corners of every strength, some plateaus after rounding.
  Rng rng(seed);
  cv::Mat coarse(height / 4 + 2, width / 4 + 2, CV_8UC1);
  for (int v = 0; v < coarse.rows; ++v)
    for (int u = 0; u < coarse.cols; ++u)
      coarse.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(rng.uniform_int(256));
  cv::Mat img(height, width, CV_8UC1);
  for (int v = 0; v < height; ++v)
    for (int u = 0; u < width; ++u) {
      const double cu = u / 4.0, cv_ = v / 4.0;
      const int iu = static_cast<int>(cu), iv = static_cast<int>(cv_);
      const double a = cu - iu, b = cv_ - iv;
      const double g = (1 - a) * (1 - b) * coarse.at<std::uint8_t>(iv, iu) +
                       a * (1 - b) * coarse.at<std::uint8_t>(iv, iu + 1) +
                       (1 - a) * b * coarse.at<std::uint8_t>(iv + 1, iu) +
                       a * b * coarse.at<std::uint8_t>(iv + 1, iu + 1);
      img.at<std::uint8_t>(v, u) =
          static_cast<std::uint8_t>(std::clamp(g + rng.uniform(-8.0, 8.0), 0.0, 255.0));
    }
  return img;
}

// ---------------------------------------------------------------------------------------------
// Options

TEST(SparseVoOptionsTest, DefaultsAreThePapersValues) {
  const SparseVoOptions o;
  EXPECT_EQ(o.descriptor_window_px, 11);  // river paper 2.3.1 (ii)
  EXPECT_EQ(o.bucket_width_px, 50);       // "50x50 pixel window"
  EXPECT_EQ(o.bucket_height_px, 50);
  EXPECT_EQ(o.max_features_per_bucket, 2);  // "reduced to two"
  EXPECT_EQ(o.ransac_iterations, 50);       // "50 times"
  EXPECT_EQ(o.ransac_sample_size, 3);       // "three randomly-selected matches"
  EXPECT_TRUE(o.final_refinement);          // "used in a final optimisation"
  EXPECT_EQ(o.inlier_threshold_px, 1.0);    // ours, not libviso2's 2 px (documented)
  EXPECT_EQ(yaml::validate(o), "");
}

TEST(SparseVoOptionsTest, ValidationNamesTheFieldAndValue) {
  SparseVoOptions o;
  o.descriptor_window_px = 10;
  o.bucket_width_px = 0;
  o.inlier_threshold_px = -1.0;
  o.min_disparity_px = 300.0;
  const std::string problems = yaml::validate(o);
  EXPECT_NE(problems.find("descriptor_window_px"), std::string::npos) << problems;
  EXPECT_NE(problems.find("odd"), std::string::npos) << problems;
  EXPECT_NE(problems.find("bucket_width_px: got 0"), std::string::npos) << problems;
  EXPECT_NE(problems.find("inlier_threshold_px: got -1"), std::string::npos) << problems;
  EXPECT_NE(problems.find("min_disparity_px"), std::string::npos) << problems;
}

TEST(SparseVoOptionsTest, YamlRoundTripAndStrictKeys) {
  SparseVoOptions o;
  o.nms_radius_px = 4;
  o.inlier_threshold_px = 1.5;
  o.two_stage_matching = false;
  SparseVoOptions back;
  yaml::read_into(yaml::load_string(yaml::to_yaml(o), "test"), {"test", false}, &back);
  EXPECT_EQ(yaml::to_yaml(back), yaml::to_yaml(o));
  EXPECT_EQ(back.nms_radius_px, 4);
  EXPECT_FALSE(back.two_stage_matching);
  SparseVoOptions target;
  EXPECT_THROW(
      yaml::read_into(yaml::load_string("ransac_iteration: 10\n", "t"), {"t", false}, &target),
      UserError);
  EXPECT_THROW(
      yaml::read_into(yaml::load_string("ransac_sample_size: 2\n", "t"), {"t", false}, &target),
      UserError);
}

TEST(SparseVoOptionsTest, ConstructorRejectsBadOptionsAndRigs) {
  SparseVoOptions bad;
  bad.ransac_iterations = 0;
  EXPECT_THROW((void)SparseStereoOdometry(test::rig_640x480(), bad, Rng(1)), UserError);
  StereoRig rig = test::rig_640x480();
  rig.baseline_m = 0.0;
  EXPECT_THROW((void)SparseStereoOdometry(rig, SparseVoOptions{}, Rng(1)), UserError);
  StereoRig tiny = test::rig_640x480();
  tiny.camera.width = 20;
  tiny.camera.height = 20;
  tiny.camera.cx = 9.5;
  tiny.camera.cy = 9.5;
  EXPECT_THROW((void)SparseStereoOdometry(tiny, SparseVoOptions{}, Rng(1)), UserError);
}

// ---------------------------------------------------------------------------------------------
// Detection: StereoScan's 5x5 masks (Geiger et al. 2011, Fig. 3), written out independently.

constexpr std::array<std::array<int, 5>, 5> kBlobMask{{{-1, -1, -1, -1, -1},
                                                       {-1, 1, 1, 1, -1},
                                                       {-1, 1, 8, 1, -1},
                                                       {-1, 1, 1, 1, -1},
                                                       {-1, -1, -1, -1, -1}}};
constexpr std::array<std::array<int, 5>, 5> kCornerMask{
    {{-1, -1, 0, 1, 1}, {-1, -1, 0, 1, 1}, {0, 0, 0, 0, 0}, {1, 1, 0, -1, -1}, {1, 1, 0, -1, -1}}};

int convolve(const cv::Mat& img, int x, int y, const std::array<std::array<int, 5>, 5>& mask) {
  int sum = 0;
  for (int dy = -2; dy <= 2; ++dy)
    for (int dx = -2; dx <= 2; ++dx)
      sum += mask[dy + 2][dx + 2] * img.at<std::uint8_t>(y + dy, x + dx);
  return sum;
}

TEST(SparseDetectorTest, ResponsesAreTheBlobAndCornerMasks) {
  const cv::Mat img = random_image(160, 120, 3);
  FeatureDetector det(img.cols, img.rows, SparseVoOptions{});
  std::vector<std::int16_t> blob, corner;
  det.filter_responses(img, &blob, &corner);
  for (int y = 2; y < img.rows - 2; ++y)
    for (int x = 2; x < img.cols - 2; ++x) {
      ASSERT_EQ(blob[static_cast<std::size_t>(y * img.cols + x)], convolve(img, x, y, kBlobMask))
          << x << "," << y;
      ASSERT_EQ(corner[static_cast<std::size_t>(y * img.cols + x)],
                convolve(img, x, y, kCornerMask))
          << x << "," << y;
    }
}

TEST(SparseDetectorTest, SinglePointGivesABlobMaximumAtThePoint) {
  cv::Mat img(64, 64, CV_8UC1, cv::Scalar(20));
  img.at<std::uint8_t>(30, 33) = 220;  // 200 above the background: response 8 * 200
  SparseVoOptions o;
  FeatureDetector det(img.cols, img.rows, o);
  std::vector<std::int16_t> blob, corner;
  det.filter_responses(img, &blob, &corner);
  EXPECT_EQ(blob[30 * 64 + 33], 1600);
  ImageFeatures f;
  det.detect(img, &f);
  int maxima = 0;
  for (const Feature& ft : f.all.features) {
    if (ft.cls != sparse::kBlobMax) continue;
    ++maxima;
    EXPECT_EQ(ft.x, 33);
    EXPECT_EQ(ft.y, 30);
    EXPECT_EQ(ft.response, 1600);
  }
  EXPECT_EQ(maxima, 1);
}

// Brute-force non-maximum/-minimum suppression over (2n+1)^2 windows.
std::vector<std::array<int, 4>> brute_force_features(const cv::Mat& img, int n, int tau,
                                                     int margin) {
  std::vector<std::array<int, 4>> out;  // (class, y, x, response)
  for (int cls = 0; cls < 4; ++cls) {
    const auto& mask = cls < 2 ? kBlobMask : kCornerMask;
    const bool is_max = cls % 2 == 0;
    for (int y = margin; y < img.rows - margin; ++y)
      for (int x = margin; x < img.cols - margin; ++x) {
        const int v = convolve(img, x, y, mask);
        if (is_max ? v < tau : v > -tau) continue;
        bool extremum = true;
        for (int dy = -n; dy <= n && extremum; ++dy)
          for (int dx = -n; dx <= n && extremum; ++dx) {
            const int w = convolve(img, x + dx, y + dy, mask);
            extremum = is_max ? w <= v : w >= v;
          }
        if (extremum) out.push_back({cls, y, x, v});
      }
  }
  std::sort(out.begin(), out.end());
  return out;
}

TEST(SparseDetectorTest, SuppressionMatchesBruteForce) {
  const cv::Mat img = random_image(200, 150, 5);
  for (const int n : {1, 3, 5}) {
    SparseVoOptions o;
    o.nms_radius_px = n;
    o.nms_threshold = 40;
    FeatureDetector det(img.cols, img.rows, o);
    ImageFeatures f;
    det.detect(img, &f);
    std::vector<std::array<int, 4>> got;
    for (const Feature& ft : f.all.features) got.push_back({ft.cls, ft.y, ft.x, ft.response});
    std::sort(got.begin(), got.end());
    const auto expected = brute_force_features(img, n, o.nms_threshold, det.margin());
    EXPECT_GT(expected.size(), 50u);
    EXPECT_EQ(got, expected) << "nms_radius_px " << n;
  }
}

TEST(SparseDetectorTest, SimdPathsGiveIdenticalFeaturesAndGradients) {
  const test::Sequence& seq = short_640();
  const StereoRig& rig = seq.rig;
  FeatureDetector best(rig.camera.width, rig.camera.height, SparseVoOptions{});
  FeatureDetector base(rig.camera.width, rig.camera.height, SparseVoOptions{},
                       FeatureDetector::Simd::kBaseline);
  ImageFeatures a, b;
  best.detect(seq.frames[0].left, &a);
  base.detect(seq.frames[0].left, &b);
  ASSERT_EQ(a.all.features.size(), b.all.features.size());
  EXPECT_EQ(std::memcmp(a.all.features.data(), b.all.features.data(),
                        a.all.features.size() * sizeof(Feature)),
            0);
  EXPECT_TRUE(a.grad == b.grad);
  if (!best.uses_avx2()) GTEST_SKIP() << "no AVX2 on this CPU: both paths were the baseline";
}

TEST(SparseDetectorTest, CoarseSetKeepsTheStrongestPerClassAndBucket) {
  const test::Sequence& seq = short_640();
  SparseVoOptions o;
  FeatureDetector det(seq.rig.camera.width, seq.rig.camera.height, o);
  ImageFeatures f;
  det.detect(seq.frames[0].left, &f);
  std::map<std::pair<int, int>, std::vector<int>> all, coarse;  // (class, bucket) -> |responses|
  auto bucket = [&](const Feature& ft) {
    return (ft.y / o.bucket_height_px) * f.buckets_x + ft.x / o.bucket_width_px;
  };
  for (const Feature& ft : f.all.features)
    all[{ft.cls, bucket(ft)}].push_back(std::abs(ft.response));
  for (const Feature& ft : f.coarse.features)
    coarse[{ft.cls, bucket(ft)}].push_back(std::abs(ft.response));
  for (auto& [key, responses] : all) {
    std::sort(responses.rbegin(), responses.rend());
    responses.resize(std::min<std::size_t>(responses.size(),
                                           static_cast<std::size_t>(o.coarse_features_per_class)));
    auto got = coarse[key];
    std::sort(got.rbegin(), got.rend());
    EXPECT_EQ(got, responses);
  }
}

// ---------------------------------------------------------------------------------------------
// Descriptors and sub-pixel fits

TEST(SparseDescriptorTest, SadMatchesTheReferenceAndStopsEarly) {
  const test::Sequence& seq = short_640();
  for (const int w : {3, 11, 15}) {
    SparseVoOptions o;
    o.descriptor_window_px = w;
    FeatureDetector det(seq.rig.camera.width, seq.rig.camera.height, o);
    ImageFeatures f;
    det.detect(seq.frames[0].left, &f);
    Rng rng(static_cast<std::uint64_t>(w));
    for (int k = 0; k < 200; ++k) {
      const int x0 = 20 + static_cast<int>(rng.uniform_int(600)),
                y0 = 20 + static_cast<int>(rng.uniform_int(440));
      const int x1 = 20 + static_cast<int>(rng.uniform_int(600)),
                y1 = 20 + static_cast<int>(rng.uniform_int(440));
      Descriptor q;
      f.descriptor(x0, y0, &q);
      const std::uint32_t full = f.sad(q, x1, y1, std::numeric_limits<std::uint32_t>::max());
      EXPECT_EQ(full, f.sad_reference(q, x1, y1));
      EXPECT_EQ(f.sad(q, x0, y0, 1), 0u);  // a descriptor matches itself exactly
      const std::uint32_t early = f.sad(q, x1, y1, full / 4 + 1);
      EXPECT_GE(early, full / 4 + 1 > full ? full : full / 4 + 1);
      EXPECT_LE(early, full);
    }
  }
}

TEST(SparseDescriptorTest, EquiangularFitFindsTheApexOfAV) {
  for (const double apex : {-0.5, -0.3, 0.0, 0.12, 0.49}) {
    auto v = [&](double x) { return 7.0 + 40.0 * std::abs(x - apex); };
    EXPECT_NEAR(sparse::equiangular_offset(v(-1), v(0), v(1)), apex, 64 * kEps);
  }
  EXPECT_EQ(sparse::equiangular_offset(5.0, 5.0, 5.0), 0.0);  // flat: no information
}

// ---------------------------------------------------------------------------------------------
// Eq. (2): projection, Jacobian, Gauss-Newton, RANSAC

TEST(SparseMotionTest, ReprojectionJacobianMatchesFiniteDifferences) {
  const StereoRig rig = test::kitti_rig();
  Rng rng(11);
  constexpr double kStep = 1e-6;    // central differences: error ~ step^2 * third derivative
  constexpr double kRelTol = 1e-6;  // relative to the Jacobian's scale (~fx / Z)
  for (int trial = 0; trial < 50; ++trial) {
    Vec6 xi0;
    for (int k = 0; k < 6; ++k) xi0[k] = rng.uniform(-0.2, 0.2);
    const SE3 T = SE3::exp(xi0);
    const Vec3 p(rng.uniform(-5, 5), rng.uniform(-2, 2), rng.uniform(4, 40));
    sparse::Vec4 px;
    sparse::Mat46 J;
    ASSERT_TRUE(sparse::project_stereo(rig, T.rotation(), T.translation(), p, &px, &J));
    for (int k = 0; k < 6; ++k) {
      Vec6 d = Vec6::Zero();
      d[k] = kStep;
      const SE3 Tp = SE3::exp(d) * T, Tm = SE3::exp(-d) * T;  // the left perturbation of the doc
      sparse::Vec4 pp, pm;
      ASSERT_TRUE(sparse::project_stereo(rig, Tp.rotation(), Tp.translation(), p, &pp, nullptr));
      ASSERT_TRUE(sparse::project_stereo(rig, Tm.rotation(), Tm.translation(), p, &pm, nullptr));
      const sparse::Vec4 fd = (pp - pm) / (2 * kStep);
      const double scale = J.cwiseAbs().maxCoeff();
      EXPECT_LT((fd - J.col(k)).cwiseAbs().maxCoeff(), kRelTol * scale) << "column " << k;
    }
  }
}

TEST(SparseMotionTest, ProjectionIsEq1Inverted) {
  // A point triangulated by Eq. (1) projects back to where it was seen, in both images.
  const StereoRig rig = test::rig_640x480();
  const Vec3 p = rig.triangulate(Eigen::Vector2d(400.25, 100.5), 12.75);
  sparse::Vec4 px;
  ASSERT_TRUE(sparse::project_stereo(rig, Mat3::Identity(), Vec3::Zero(), p, &px, nullptr));
  EXPECT_NEAR(px(0), 400.25, 1e-9);
  EXPECT_NEAR(px(1), 100.5, 1e-9);
  EXPECT_NEAR(px(2), 400.25 - 12.75, 1e-9);
  EXPECT_NEAR(px(3), 100.5, 1e-9);
  EXPECT_FALSE(sparse::project_stereo(rig, Mat3::Identity(), Vec3(0, 0, -20), p, &px, nullptr));
}

std::vector<StereoPointMatch> synthetic_matches(const StereoRig& rig, const SE3& T_curr_prev, int n,
                                                double noise_px, double outlier_fraction,
                                                std::uint64_t seed) {
  Rng rng(seed);
  std::vector<StereoPointMatch> out;
  while (static_cast<int>(out.size()) < n) {
    StereoPointMatch m;
    m.p_prev = Vec3(rng.uniform(-6, 6), rng.uniform(-2, 1.5), rng.uniform(3, 40));
    const Vec3 c = T_curr_prev * m.p_prev;
    if (c.z() < 1.0) continue;
    const Eigen::Vector2d l = rig.camera.project(c), r = rig.project_right(c);
    if (!rig.camera.in_image(l) || !rig.camera.in_image(r)) continue;
    m.u_l = l.x() + noise_px * rng.normal();
    m.v_l = l.y() + noise_px * rng.normal();
    m.u_r = r.x() + noise_px * rng.normal();
    m.v_r = m.v_l;
    if (rng.uniform() < outlier_fraction) {
      m.u_l += rng.uniform(-80, 80);
      m.v_l += rng.uniform(-80, 80);
      m.u_r = m.u_l - rng.uniform(0, 30);
      m.v_r = m.v_l;
    }
    out.push_back(m);
  }
  return out;
}

TEST(SparseMotionTest, GaussNewtonRecoversAnExactMotion) {
  const StereoRig rig = test::rig_640x480();
  const SE3 truth(Quat(Eigen::AngleAxisd(3 * kDeg, Vec3(0.1, 1.0, -0.2).normalized())),
                  Vec3(0.05, -0.02, -0.5));
  const auto m = synthetic_matches(rig, truth, 40, 0.0, 0.0, 1);
  std::vector<int> all(m.size());
  for (std::size_t i = 0; i < all.size(); ++i) all[i] = static_cast<int>(i);
  StereoMotionEstimator est(rig, SparseVoOptions{});
  SE3 T;
  ASSERT_TRUE(est.gauss_newton(m, all, &T));
  EXPECT_TRUE(T.is_approx(truth, 1e-9, 1e-10));
}

TEST(SparseMotionTest, GaussNewtonRefusesDegenerateSamples) {
  const StereoRig rig = test::rig_640x480();
  auto m = synthetic_matches(rig, SE3(), 3, 0.0, 0.0, 2);
  m[1] = m[0];
  m[2] = m[0];  // one point three times: rank-deficient
  StereoMotionEstimator est(rig, SparseVoOptions{});
  SE3 T = SE3::from_translation(Vec3(1, 2, 3));
  const std::vector<int> idx{0, 1, 2};
  EXPECT_FALSE(est.gauss_newton(m, idx, &T));
  EXPECT_EQ(T.translation(), Vec3(1, 2, 3)) << "left unchanged";
  EXPECT_EQ(T.quaternion().coeffs(), Quat::Identity().coeffs());
}

TEST(SparseMotionTest, RansacFindsTheMotionAmongOutliers) {
  const StereoRig rig = test::rig_640x480();
  const SE3 truth(Quat(Eigen::AngleAxisd(2 * kDeg, Vec3::UnitY())), Vec3(0.01, 0.0, -0.5));
  const auto m = synthetic_matches(rig, truth, 200, 0.1, 0.3, 3);
  StereoMotionEstimator est(rig, SparseVoOptions{});
  Rng rng(4);
  const auto r = est.estimate(m, &rng);
  ASSERT_TRUE(r.ok) << r.failure;
  EXPECT_TRUE(r.T_curr_prev.is_approx(truth, 5e-3, 0.02 * kDeg));
  // Every inlier agrees with the truth within the threshold; no gross outlier got in.
  for (const int i : *r.inliers) {
    const auto [el, er] = sparse::reprojection_errors(rig, truth.rotation(), truth.translation(),
                                                      m[static_cast<std::size_t>(i)]);
    EXPECT_LT(std::max(el, er), 2.0 + 1.0);
  }
  EXPECT_GT(r.inliers->size(), 120u);
}

// What the default inlier threshold is for (sparse_options.hpp): the river paper's slow boat
// seen by its Bumblebee2 (1024x768, f = 817 px, 0.12 m), 2.3 cm a frame sideways and forwards,
// features 8-50 m away moving 0.4-2.4 px, matched to 0.05 px; and 2 % of stereo matches on
// horizontal edges at a wrong disparity of 28 px (they look 3.5 m away but move like the far
// scene). Within libviso2's 2 px, a turn without translation fits every match, wrong ones
// included, better than the true motion (which rejects the wrong ones), so RANSAC takes it; the
// 1 px default tells them apart. The true motion is the independent expectation.
TEST(SparseMotionTest, SubPixelMotionWithWrongDisparitiesNeedsTheDefaultThreshold) {
  const StereoRig rig = test::bumblebee2_rig();
  const SE3 T_prev_curr = SE3::from_translation(Vec3(-0.020, 0.0, 0.012));
  const SE3 truth = T_prev_curr.inverse();
  auto matches = [&](std::uint64_t seed) {
    Rng rng(seed);
    std::vector<StereoPointMatch> out;
    while (out.size() < 400) {
      const double z = rng.uniform(8, 50);
      const Vec3 p(rng.uniform(-0.6, 0.6) * z, rng.uniform(-0.45, 0.45) * z, z);
      const Vec3 c = truth * p;
      const Eigen::Vector2d l = rig.camera.project(c), r = rig.project_right(c);
      if (!rig.camera.in_image(l) || !rig.camera.in_image(r)) continue;
      StereoPointMatch m;
      m.p_prev = p;
      m.u_l = l.x() + 0.05 * rng.normal();
      m.v_l = l.y() + 0.05 * rng.normal();
      m.u_r = r.x() + 0.05 * rng.normal();
      m.v_r = m.v_l;
      if (out.size() % 50 == 0) {  // a wrong disparity of 28 px, in both frames
        const Eigen::Vector2d l_prev = rig.camera.project(p);
        m.p_prev = rig.triangulate(l_prev, 28.0);
        m.u_r = m.u_l - 28.0;
      }
      out.push_back(m);
    }
    return out;
  };
  SparseVoOptions libviso2;
  libviso2.inlier_threshold_px = 2.0;
  // MSAC (ransac_score msac) at 2 px: the turn fits every match, but loosely; the true motion
  // fits all but the wrong ones to 0.05 px, and its truncated cost is the lower.
  SparseVoOptions msac_2px = libviso2;
  msac_2px.ransac_score = RansacScore::kMsac;
  const SparseVoOptions defaults;
  const std::array<const SparseVoOptions*, 3> variants = {&defaults, &libviso2, &msac_2px};
  std::array<int, 3> failed = {};
  std::array<double, 3> worst_m = {};
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    const auto m = matches(seed);
    for (std::size_t v = 0; v < variants.size(); ++v) {
      StereoMotionEstimator est(rig, *variants[v]);
      Rng rng(100 + seed);
      const auto r = est.estimate(m, &rng);
      ASSERT_TRUE(r.ok) << r.failure;
      const double error_m =
          (r.T_curr_prev.inverse().translation() - T_prev_curr.translation()).norm();
      failed[v] += error_m > 0.25 * T_prev_curr.translation().norm() ? 1 : 0;
      worst_m[v] = std::max(worst_m[v], error_m);
    }
  }
  std::printf(
      "[ sparse   ] 20 frames, motion off by more than 25 %%: %d at 1 px (worst %.2f mm), "
      "%d at 2 px, %d at 2 px with MSAC (worst %.2f mm)\n",
      failed[0], worst_m[0] * 1e3, failed[1], failed[2], worst_m[2] * 1e3);
  EXPECT_EQ(failed[0], 0);
  EXPECT_LT(worst_m[0], 0.1 * T_prev_curr.translation().norm());
  EXPECT_GE(failed[1], 5) << "the case no longer tells the thresholds apart";
  EXPECT_EQ(failed[2], 0);
  EXPECT_LT(worst_m[2], 0.1 * T_prev_curr.translation().norm());
}

TEST(SparseMotionTest, MsacCostIsTheTruncatedSquaredError) {
  const StereoRig rig = test::rig_640x480();
  const SE3 T(Quat(Eigen::AngleAxisd(1 * kDeg, Vec3::UnitY())), Vec3(0.02, 0.0, -0.3));
  auto m = synthetic_matches(rig, T, 4, 0.0, 0.0, 11);
  m[0].u_l += 0.3;  // left 0.3^2 + 0.4^2 = 0.25 against right 0.2^2: 0.25
  m[0].v_l += 0.4;
  m[0].u_r += 0.2;
  m[0].v_r = m[0].v_l - 0.4;
  m[1].u_r -= 0.6;  // the right image's 0.36
  m[2].v_l += 3.0;  // beyond the 1 px threshold: 1
  m[2].v_r = m[2].v_l - 3.0;
  m[3].p_prev = -m[3].p_prev;  // behind the camera: 1
  StereoMotionEstimator est(rig, SparseVoOptions{});
  EXPECT_NEAR(est.msac_cost(m, T), 0.25 + 0.36 + 1.0 + 1.0, 1e-9);
  SparseVoOptions two_px;
  two_px.inlier_threshold_px = 2.0;
  EXPECT_NEAR(StereoMotionEstimator(rig, two_px).msac_cost(m, T), 0.25 + 0.36 + 4.0 + 4.0, 1e-9);
}

TEST(SparseMotionTest, RansacReportsTooFewMatches) {
  const StereoRig rig = test::rig_640x480();
  const auto m = synthetic_matches(rig, SE3(), 5, 0.0, 0.0, 5);
  StereoMotionEstimator est(rig, SparseVoOptions{});
  Rng rng(1);
  const auto r = est.estimate(m, &rng);
  EXPECT_FALSE(r.ok);
  EXPECT_NE(r.failure.find("too few matches"), std::string::npos);
}

// ---------------------------------------------------------------------------------------------
// The whole VO

TEST(SparseVoTest, BucketingKeepsAtMostTheLimitPerCell) {
  const test::Sequence& seq = short_640();
  for (const int limit : {1, 2, 3}) {
    SparseVoOptions o;
    o.max_features_per_bucket = limit;
    SparseStereoOdometry vo(seq.rig, o, Rng(7));
    vo.process(seq.frames[0]);
    const VoResult r = vo.process(seq.frames[1]);
    ASSERT_TRUE(r.valid) << r.reason;
    std::map<int, int> per_cell;
    for (const SparseMatchInfo& m : vo.last_matches()) {
      const int cell = static_cast<int>(m.v_lc) / o.bucket_height_px * 100 +
                       static_cast<int>(m.u_lc) / o.bucket_width_px;
      ++per_cell[cell];
    }
    int full = 0;
    for (const auto& [cell, count] : per_cell) {
      EXPECT_LE(count, limit) << "cell " << cell;
      full += count == limit;
    }
    EXPECT_EQ(static_cast<int>(vo.last_matches().size()), r.matches);
    // A textured scene fills most of its 13 x 10 cells to the limit.
    EXPECT_GT(full, 80) << "limit " << limit;
  }
}

TEST(SparseVoTest, MatchesLieOnTheExactCorrespondences) {
  // The refined positions against ray-cast truth: the scene point at the current-left pixel,
  // projected into the other three images.
  const test::Sequence& seq = short_640();
  const test::Scene scene = test::river_bank_scene_640();
  SparseStereoOdometry vo(seq.rig, SparseVoOptions{}, Rng(7));
  vo.process(seq.frames[0]);
  ASSERT_TRUE(vo.process(seq.frames[1]).valid);
  std::vector<double> disparity_err, temporal_err;
  for (const SparseMatchInfo& m : vo.last_matches()) {
    if (!m.inlier) continue;
    Vec3 p;
    ASSERT_TRUE(test::scene_point(scene, seq.rig.camera, seq.T_scene_cam[1], m.u_lc, m.v_lc, &p));
    const Vec3 pc = seq.T_scene_cam[1].inverse() * p, pp = seq.T_scene_cam[0].inverse() * p;
    disparity_err.push_back(std::abs(
        (m.u_lc - m.u_rc) - (seq.rig.camera.project(pc).x() - seq.rig.project_right(pc).x())));
    temporal_err.push_back((Eigen::Vector2d(m.u_lp, m.v_lp) - seq.rig.camera.project(pp)).norm());
  }
  ASSERT_GT(disparity_err.size(), 150u);
  auto quantile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
  };
  EXPECT_LT(quantile(disparity_err, 0.5), 0.1);  // sub-pixel: integer matching alone gives 0.25
  EXPECT_LT(quantile(disparity_err, 0.9), 0.3);
  EXPECT_LT(quantile(temporal_err, 0.5), 0.3);
  EXPECT_LT(quantile(temporal_err, 0.9), 1.5);
}

TEST(SparseVoTest, DeterministicBytesAcrossInstancesAndResets) {
  const test::Sequence& seq = short_640();
  auto run = [&](SparseStereoOdometry& vo) {
    std::vector<double> bytes;
    for (const StereoFrame& f : seq.frames) {
      test::append_result_bytes(vo.process(f), &bytes);
      for (const SparseMatchInfo& m : vo.last_matches())
        bytes.insert(bytes.end(), {m.u_lc, m.v_lc, m.u_rc, m.u_lp, m.v_lp, m.u_rp});
    }
    return bytes;
  };
  const Rng stream = RngStreams(2015).stream("vo.sparse");
  SparseStereoOdometry a(seq.rig, SparseVoOptions{}, stream);
  SparseStereoOdometry b(seq.rig, SparseVoOptions{}, stream);
  test::expect_same_bytes_across_instances_and_reset(a, b, run);
}

// sparse and sparse_kf sharing one detection per pair, processing each frame side by side as a
// run does, give byte for byte what each gives detecting alone; each pair is detected once.
TEST(SparseVoTest, SharedDetectionGivesTheSameBytesAsDetectingAlone) {
  const test::Sequence& seq = short_640();
  SparseVoOptions kf;
  kf.keyframes = true;
  const Rng s1 = RngStreams(2015).stream("vo.sparse"), s2 = RngStreams(2015).stream("vo.kf");
  auto bytes_of = [](SparseStereoOdometry& vo, const StereoFrame& f, std::vector<double>* out) {
    test::append_result_bytes(vo.process(f), out);
    for (const SparseMatchInfo& m : vo.last_matches())
      out->insert(out->end(), {m.u_lc, m.v_lc, m.u_rc, m.u_lp, m.v_lp, m.u_rp});
  };
  std::vector<double> alone_a, alone_b, shared_a, shared_b;
  {
    SparseStereoOdometry a(seq.rig, SparseVoOptions{}, s1), b(seq.rig, kf, s2);
    for (const StereoFrame& f : seq.frames) {
      bytes_of(a, f, &alone_a);
      bytes_of(b, f, &alone_b);
    }
  }
  const auto shared = std::make_shared<sparse::SharedDetection>(sparse::detection_settings(kf));
  SparseStereoOdometry a(seq.rig, SparseVoOptions{}, s1, shared), b(seq.rig, kf, s2, shared);
  for (const StereoFrame& f : seq.frames) {
    auto other = std::async(std::launch::async, [&] { bytes_of(b, f, &shared_b); });
    bytes_of(a, f, &shared_a);
    other.get();
  }
  ASSERT_GT(alone_a.size(), 20u);
  EXPECT_EQ(0, std::memcmp(alone_a.data(), shared_a.data(), alone_a.size() * sizeof(double)));
  ASSERT_EQ(alone_b.size(), shared_b.size());
  EXPECT_EQ(0, std::memcmp(alone_b.data(), shared_b.data(), alone_b.size() * sizeof(double)));
  EXPECT_EQ(shared->detected(), static_cast<long>(seq.frames.size()));
  EXPECT_EQ(shared->shared(), static_cast<long>(seq.frames.size()));
  const auto ca = a.detection_counts(), cb = b.detection_counts();
  EXPECT_EQ(ca.detected + cb.detected, shared->detected());
  EXPECT_EQ(ca.shared + cb.shared, shared->shared());
  EXPECT_EQ(ca.detected + ca.shared, static_cast<long>(seq.frames.size()));
  // Sharing needs equal detection options.
  SparseVoOptions other_nms;
  other_nms.nms_threshold += 1;
  EXPECT_THROW(SparseStereoOdometry(seq.rig, other_nms, s1, shared), InternalError);
}

// The shared result is keyed by the images' bytes, not by their buffers: a buffer refilled with
// other bytes is detected anew, the same bytes in another buffer are not.
TEST(SparseVoTest, SharedDetectionComparesTheImagesBytes) {
  const test::Sequence& seq = short_640();
  const SparseVoOptions o;
  sparse::SharedDetection shared(sparse::detection_settings(o));
  sparse::PairDetector detector(seq.rig.camera.width, seq.rig.camera.height, o);
  cv::Mat left = seq.frames[0].left.clone(), right = seq.frames[0].right.clone();
  auto first = shared.get(left, right, &detector).features;
  auto again = shared.get(left.clone(), right.clone(), &detector).features;
  EXPECT_EQ(first.get(), again.get());
  left.at<std::uint8_t>(100, 100) ^= 0x40;
  const auto changed = shared.get(left, right, &detector).features;
  EXPECT_NE(first.get(), changed.get());
  EXPECT_EQ(shared.detected(), 2);
  EXPECT_EQ(shared.shared(), 1);
  // Pairs nobody holds any more are refilled for the next ones once kRecentPairs newer pairs
  // came, not reallocated: 3 x kRecentPairs new pairs, none held, in at most kRecentPairs + 1
  // buffers.
  first.reset();
  again.reset();
  std::set<const sparse::PairFeatures*> buffers;
  constexpr std::size_t kRecent = sparse::SharedDetection::kRecentPairs;
  for (std::size_t i = 0; i < 3 * kRecent; ++i) {
    left.at<std::uint8_t>(200, 10 + static_cast<int>(i)) ^= 0x40;
    buffers.insert(shared.get(left, right, &detector).features.get());
  }
  EXPECT_LE(buffers.size(), kRecent + 1);
  EXPECT_EQ(shared.detected(), 2 + 3 * static_cast<long>(kRecent));
}

// VOs that run frames apart (pipeline/vo_pipeline.hpp) still share: the last kRecentPairs
// pairs are kept for a caller that comes later.
TEST(SparseVoTest, SharedDetectionServesACallerSomeFramesBehind) {
  const test::Sequence& seq = short_640();
  const SparseVoOptions o;
  sparse::SharedDetection shared(sparse::detection_settings(o));
  sparse::PairDetector detector(seq.rig.camera.width, seq.rig.camera.height, o);
  std::vector<cv::Mat> lefts;
  for (std::size_t i = 0; i < sparse::SharedDetection::kRecentPairs; ++i) {
    lefts.push_back(seq.frames[0].left.clone());
    lefts.back().at<std::uint8_t>(50, 50 + static_cast<int>(i)) ^= 0x40;
  }
  std::vector<const sparse::PairFeatures*> ahead;
  for (const cv::Mat& l : lefts)
    ahead.push_back(shared.get(l, seq.frames[0].right, &detector).features.get());
  for (std::size_t i = 0; i < lefts.size(); ++i)
    EXPECT_EQ(shared.get(lefts[i].clone(), seq.frames[0].right, &detector).features.get(), ahead[i])
        << i;
  EXPECT_EQ(shared.detected(), static_cast<long>(lefts.size()));
  EXPECT_EQ(shared.shared(), static_cast<long>(lefts.size()));
}

TEST(SparseVoTest, SingleStageMatchingTracksToo) {
  // two_stage_matching = false: one exhaustive stage with match_radius_px windows.
  const test::Sequence& seq = short_640();
  SparseVoOptions o;
  o.two_stage_matching = false;
  SparseStereoOdometry vo(seq.rig, o, Rng(7));
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    const VoResult r = vo.process(seq.frames[k]);
    if (k == 0) continue;
    ASSERT_TRUE(r.valid) << r.reason;
    const auto e = test::motion_error(r.T_prev_curr, seq.T_prev_curr(k));
    EXPECT_LT(e.translation_m, 5e-3);
    EXPECT_LT(e.rotation_rad, 0.02 * kDeg);
  }
}

TEST(SparseVoTest, MotionBeyondTheSearchRadiusIsInvalidNotWrong) {
  // 60 px of image motion against a 20 px search: no consistent matches, no made-up motion.
  const test::Sequence& seq = short_640();
  const test::Sequence far = test::make_sequence(
      test::river_bank_scene_640(), seq.rig,
      {SE3(), SE3(Quat(Eigen::AngleAxisd(7 * kDeg, Vec3::UnitY())), Vec3::Zero())});
  SparseVoOptions o;
  o.match_radius_px = 20;
  SparseStereoOdometry vo(seq.rig, o, Rng(7));
  vo.process(far.frames[0]);
  const VoResult r = vo.process(far.frames[1]);
  if (r.valid) {
    const auto e = test::motion_error(r.T_prev_curr, far.T_prev_curr(1));
    EXPECT_LT(e.rotation_rad, 0.1 * kDeg) << "a valid result must be right";
  } else {
    EXPECT_FALSE(r.reason.empty());
  }
}

// ---------------------------------------------------------------------------------------------
// Keyframes (sparse_kf)

// A slow straight run: 2 cm per frame, sub-pixel to a few pixels of flow per frame.
const test::Sequence& slow_640() {
  static const test::Sequence s = test::make_sequence(
      test::river_bank_scene_640(), test::rig_640x480(), test::straight_poses(10, 0.02));
  return s;
}

std::vector<int> reference_frames(SparseStereoOdometry& vo, const test::Sequence& seq,
                                  SE3* T_first_last) {
  std::vector<int> refs;
  SE3 T;
  for (std::size_t k = 0; k < seq.frames.size(); ++k) {
    const VoResult r = vo.process(seq.frames[k]);
    if (k == 0) continue;
    EXPECT_TRUE(r.valid) << "frame " << k << ": " << r.reason;
    refs.push_back(r.reference_frames_back);
    T = accumulate_pose(T, r);
  }
  *T_first_last = T;
  return refs;
}

TEST(SparseKeyframeTest, OffByDefaultAndNamedSparseKfWhenOn) {
  const test::Sequence& seq = slow_640();
  SparseVoOptions o;
  EXPECT_FALSE(o.keyframes);  // the paper's frame-to-frame method
  SparseStereoOdometry paper(seq.rig, o, Rng(7));
  EXPECT_EQ(paper.name(), "sparse");
  SE3 T;
  EXPECT_EQ(reference_frames(paper, seq, &T), std::vector<int>(9, 1));
  o.keyframes = true;
  EXPECT_EQ(SparseStereoOdometry(seq.rig, o, Rng(7)).name(), "sparse_kf");
}

TEST(SparseKeyframeTest, KeyframeMovesAfterMaxFramesAndTheChainFollowsTheTruth) {
  // Flow, inlier and scale limits out of reach: the reference moves every keyframe_max_frames
  // frames, so the references are 1, 2, 3, 1, 2, 3, ... frames back, and Eq. (3) chained over the
  // increments still lands on the true last pose (0.18 m ahead).
  const test::Sequence& seq = slow_640();
  SparseVoOptions o;
  o.keyframes = true;
  o.keyframe_min_flow_px = 1000;
  o.keyframe_min_inliers = 0;
  o.keyframe_max_scale_change = 1.0;
  o.keyframe_max_frames = 3;
  SparseStereoOdometry vo(seq.rig, o, Rng(7));
  SE3 T;
  EXPECT_EQ(reference_frames(vo, seq, &T), (std::vector<int>{1, 2, 3, 1, 2, 3, 1, 2, 3}));
  const SE3 truth = seq.T_scene_cam.front().inverse() * seq.T_scene_cam.back();
  const auto e = test::motion_error(T, truth);
  EXPECT_LT(e.translation_m, 2e-3);
  EXPECT_LT(e.rotation_rad, 0.05 * kDeg);
}

TEST(SparseKeyframeTest, KeyframeMovesOnceTheMedianFlowReachesTheThreshold) {
  // The same run with the flow rule alone: the reference stays while the median inlier flow
  // from the keyframe is below the threshold. The flow grows with the distance from the
  // keyframe, so a smaller threshold moves the keyframe at least as often, and a threshold
  // below the flow of one frame gives the frame-to-frame method.
  const test::Sequence& seq = slow_640();
  auto refs = [&](double min_flow_px) {
    SparseVoOptions o;
    o.keyframes = true;
    o.keyframe_min_flow_px = min_flow_px;
    o.keyframe_min_inliers = 0;
    o.keyframe_max_scale_change = 1.0;
    o.keyframe_max_frames = 1000;
    SparseStereoOdometry vo(seq.rig, o, Rng(7));
    SE3 T;
    return reference_frames(vo, seq, &T);
  };
  const auto max_of = [](const std::vector<int>& v) {
    return *std::max_element(v.begin(), v.end());
  };
  EXPECT_EQ(refs(1e-3), std::vector<int>(9, 1));
  EXPECT_EQ(refs(1000), (std::vector<int>{1, 2, 3, 4, 5, 6, 7, 8, 9}));
  const std::vector<int> mid = refs(2.0);
  EXPECT_GT(max_of(mid), 1);
  EXPECT_LT(max_of(mid), 9);
  EXPECT_LE(max_of(refs(1.0)), max_of(mid));
}

TEST(SparseKeyframeTest, KeyframeMovesOnceTheNearPointsScaleChanges) {
  // Flow and frame limits out of reach, 2 cm per frame straight ahead: the reference moves
  // once the run since it reaches the scale limit times the near inliers' depth, so a tighter
  // limit moves it sooner, and a limit below one frame's run gives the frame-to-frame method.
  const test::Sequence& seq = slow_640();
  auto longest = [&](double max_scale_change) {
    SparseVoOptions o;
    o.keyframes = true;
    o.keyframe_min_flow_px = 1000;
    o.keyframe_min_inliers = 0;
    o.keyframe_max_frames = 1000;
    o.keyframe_max_scale_change = max_scale_change;
    SparseStereoOdometry vo(seq.rig, o, Rng(7));
    SE3 T;
    const std::vector<int> refs = reference_frames(vo, seq, &T);
    return *std::max_element(refs.begin(), refs.end());
  };
  EXPECT_EQ(longest(1e-4), 1);
  EXPECT_EQ(longest(1.0), 9);
  EXPECT_LE(longest(0.02), longest(0.05));
  EXPECT_LT(longest(0.02), 9);
}

TEST(SparseKeyframeTest, DeterministicBytesAcrossInstancesAndResets) {
  const test::Sequence& seq = slow_640();
  auto run = [&](SparseStereoOdometry& vo) {
    std::vector<double> bytes;
    for (const StereoFrame& f : seq.frames) test::append_result_bytes(vo.process(f), &bytes);
    return bytes;
  };
  SparseVoOptions o;
  o.keyframes = true;
  const Rng stream = RngStreams(2015).stream("vo.sparse_kf");
  SparseStereoOdometry a(seq.rig, o, stream);
  SparseStereoOdometry b(seq.rig, o, stream);
  test::expect_same_bytes_across_instances_and_reset(a, b, run);
}

TEST(SparseKeyframeTest, KeyframesRefuseTheWindowAdjustment) {
  SparseVoOptions o;
  o.keyframes = true;
  o.refine = SparseRefine::kWindowBa;
  EXPECT_NE(yaml::validate(o).find("keyframes"), std::string::npos) << yaml::validate(o);
}

}  // namespace
}  // namespace driftlab::vo
