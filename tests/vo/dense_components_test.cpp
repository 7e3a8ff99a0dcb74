// Tests of the dense stereo VO's parts (river paper Section 2.3.2): the analytic Jacobians
// against finite differences, the warp's and the pyramid's fast paths against one plain
// computation, the disparity refinement against the ray-cast truth and the box filter against
// long-double sums and OpenCV. Expectations never come from the VO itself.
#include "vo/dense/dense_vo.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <utility>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "tests/vo/dense_vo_fixtures.hpp"
#include "tests/vo/vo_test_sequences.hpp"
#include "vo/dense/box_filter.hpp"
#include "vo/dense/disparity.hpp"
#include "vo/dense/photometric.hpp"

namespace driftlab::vo {
namespace {

using test::dense_straight_640;
using test::dense_turn_640;
using test::Sequence;
using test::true_disparity;
using Vec2 = Eigen::Vector2d;

// The dense VO's pyramid (its default scales and blur) of the left image of frame `frame`.
dense::Pyramid default_pyramid(const Sequence& seq, std::size_t frame) {
  const DenseVoOptions o;
  dense::Pyramid pyr;
  pyr.configure(seq.rig.camera, o.pyramid_scales);
  pyr.build(seq.frames[frame].left, o.pyramid_blur_sigma_px);
  return pyr;
}

// ---------------------------------------------------------------------------------------------
// Jacobians (Ceres GradientChecker style: analytic against central differences)

// Points in front of the camera, with off-axis and near/far depths.
std::vector<Vec3> test_points() {
  return {Vec3(0.3, -0.2, 4.0), Vec3(-2.5, 1.4, 7.0), Vec3(10.0, -3.0, 35.0), Vec3(0.01, 0.02, 1.2),
          Vec3(-0.7, 1.6, 2.5)};
}

Vec2 project(const Vec3& P, double fx, double fy, double cx, double cy) {
  return Vec2(fx * P.x() / P.z() + cx, fy * P.y() / P.z() + cy);
}

TEST(DenseJacobianTest, WarpJacobianMatchesFiniteDifferences) {
  // d pi(exp(xi) P) / d xi of Eqs. (6)-(7) against central differences of the exact warp.
  const double fx = 500.0, fy = 480.0, cx = 319.5, cy = 239.5;
  constexpr double h = 1e-6;
  for (const Vec3& P : test_points()) {
    const dense::Mat26 J = dense::warp_jacobian(P, fx, fy);
    for (int k = 0; k < 6; ++k) {
      Vec6 d = Vec6::Zero();
      d[k] = h;
      const Vec2 fd =
          (project(SE3::exp(d) * P, fx, fy, cx, cy) - project(SE3::exp(-d) * P, fx, fy, cx, cy)) /
          (2 * h);
      EXPECT_LT((fd - J.col(k)).norm(), 1e-6 * (1.0 + J.col(k).norm()))
          << "P = " << P.transpose() << ", column " << k << ": analytic " << J.col(k).transpose()
          << ", numeric " << fd.transpose();
    }
  }
}

// A smooth image with analytic gradient: I(u, v) = 128 + 50 sin(a u + b v) + 30 cos(c v - d u).
struct SmoothImage {
  double a = 0.031, b = 0.017, c = 0.043, d = 0.011;
  double operator()(double u, double v) const {
    return 128.0 + 50.0 * std::sin(a * u + b * v) + 30.0 * std::cos(c * v - d * u);
  }
  Vec2 gradient(double u, double v) const {
    const double s = std::cos(a * u + b * v), t = -std::sin(c * v - d * u);
    return Vec2(50.0 * a * s + 30.0 * -d * t, 50.0 * b * s + 30.0 * c * t);
  }
};

TEST(DenseJacobianTest, PhotometricJacobianMatchesFiniteDifferencesOfASmoothImage) {
  // The row of Eq. (9)'s residual, d I(pi(exp(xi) P)) / d xi, with the analytic gradient.
  const SmoothImage I;
  const double fx = 500.0, fy = 500.0, cx = 319.5, cy = 239.5;
  constexpr double h = 1e-6;
  for (const Vec3& P : test_points()) {
    const Vec2 p = project(P, fx, fy, cx, cy);
    const Vec2 g = I.gradient(p.x(), p.y());
    const dense::Row6 J = dense::photometric_jacobian(g.x(), g.y(), P, fx, fy);
    EXPECT_LT((J - g.transpose() * dense::warp_jacobian(P, fx, fy)).norm(), 1e-9 * J.norm());
    for (int k = 0; k < 6; ++k) {
      Vec6 d = Vec6::Zero();
      d[k] = h;
      const Vec2 pp = project(SE3::exp(d) * P, fx, fy, cx, cy);
      const Vec2 pm = project(SE3::exp(-d) * P, fx, fy, cx, cy);
      const double fd = (I(pp.x(), pp.y()) - I(pm.x(), pm.y())) / (2 * h);
      EXPECT_NEAR(J[k], fd, 1e-5 * (1.0 + J.norm())) << "P = " << P.transpose() << ", k " << k;
    }
  }
}

TEST(DenseJacobianTest, ReferenceJacobiansMatchFiniteDifferencesOnEveryLevel) {
  // What the solver actually uses: the stored points and rows of every pyramid level, built
  // from images and a disparity map. Each row must be the derivative of the level image
  // (bilinear) sampled through the warp. Central differences of the image stand in for its
  // gradient, which on this smooth image differs from the bilinear slope by ~ omega / 2 < 3%.
  const StereoRig rig = test::kitti_rig();  // odd size: 1241 x 376 does not halve evenly
  const SmoothImage I;
  dense::Pyramid pyr;
  pyr.configure(rig.camera, {0.125, 0.25, 0.5, 1.0});
  for (std::size_t l = 0; l < pyr.cameras.size(); ++l) {
    const dense::LevelCamera& c = pyr.cameras[l];
    pyr.images[l].create(c.height, c.width, CV_32FC1);
    for (int v = 0; v < c.height; ++v)
      for (int u = 0; u < c.width; ++u)  // the same scene at every level, in full-image pixels
        pyr.images[l].at<float>(v, u) =
            static_cast<float>(I((u + 0.5) / c.sx - 0.5, (v + 0.5) / c.sy - 0.5));
  }
  // A slanted plane: disparity affine in the pixel, as for a real plane.
  cv::Mat disparity(rig.camera.height, rig.camera.width, CV_32FC1);
  for (int v = 0; v < disparity.rows; ++v)
    for (int u = 0; u < disparity.cols; ++u)
      disparity.at<float>(v, u) = static_cast<float>(20.0 + 0.01 * u + 0.05 * v);
  dense::Reference ref;
  dense::build_reference(pyr, disparity, rig.camera.fx * rig.baseline_m, dense::RefSelection{},
                         &ref);
  for (std::size_t l = 0; l < pyr.cameras.size(); ++l) {
    const dense::LevelCamera& c = pyr.cameras[l];
    const dense::RefLevel& lev = ref.levels[l];
    const std::vector<dense::RefPoint>& pts = lev.points;
    ASSERT_GT(pts.size(), 100u) << "level " << l;
    double worst = 0.0;
    int checked = 0;
    for (std::size_t i = 0; i < pts.size(); i += pts.size() / 97) {
      const dense::RefPoint& p = pts[i];
      const Vec3 P(p.x, p.y, p.z);
      // Eq. (1) independently: the full-image pixel this point projects to has the plane's
      // disparity f B / Z.
      const Vec2 full = project(P, rig.camera.fx, rig.camera.fy, rig.camera.cx, rig.camera.cy);
      const double expected_d = 20.0 + 0.01 * full.x() + 0.05 * full.y();
      EXPECT_NEAR(rig.camera.fx * rig.baseline_m / P.z(), expected_d, 2e-4 * expected_d)
          << "level " << l;
      const Vec2 at = project(P, c.fx, c.fy, c.cx, c.cy);
      EXPECT_NEAR(
          p.intensity,
          dense::bilinear(pyr.images[l], static_cast<float>(at.x()), static_cast<float>(at.y())),
          1e-3);
      constexpr double h = 1e-4;
      Eigen::Matrix<double, 1, 6> fd;
      for (int k = 0; k < 6; ++k) {
        Vec6 d = Vec6::Zero();
        d[k] = h;
        const Vec2 pp = project(SE3::exp(d) * P, c.fx, c.fy, c.cx, c.cy);
        const Vec2 pm = project(SE3::exp(-d) * P, c.fx, c.fy, c.cx, c.cy);
        fd[k] = (dense::bilinear(pyr.images[l], static_cast<float>(pp.x()),
                                 static_cast<float>(pp.y())) -
                 dense::bilinear(pyr.images[l], static_cast<float>(pm.x()),
                                 static_cast<float>(pm.y()))) /
                (2 * h);
      }
      Eigen::Matrix<double, 1, 6> J;
      for (int k = 0; k < 6; ++k) J[k] = lev.jacobians[i].J[k];
      worst = std::max(worst, (J - fd).norm() / fd.norm());
      // And exactly the tested double-precision row, from the central-difference gradient at
      // the point's pixel (the float expansion in build_reference must match it).
      const int u = static_cast<int>(std::lround(at.x())),
                v = static_cast<int>(std::lround(at.y()));
      const cv::Mat& L = pyr.images[l];
      const double gx = 0.5 * (L.at<float>(v, u + 1) - L.at<float>(v, u - 1));
      const double gy = 0.5 * (L.at<float>(v + 1, u) - L.at<float>(v - 1, u));
      const dense::Row6 expected = dense::photometric_jacobian(gx, gy, P, c.fx, c.fy);
      EXPECT_LT((J - expected).norm(), 1e-4 * expected.norm()) << "level " << l;
      ++checked;
    }
    EXPECT_GT(checked, 90);
    EXPECT_LT(worst, 0.05) << "level " << l << " (" << c.width << "x" << c.height << ")";
  }
}

TEST(DenseWarpTest, ResidualsInLanesGiveTheBytesOfThePlainLoop) {
  // The alignment's warp runs four points at a time with a plain loop for the rest: on the
  // reference of a real frame, at every level, for a small motion and for one that takes points
  // out of the image, both give the same residuals bit for bit, NaN included, and the same count.
  const Sequence& seq = dense_straight_640();
  const DenseVoOptions o;
  const dense::Pyramid pyr = default_pyramid(seq, 1);
  cv::Mat left_f, disparity;
  seq.frames[1].left.convertTo(left_f, CV_32F);
  dense::DisparityEstimator(dense::disparity_options(o))
      .compute(seq.frames[1].left, seq.frames[1].right, left_f, &disparity);
  dense::Reference ref;
  dense::build_reference(pyr, disparity, seq.rig.camera.fx * seq.rig.baseline_m,
                         dense::RefSelection{}, &ref);
  Vec6 small, large;
  small << 0.02, -0.01, 0.05, 0.002, -0.003, 0.001;
  large << 1.5, 0.8, 0.3, 0.0, 0.2, 0.05;
  for (const Vec6& xi : {small, large}) {
    for (std::size_t l = 0; l < pyr.cameras.size(); ++l) {
      const std::vector<dense::RefPoint>& pts = ref.levels[l].points;
      const std::size_t n = (pts.size() - 3) / 4 * 4 + 3;  // three points past the lanes
      ASSERT_LE(n, pts.size());
      std::vector<float> lanes(n), plain(n);
      const int used = dense::warp_residuals(pts.data(), n, pyr.images[l], pyr.cameras[l],
                                             SE3::exp(xi), true, lanes.data());
      EXPECT_EQ(dense::warp_residuals(pts.data(), n, pyr.images[l], pyr.cameras[l], SE3::exp(xi),
                                      false, plain.data()),
                used);
      EXPECT_EQ(std::memcmp(lanes.data(), plain.data(), n * sizeof(float)), 0) << "level " << l;
      EXPECT_GT(used, 0);
      if (xi == large) {
        EXPECT_LT(used, static_cast<int>(n)) << "level " << l;
      }
    }
  }
}

TEST(DensePyramidTest, LevelCamerasFollowCvResize) {
  // A linear ramp survives bilinear resizing exactly, so each level pixel's value is the
  // full-image coordinate of its centre; the level camera must agree.
  const PinholeCamera cam = test::kitti_rig().camera;
  cv::Mat fu(cam.height, cam.width, CV_32FC1), fv(cam.height, cam.width, CV_32FC1);
  for (int v = 0; v < cam.height; ++v)
    for (int u = 0; u < cam.width; ++u) {
      fu.at<float>(v, u) = static_cast<float>(u);
      fv.at<float>(v, u) = static_cast<float>(v);
    }
  for (const double scale : {0.125, 0.25, 0.5, 1.0}) {
    const dense::LevelCamera c = dense::level_camera(cam, scale);
    cv::Mat lu, lv;
    cv::resize(fu, lu, cv::Size(c.width, c.height), 0, 0, cv::INTER_LINEAR);
    cv::resize(fv, lv, cv::Size(c.width, c.height), 0, 0, cv::INTER_LINEAR);
    // A ray through level pixel (u, v) must pass through the full-image pixel the resize took.
    for (const auto& [u, v] : {std::pair{3, 2}, std::pair{c.width / 2, c.height / 3},
                               std::pair{c.width - 4, c.height - 3}}) {
      const Vec3 ray((u - c.cx) / c.fx, (v - c.cy) / c.fy, 1.0);
      const Vec2 full = project(ray, cam.fx, cam.fy, cam.cx, cam.cy);
      EXPECT_NEAR(full.x(), lu.at<float>(v, u), 1e-3) << "scale " << scale;
      EXPECT_NEAR(full.y(), lv.at<float>(v, u), 1e-3) << "scale " << scale;
    }
  }
}

TEST(DensePyramidTest, BlurInPiecesOfRowsEqualsOneBlurOfTheWholeImage) {
  // The pyramid blurs its image in pieces of rows on OpenCV's threads; each piece must read the
  // rows around it, so the levels are those of one cv::GaussianBlur and one cv::resize.
  const Sequence& seq = dense_turn_640();
  const DenseVoOptions o;
  const dense::Pyramid pyr = default_pyramid(seq, 1);
  cv::Mat full, blurred;
  seq.frames[1].left.convertTo(full, CV_32F);
  const int k = 2 * static_cast<int>(std::ceil(3.0 * o.pyramid_blur_sigma_px)) + 1;
  cv::GaussianBlur(full, blurred, cv::Size(k, k), o.pyramid_blur_sigma_px, o.pyramid_blur_sigma_px,
                   cv::BORDER_REFLECT_101);
  EXPECT_EQ(cv::norm(pyr.blurred, blurred, cv::NORM_INF), 0.0);
  for (std::size_t l = 0; l + 1 < pyr.cameras.size(); ++l) {
    cv::Mat level;
    cv::resize(blurred, level, pyr.images[l].size(), 0, 0, cv::INTER_LINEAR);
    EXPECT_EQ(cv::norm(pyr.images[l], level, cv::NORM_INF), 0.0) << "level " << l;
  }
}

// ---------------------------------------------------------------------------------------------
// Disparity

// Disparity error of one estimator setting against the ray-cast truth.
struct DisparityErrors {
  std::vector<double> band_bias;  // mean error in bands of 4 px of true disparity (> 1000 px)
  double rms = 0.0;               // over pixels within 2 px of the truth
  int valid = 0;                  // pixels with a disparity
};

TEST(DenseDisparityTest, RefinementRemovesTheBiasOfSgbm) {
  // SGBM's parabolic sub-pixel step leaves biases of 0.1-0.3 px on these planes; the
  // Lucas-Kanade refinement must bring every depth band's bias under 0.05 px, both after SGBM on
  // the full pair and after SGBM on the pair shrunk 2x (the dense VO's default), whose raw
  // disparities are only as fine as the shrunk pixels.
  const Sequence& seq = dense_straight_640();
  const cv::Mat truth = true_disparity(test::river_bank_scene_640(), seq.rig, seq.T_scene_cam[1]);
  cv::Mat left_f;
  seq.frames[1].left.convertTo(left_f, CV_32F);
  auto errors = [&](int downsample, int iterations) {
    dense::DisparityOptions o;
    o.downsample = downsample;
    o.refine_iterations = iterations;
    dense::DisparityEstimator est(o);
    cv::Mat d;
    est.compute(seq.frames[1].left, seq.frames[1].right, left_f, &d);
    std::vector<double> sum(5, 0.0);
    std::vector<int> n(5, 0);
    double sq = 0.0;
    int total = 0;
    DisparityErrors out;
    for (int v = 0; v < d.rows; ++v)
      for (int u = 0; u < d.cols; ++u) {
        const float e = d.at<float>(v, u), g = truth.at<float>(v, u);
        out.valid += e > 0.0f ? 1 : 0;
        if (e < 1.0f || g < 1.0f || std::abs(e - g) > 2.0f) continue;  // no depth, or mismatch
        const int band = std::min(4, static_cast<int>(g / 4.0f));
        sum[static_cast<std::size_t>(band)] += e - g;
        ++n[static_cast<std::size_t>(band)];
        sq += (e - g) * (e - g);
        ++total;
      }
    for (std::size_t b = 0; b < sum.size(); ++b)
      if (n[b] > 1000) out.band_bias.push_back(sum[b] / n[b]);
    out.rms = std::sqrt(sq / total);
    return out;
  };
  for (int downsample : {1, 2}) {
    const DisparityErrors raw = errors(downsample, 0);
    const DisparityErrors refined = errors(downsample, 1);
    ASSERT_GE(refined.band_bias.size(), 4u);
    ASSERT_EQ(refined.band_bias.size(), raw.band_bias.size());
    for (std::size_t b = 0; b < refined.band_bias.size(); ++b) {
      std::printf(
          "[ dense    ] SGBM 1/%d, disparity band %zu: bias SGBM %+.3f px, refined %+.3f px\n",
          downsample, b, raw.band_bias[b], refined.band_bias[b]);
      EXPECT_LT(std::abs(refined.band_bias[b]), 0.05) << "band " << b;
    }
    std::printf("[ dense    ] SGBM 1/%d, disparity RMS error: SGBM %.3f px, refined %.3f px\n",
                downsample, raw.rms, refined.rms);
    EXPECT_LT(refined.rms, 0.5 * raw.rms);
    // The shrunk pair's matches cover the image as the full pair's do.
    EXPECT_GT(refined.valid, 0.85 * seq.rig.camera.width * seq.rig.camera.height);
  }
}

TEST(DenseDisparityTest, RefinementDropsMatchesTheRightImageDoesNotConfirm) {
  // A right image of noise (a faulty camera): SGBM on the shrunk pair still matches about a
  // tenth of the pixels; the residual check leaves (almost) none of them.
  const Sequence& seq = dense_straight_640();
  cv::Mat left_f, noise(seq.rig.camera.height, seq.rig.camera.width, CV_8UC1);
  seq.frames[1].left.convertTo(left_f, CV_32F);
  cv::randu(noise, 0, 256);
  auto valid_pixels = [&](double max_residual) {
    dense::DisparityOptions o;
    o.downsample = 2;
    o.refine_iterations = 1;
    o.refine_max_residual = max_residual;
    dense::DisparityEstimator est(o);
    cv::Mat d;
    est.compute(seq.frames[1].left, noise, left_f, &d);
    return cv::countNonZero(d > 0.0f);
  };
  const int unchecked = valid_pixels(std::numeric_limits<double>::infinity());
  const int checked = valid_pixels(DenseVoOptions{}.refine_max_residual_grey);
  std::printf("[ dense    ] right image of noise: %d matches unchecked, %d checked\n", unchecked,
              checked);
  EXPECT_GT(unchecked, 10000);
  EXPECT_LT(checked, 100);
}

TEST(DenseBoxFilterTest, RowsAreTheWindowSumsAndOpenCvsBytes) {
  // box_filter_rows on pieces of rows of an image of products of gradients and residuals (what
  // the refinement sums): within 1e-6 of each window's sum in long double and, on the OpenCV the
  // project is built against (Debian's 4.6), the bytes of cv::boxFilter on the same rows.
  const Sequence& seq = dense_straight_640();
  cv::Mat left, right, dx;
  seq.frames[1].left.convertTo(left, CV_32F);
  seq.frames[1].right.convertTo(right, CV_32F);
  cv::Sobel(right, dx, CV_32F, 1, 0, 1, 0.5);
  const cv::Mat products = dx.mul(left - right);
  // And one whose double sums round (the products above are multiples of 0.5 below 2^17, whose
  // sums are exact): the products scaled by 1e-6 with a spike of 2^40 / 3 on every 97th pixel, so
  // a change in the order of the additions changes bytes.
  cv::Mat spiky = products * 1e-6;
  for (std::size_t i = 0; i < spiky.total(); i += 97)
    spiky.ptr<float>()[i] = ((i / 97) % 2 != 0 ? 1.0f : -1.0f) * 0x1p40f / 3.0f;
  for (const cv::Mat& src : {products, spiky}) {
    const int H = src.rows, W = src.cols;
    for (const int window : {3, 5, 9, 11}) {
      for (const bool normalize : {false, true}) {
        cv::Mat ours(src.size(), CV_32FC1, cv::Scalar(0)), cv_rows(src.size(), CV_32FC1);
        for (const auto& [v0, v1] :
             std::vector<std::pair<int, int>>{{0, 37}, {37, 300}, {300, H}}) {
          dense::box_filter_rows(src, v0, v1, window, normalize, &ours);
          const cv::Rect rows(0, v0, W, v1 - v0);
          cv::Mat out = cv_rows(rows);
          cv::boxFilter(src(rows), out, CV_32F, cv::Size(window, window), cv::Point(-1, -1),
                        normalize, cv::BORDER_CONSTANT);
        }
        const int r = window / 2;
        double worst = 0.0;
        for (int v = 0; v < H; v += 7)
          for (int u = 0; u < W; u += 3) {
            long double sum = 0.0L;
            for (int y = std::max(0, v - r); y <= std::min(H - 1, v + r); ++y)
              for (int x = std::max(0, u - r); x <= std::min(W - 1, u + r); ++x)
                sum += src.at<float>(y, x);
            if (normalize) sum /= window * window;
            worst = std::max(worst, static_cast<double>(std::abs(sum - ours.at<float>(v, u)) /
                                                        (1.0L + std::abs(sum))));
          }
        if (src.data == products.data) {
          EXPECT_LT(worst, 1e-6) << "window " << window << (normalize ? ", means" : ", sums");
        }
#if CV_VERSION_MAJOR == 4 && CV_VERSION_MINOR == 6
        EXPECT_EQ(cv::norm(ours, cv_rows, cv::NORM_INF), 0.0)
            << "window " << window << (normalize ? ", means" : ", sums");
#endif
      }
    }
  }
}

TEST(DenseDisparityTest, RefinementInLanesGivesTheBytesOfThePlainLoop) {
  // The refinement's row loops run four pixels at a time with a plain loop for the rest of a
  // row; on a pair 638 px wide (two pixels left over per row) both give the plain loop's bytes.
  const Sequence& seq = dense_straight_640();
  const cv::Rect crop(0, 0, 638, seq.rig.camera.height);
  const cv::Mat left = seq.frames[1].left(crop).clone(), right = seq.frames[1].right(crop).clone();
  cv::Mat left_f;
  left.convertTo(left_f, CV_32F);
  const dense::DisparityOptions o = dense::disparity_options(DenseVoOptions{});
  ASSERT_GT(o.refine_iterations, 0);
  cv::Mat lanes, plain;
  dense::DisparityEstimator(o, dense::DisparityEstimator::Lanes::kSimd)
      .compute(left, right, left_f, &lanes);
  dense::DisparityEstimator(o, dense::DisparityEstimator::Lanes::kScalar)
      .compute(left, right, left_f, &plain);
  ASSERT_EQ(lanes.size(), plain.size());
  EXPECT_GT(cv::countNonZero(plain > 0.0f), crop.area() / 2);
  EXPECT_EQ(std::memcmp(lanes.data, plain.data, lanes.total() * lanes.elemSize()), 0);
}

}  // namespace
}  // namespace driftlab::vo
