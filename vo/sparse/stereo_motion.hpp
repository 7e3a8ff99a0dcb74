// Sparse VO internals, step (iv) of river paper Section 2.3.1: the incremental motion that
// minimises the stereo reprojection error of Eq. (2) by Gauss-Newton, inside RANSAC.
// Internal to vo/sparse (tests include it).
#pragma once

#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "core/se3.hpp"
#include "vo/sparse/sparse_options.hpp"

namespace driftlab::vo::sparse {

/// A scene point triangulated in the previous left camera by Eq. (1) and where it was
/// observed in the current left and right images.
struct StereoPointMatch {
  Vec3 p_prev = Vec3::Zero();  ///< previous left optical frame [m]
  double u_l = 0, v_l = 0;     ///< current left observation [px]
  double u_r = 0, v_r = 0;     ///< current right observation [px]
};

using Vec4 = Eigen::Matrix<double, 4, 1>;
using Mat46 = Eigen::Matrix<double, 4, 6>;

/// Points closer than this to the current camera plane are "behind" it: no projection [m].
inline constexpr double kMinProjectionDepthM = 1e-3;

/// pi^(l) and pi^(r) of Eq. (2): the pixels [u_l, v_l, u_r, v_r] of p_prev in the current
/// cameras, with p_curr = T_curr_prev * p_prev. With J, also d(pixels)/d(xi) for the left
/// perturbation T_curr_prev -> exp(xi) * T_curr_prev, xi = [rho; phi] (SE3::exp). Returns
/// false when the point is not in front of the current camera.
bool project_stereo(const StereoRig& rig, const Mat3& R_curr_prev, const Vec3& t_curr_prev,
                    const Vec3& p_prev, Vec4* pixels, Mat46* J);

/// Both images' reprojection errors of one match [px]: (left, right) Euclidean norms.
/// Infinite when the point is not in front.
std::pair<double, double> reprojection_errors(const StereoRig& rig, const Mat3& R, const Vec3& t,
                                              const StereoPointMatch& m);

/// The RANSAC + Gauss-Newton estimator; its index buffers are reused between calls.
class StereoMotionEstimator {
 public:
  StereoMotionEstimator(const StereoRig& rig, const SparseVoOptions& options);

  /// Minimises Eq. (2) over matches[indices] by Gauss-Newton, starting from and updating
  /// *T_curr_prev. False when the normal equations are singular or the iterate not finite
  /// (T is then left unchanged).
  bool gauss_newton(std::span<const StereoPointMatch> matches, std::span<const int> indices,
                    SE3* T_curr_prev) const;

  /// Indices of the matches whose left and right reprojection errors under T are both at
  /// most inlier_threshold_px.
  void inliers(std::span<const StereoPointMatch> matches, const SE3& T_curr_prev,
               std::vector<int>* out);

  /// MSAC's cost of T over the matches (ransac_score msac ranks hypotheses by it): the sum of
  /// each match's squared reprojection error, the larger of its left and right image's,
  /// truncated at inlier_threshold_px squared; a point not in front costs the truncation.
  double msac_cost(std::span<const StereoPointMatch> matches, const SE3& T_curr_prev);

  struct Result {
    bool ok = false;
    std::string failure;                  ///< why not, when !ok
    SE3 T_curr_prev;                      ///< maps previous-frame points into the current frame
    std::vector<int>* inliers = nullptr;  ///< points into the estimator's buffer
  };

  /// RANSAC: ransac_iterations times, Gauss-Newton from `initial` (identity: no motion) on
  /// ransac_sample_size matches drawn from `rng`; the iteration with the most inliers (or with
  /// ransac_score msac, the least truncated cost) wins (the first of equals), and with
  /// final_refinement Eq. (2) is minimised again over its inliers.
  Result estimate(std::span<const StereoPointMatch> matches, Rng* rng, const SE3& initial = SE3());

 private:
  void load(std::span<const StereoPointMatch> matches);
  class SquaredErrors;  // the loaded matches' squared reprojection errors under a motion
  SquaredErrors squared_errors(const SE3& T_curr_prev) const;
  int collect_inliers(const SE3& T_curr_prev, int to_beat, std::vector<int>* out) const;
  double msac_cost(const SE3& T_curr_prev, double to_beat) const;

  StereoRig rig_;
  SparseVoOptions options_;
  std::vector<int> sample_, candidate_, best_, refined_;
  std::vector<double> X_, Y_, Z_, ul_, vl_, ur_, vr_;  // the matches, structure of arrays
};

}  // namespace driftlab::vo::sparse
