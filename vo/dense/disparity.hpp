// Disparity of a rectified pair for the dense VO: cv::StereoSGBM (river paper Section 2.3.2,
// "semi-global block matching [49]"), optionally refined to sub-pixel precision by windowed
// Lucas-Kanade along the rows (ours, see DisparityEstimator::refine).
#pragma once

#include <limits>

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
  int mode = cv::StereoSGBM::MODE_SGBM;  ///< cv::StereoSGBM's mode
  /// SGBM runs on the pair shrunk by this factor (cv::INTER_AREA) with num_disparities /
  /// downsample disparities (rounded up to a multiple of 16); its disparity is scaled back to
  /// full resolution by nearest-neighbour lookup, for the refinement to make sub-pixel. 1: SGBM
  /// on the full pair.
  int downsample = 1;
  int refine_iterations = 0;       ///< 0: SGBM's own sub-pixel disparity
  int refine_window = 9;           ///< side of the refinement window [px], odd
  double refine_max_change = 1.0;  ///< a larger total change invalidates the pixel [px]
  /// A refined pixel whose window's RMS residual |L(x) - R(x - d)| exceeds this loses its
  /// disparity [grey levels]; infinity keeps every pixel.
  double refine_max_residual = std::numeric_limits<double>::infinity();
};

/// The disparities SGBM searches on the (possibly shrunk) pair: num_disparities / downsample,
/// rounded up to a multiple of 16, so that the full-resolution range is covered.
int searched_disparities(const DisparityOptions& options);

/// SGBM plus refinement, with buffers kept between calls. Not thread-safe.
class DisparityEstimator {
 public:
  /// kSimd: the refinement's row loops four pixels at a time (OpenCV's universal intrinsics)
  /// where the build has them; kScalar: one at a time. Both give the same bytes (tests compare).
  enum class Lanes { kSimd, kScalar };

  explicit DisparityEstimator(const DisparityOptions& options, Lanes lanes = Lanes::kSimd);

  /// Disparity of the left image [px], CV_32FC1; 0 where SGBM found none. `left_f32` is the
  /// left image as CV_32FC1 (the pyramid's finest level), used by the refinement only.
  void compute(const cv::Mat& left8, const cv::Mat& right8, const cv::Mat& left_f32,
               cv::Mat* disparity);

 private:
  // Lucas-Kanade on the disparity, one common correction per window: with R_w(x) = R(x - d(x))
  // and e = L - R_w, minimise sum_window (e + dR/dx(x - d) delta)^2 over delta; the sums are box
  // filters, so an iteration costs a few passes over the image whatever the window.
  void refine(const cv::Mat& left_f32, cv::Mat* disparity);
  /// Per pixel of row v at the given disparity, with e = L - R_w and g = dR/dx(x - d): g e into
  /// ge_ and g^2 into gg_ (slopes) or e^2 into ee_ (zeros without a disparity or outside the
  /// right image).
  void linearise_row(const cv::Mat& left_f32, const cv::Mat& disparity, int v, bool slopes);

  /// SGBM on the (possibly shrunk) pair, written as full-resolution disparity [px] with 0 where
  /// SGBM found none.
  void match(const cv::Mat& left8, const cv::Mat& right8, cv::Mat* disparity);

  DisparityOptions options_;
  bool simd_ = true;
  cv::Ptr<cv::StereoSGBM> sgbm_;
  cv::Mat small_left_, small_right_, small_disparity_;
  cv::Mat raw_, sgbm_disparity_, right_f32_, right_dx_, ge_, gg_, ee_, ge_sum_, gg_sum_, ee_mean_;
};

}  // namespace driftlab::vo::dense
