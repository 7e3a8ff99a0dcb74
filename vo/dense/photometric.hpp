// The photometric alignment of the dense VO (river paper Section 2.3.2): image pyramids, the
// reference points of Eq. (1) with their Jacobians, and Levenberg-Marquardt on Eq. (9).
//
// Formulation: inverse compositional (Baker and Matthews 2004) on SE(3). With P_i the 3D point
// of reference pixel p_i (Eq. (1)), T = T_curr_prev the motion of Eq. (6) and pi the projection
// of Eq. (7), the residual of Eq. (9) is
//     r_i(T) = I_curr(pi(T P_i)) - I_prev(p_i).
// Each step looks for a small motion xi of the *reference* that explains the residuals,
//     I_curr(pi(T P_i)) ~ I_prev(pi(exp(xi) P_i)) ~ I_prev(p_i) + J_i xi,
// and composes T <- T exp(xi)^-1. J_i = grad I_prev(p_i) * d pi / d P * [I | -hat(P_i)] depends
// on the reference only, so it is computed once per level and frame; an iteration costs one
// warp of the current image. xi = [rho (translation, m); phi (rotation vector, rad)], as
// SE3::exp takes it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include <Eigen/Core>
#include <opencv2/core/mat.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"

namespace driftlab::vo::dense {

using Row6 = Eigen::Matrix<double, 1, 6>;
using Mat26 = Eigen::Matrix<double, 2, 6>;

/// Pinhole intrinsics of one pyramid level [px of that level]. The level image is the full one
/// resized by (sx, sy) = (width / W, height / H) with cv::resize's pixel-centre convention, so
/// a full-resolution pixel x maps to (x + 0.5) sx - 0.5.
struct LevelCamera {
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;
  double sx = 1, sy = 1;
};
/// The level of `camera` at `scale` (its size rounded to whole pixels).
LevelCamera level_camera(const PinholeCamera& camera, double scale);

/// d pi(exp(xi) P) / d xi at xi = 0 [px per m, px per rad]: Eq. (7) after Eq. (6).
Mat26 warp_jacobian(const Vec3& P, double fx, double fy);
/// One row of the Jacobian of Eq. (9)'s residual: [gx gy] * warp_jacobian(P) (the image
/// gradient in grey levels per pixel).
Row6 photometric_jacobian(double gx, double gy, const Vec3& P, double fx, double fy);

/// Bilinear interpolation of a CV_32FC1 image at (u, v), which must lie in
/// [0, cols - 1) x [0, rows - 1).
inline float bilinear(const cv::Mat& img, float u, float v) {
  const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
  const float ax = u - static_cast<float>(x0), ay = v - static_cast<float>(y0);
  const float* p = img.ptr<float>(y0) + x0;
  const float* q = p + img.step1();
  return (1.0f - ay) * ((1.0f - ax) * p[0] + ax * p[1]) + ay * ((1.0f - ax) * q[0] + ax * q[1]);
}

/// The levels of one left image, coarsest first, CV_32FC1 grey levels. Buffers are reused.
struct Pyramid {
  std::vector<LevelCamera> cameras;
  std::vector<cv::Mat> images;
  cv::Mat blurred;  // scratch

  void configure(const PinholeCamera& camera, const std::vector<double>& scales);
  /// Paper: levels below full size are the full image blurred by a Gaussian of `blur_sigma_px`
  /// (0: none), then resized bilinearly; or, with `area_downscaling`, by averaging the pixels
  /// each level pixel covers (cv::INTER_AREA).
  void build(const cv::Mat& gray8, double blur_sigma_px, bool area_downscaling = false);
};

/// A reference pixel of one level: its Eq. (1) point in the reference left optical frame [m]
/// and its intensity [grey]. What the warp reads, kept apart from the Jacobians.
struct RefPoint {
  float x, y, z;
  float intensity;
};

/// The Jacobian row of a reference pixel (photometric_jacobian) [grey per m, per rad] in J[0..5];
/// J[6] and J[7] are zero padding, so a row is two aligned packets of four floats.
struct alignas(16) RefJacobian {
  float J[8];
};

/// The reference pixels of one pyramid level.
struct RefLevel {
  std::vector<RefPoint> points;
  std::vector<RefJacobian> jacobians;  ///< one per point
  /// Full resolution only, one per point: 1 where the gradient reaches min_gradient (the points
  /// whose residuals tell a misalignment; flat ones stay small whatever the motion).
  std::vector<std::uint8_t> textured;
  void clear() {
    points.clear();
    jacobians.clear();
    textured.clear();
  }
  std::size_t size() const { return points.size(); }
  /// n points (and n textured flags, or none); what was there is overwritten.
  void resize(std::size_t n, bool with_textured) {
    points.resize(n);
    jacobians.resize(n);
    textured.resize(with_textured ? n : 0);
  }
};

/// What selects reference pixels.
struct RefSelection {
  double min_disparity_px = 1.0;   ///< smaller disparities have no depth
  bool gradient_mask = false;      ///< keep only pixels with |grad I| >= min_gradient
  double min_gradient = 0.0;       ///< grey levels per full-resolution pixel (the full image's)
  double lower_mask_fraction = 0;  ///< rows below (1 - fraction) * height are ignored
};

/// The reference points of every level of one frame, and the frame's statistics.
struct Reference {
  std::vector<RefLevel> levels;   ///< coarsest first, as the pyramid
  int valid_depth_pixels = 0;     ///< full-resolution pixels with disparity >= min (covariate f)
  int textured_pixels = 0;        ///< full-resolution pixels with |grad I| >= min_gradient
  int textured_depth_pixels = 0;  ///< of those, with a valid depth
  cv::Mat textured;               ///< scratch: full-resolution texture mask, CV_8UC1 0/1
  std::vector<int> col_first, col_last, row_first, row_last;  ///< scratch: coarse pixel blocks
  /// scratch, per row of the level being selected: its points and the index of its first one
  std::vector<int> row_points;
  std::vector<std::size_t> row_offset;
  std::vector<int> row_textured, row_both;  ///< scratch, per full-resolution row
  cv::Mat level_disparity;  ///< scratch: a coarse level's disparities, NaN where not kept
};

/// Builds the reference of a frame from its pyramid and its full-resolution disparity
/// (CV_32FC1 [px]; below selection.min_disparity_px: no depth). A coarse-level pixel takes the
/// mean disparity of the full-resolution pixels it covers, and only when all of them are valid:
/// for a plane the disparity is affine in the pixel, so that mean is the disparity at the level
/// pixel's centre. The gradient mask is decided at full resolution, where texture and water
/// differ (blur leaves both with similar gradients at the coarse levels): a coarse pixel is kept
/// when at least half the pixels it covers are textured. `baseline_fx` is f B of Eq. (1) [px m].
void build_reference(const Pyramid& pyramid, const cv::Mat& disparity, double baseline_fx,
                     const RefSelection& selection, Reference* out);

/// Eq. (9)'s residual I(warp(P)) - I_ref of each of the n points at motion T into out[0..n):
/// the current level image (CV_32FC1, camera `cam`) at the pixel where Eqs. (6)-(7) put the
/// point, bilinear, minus its intensity; NaN where it leaves the image or falls behind the
/// camera. Returns the number of finite residuals. `lanes`: four points at a time where the build
/// has SIMD (OpenCV's universal intrinsics), else one at a time; the same bytes (tests compare).
int warp_residuals(const RefPoint* points, std::size_t n, const cv::Mat& image,
                   const LevelCamera& cam, const SE3& T, bool lanes, float* out);

struct AlignOptions {
  std::vector<int> max_iterations;  ///< per level, coarsest first
  double initial_lambda = 1e-4;
  double step_tolerance = 1e-6;
  bool robust = false;  ///< t-distribution weights (Kerl et al. 2013)
  double t_dof = 5.0;
  double inlier_residual = 16.0;  ///< grey levels
};

/// Outcome of one alignment. The statistics are of the finest level at the final motion.
struct AlignSummary {
  bool ok = false;
  const char* failure = "";          ///< why not, when !ok
  int used = 0;                      ///< reference points that project into the current image
  int inliers = 0;                   ///< of those, |r| <= inlier_residual
  int textured_used = 0;             ///< used points that are textured (RefLevel::textured)
  int textured_inliers = 0;          ///< of those, inliers
  double mean_inlier_depth_m = 0.0;  ///< mean depth of the inliers in the current frame
  double rms_residual = 0.0;         ///< of the used points [grey]
  double sigma = 0.0;                ///< t-distribution scale at the end [grey]; 0 if not robust
  int iterations = 0;                ///< over all levels
};

/// Levenberg-Marquardt on Eq. (9). Keeps its buffers between calls; not thread-safe.
class Aligner {
 public:
  /// Refines *T_curr_prev (in: initial guess) so that the current pyramid seen through it
  /// matches the reference.
  AlignSummary align(const Reference& ref, const Pyramid& current, const AlignOptions& options,
                     SE3* T_curr_prev);

 private:
  // Sums of the weighted normal equations of one set of residuals.
  struct Normal {
    double H[6][6];  // sum w J^T J
    double b[6];     // sum w J^T r
    double wrr;      // sum w r^2
  };
  // Residuals of every reference point at motion T into *residuals (NaN where the point leaves
  // the image or falls behind the camera). Returns the number of finite residuals and sets
  // *cost to the mean of the step-acceptance cost under scale sigma2 (see cost_scale()).
  int warp(const RefLevel& level, const cv::Mat& image, const LevelCamera& cam, const SE3& T,
           double sigma2, std::vector<float>* residuals, double* cost) const;
  double estimate_sigma2(const std::vector<float>& residuals, int used, double sigma2) const;
  void normal_equations(const RefLevel& level, const std::vector<float>& residuals, double sigma2,
                        Normal* n) const;
  // The step-acceptance cost of a residual set is cost_scale() * sum w r^2 / used.
  double cost_scale() const;

  std::vector<float> res_, res_try_;
  AlignOptions options_;
};

}  // namespace driftlab::vo::dense
