// Disparity of a rectified pair for the dense VO: cv::StereoSGBM (river paper Section 2.3.2,
// "semi-global block matching [49]"), optionally refined to sub-pixel precision by windowed
// Lucas-Kanade along the rows (ours, see DisparityEstimator::refine).
#pragma once

#include <opencv2/calib3d.hpp>
#include <opencv2/core/mat.hpp>

namespace driftlab::vo::dense {

struct DisparityOptions {
  int num_disparities = 64;
  int block_size = 5;
  int p1 = 200, p2 = 800;
  int disp12_max_diff = 1;
  int pre_filter_cap = 63;
  int uniqueness_ratio = 10;
  int speckle_window = 100;
  int speckle_range = 2;
  bool full_dp = false;            ///< MODE_HH instead of MODE_SGBM
  int refine_iterations = 0;       ///< 0: SGBM's own sub-pixel disparity
  int refine_window = 9;           ///< side of the refinement window [px], odd
  double refine_max_change = 1.0;  ///< a larger total change invalidates the pixel [px]
};

/// SGBM plus refinement, with buffers kept between calls. Not thread-safe.
class DisparityEstimator {
 public:
  explicit DisparityEstimator(const DisparityOptions& options);

  /// Disparity of the left image [px], CV_32FC1; 0 where SGBM found none. `left_f32` is the
  /// left image as CV_32FC1 (the pyramid's finest level), used by the refinement only.
  void compute(const cv::Mat& left8, const cv::Mat& right8, const cv::Mat& left_f32,
               cv::Mat* disparity);

 private:
  // Lucas-Kanade on the disparity, one common correction per window: with R_w(x) = R(x - d(x))
  // and e = L - R_w, minimise sum_window (e + dR/dx(x - d) delta)^2 over delta; the sums are box
  // filters, so an iteration costs a few passes over the image whatever the window.
  void refine(const cv::Mat& left_f32, cv::Mat* disparity);

  DisparityOptions options_;
  cv::Ptr<cv::StereoSGBM> sgbm_;
  cv::Mat raw_, sgbm_disparity_, right_f32_, right_dx_, ge_, gg_, ge_sum_, gg_sum_;
};

}  // namespace driftlab::vo::dense
