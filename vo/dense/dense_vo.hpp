// Dense appearance-based stereo visual odometry: our implementation of river paper Section
// 2.3.2 (Kriechbaumer et al. 2015, after Steinbruecker et al. 2011):
//   1. disparity of each rectified pair by semi-global block matching (cv::StereoSGBM), and a
//      dense cloud of 3D points from it by Eq. (1), in the left optical frame;
//   2. the motion H = [R T] of Eq. (6) from the previous pair (reference: its left image and
//      points) to the current left image that minimises the photometric error of Eq. (9)
//      through the warp of Eqs. (7)-(8), by Levenberg-Marquardt on a four-level pyramid
//      (scales 0.125, 0.25, 0.5, 1; at most 40, 20, 3, 1 iterations; the coarser levels made
//      from the full image blurred by a Gaussian of sigma 3 px), coarse to fine.
// The paper uses p_L ~ p: depth pixels are the left image's pixels, as SGBM's left disparity
// map gives them. Details of the solver (inverse compositional, analytic Jacobians) are in
// vo/dense/photometric.hpp.
//
// Beyond the paper (DenseVoOptions::method = extended, the default; `paper` runs the plain
// method for comparison): SGBM on the pair shrunk 2x (a third of the cost of the full pair),
// its disparities refined to sub-pixel precision at full resolution by Lucas-Kanade along the
// rows and checked against the right image (vo/dense/disparity.hpp; SGBM's own interpolation is
// biased by 0.1-0.3 px, which was the paper method's main error on tests/vo's scenes),
// t-distribution weights of the residuals (Kerl et al. 2013), the previous motion as initial guess
// (constant velocity), and a mask that keeps only textured pixels (no water, sky or other flat
// areas) and optionally drops the lower image. Worst per-frame errors at 0.5 m/frame on tests/vo's
// sequences: paper 4.8 mm and 0.026 deg, extended 0.4 mm and 0.003 deg (tests/vo/dense_vo_test.cpp
// prints them).
//
// A motion is valid when both images are textured, the previous pair has depth, and at least
// min_inlier_fraction of the textured reference pixels compared at full resolution end within
// inlier_residual_grey: an alignment caught in a wrong minimum leaves 60-70%, a right one >99%.
//
// Per-frame statistics (VoResult): matches = reference pixels compared at full resolution,
// inliers = those whose residual is within inlier_residual_grey, mean_inlier_depth_m = their
// mean depth in the current frame (covariate d), valid_depth_pixels = pixels with a valid
// disparity in the reference (previous) pair, whose depth the motion was estimated from
// (covariate f).
//
// Determinism: single-threaded apart from OpenCV's own parallel loops (SGBM, blur, resize, box
// filters), which split work by rows without changing any result; the SGBM modes offered do not
// depend on the thread count (tests/vo/dense_vo_test.cpp checks 1 and several OpenCV threads).
#pragma once

#include <memory>
#include <string>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "vo/dense/dense_options.hpp"
#include "vo/dense/disparity.hpp"
#include "vo/dense/photometric.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::vo {

namespace dense {
/// cv::StereoSGBM's mode constant for a DenseSgbmMode.
int sgbm_mode(DenseSgbmMode mode);
/// The disparity estimator's settings that a dense VO with these options uses.
DisparityOptions disparity_options(const DenseVoOptions& options);
/// Which reference pixels a dense VO with these options keeps.
RefSelection ref_selection(const DenseVoOptions& options);
/// The alignment settings of a dense VO with these options.
AlignOptions align_options(const DenseVoOptions& options);
}  // namespace dense

/// Details of the last process() call, for diagnostics, tests and benchmarks.
struct DenseFrameStats {
  int valid_depth_pixels = 0;      ///< current pair: pixels with a valid disparity
  int textured_pixels = 0;         ///< current left image: |grad I| >= min_gradient_grey_per_px
  int textured_depth_pixels = 0;   ///< of those, with a valid disparity
  int reference_points = 0;        ///< previous pair: points at full resolution used as reference
  int iterations = 0;              ///< Levenberg-Marquardt iterations over all levels
  double rms_residual_grey = 0.0;  ///< Eq. (9) residual at the final motion, full resolution
  double sigma_grey = 0.0;         ///< t-distribution scale at the end (robust weights only)
  double pyramid_ms = 0.0;         ///< image pyramid of the current left image
  double sgbm_ms = 0.0;            ///< disparity of the current pair (SGBM and refinement)
  double reference_ms = 0.0;       ///< Eq. (1) points and Jacobians of the current pair
  double align_ms = 0.0;           ///< Levenberg-Marquardt
};

/// The dense VO. Not thread-safe; one instance per stream of frames.
class DenseStereoOdometry final : public StereoOdometry {
 public:
  /// Throws UserError when the rig or the options are invalid, or the coarsest pyramid level
  /// is smaller than 8 px a side. `rng` is kept for a uniform constructor; the method draws no
  /// random numbers.
  DenseStereoOdometry(const StereoRig& rig, const DenseVoOptions& options, Rng rng);
  ~DenseStereoOdometry() override;

  VoResult process(const StereoFrame& frame) override;
  void reset() override;
  std::string name() const override { return "dense"; }

  const DenseVoOptions& options() const;
  const DenseFrameStats& last_stats() const;
  /// The last pair's disparity (CV_32FC1 [px], refined if so set; below min_disparity_px: no
  /// depth), valid until the next process() call.
  const cv::Mat& last_disparity() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace driftlab::vo
