// Spatial alignment of an estimated trajectory to ground truth before the
// absolute error is measured: the transform T minimising
// sum_i |gt_i - T(est_i)|^2 over corresponding positions [m].
//
// All functions take the positions of associated poses, est[i] <-> gt[i], and
// throw UserError for too few points or a degenerate set (all estimate or all
// ground-truth points at one place, where the rotation is undetermined).
// Collinear points (a straight run) are accepted: the rotation about the line
// is then unobservable and its value is whatever the solver returns; the
// aligned positions, and so the translation error, do not depend on it.
// (A deliberate difference: evo's umeyama_alignment raises "Degenerate
// covariance rank" when fewer than 2 singular values exceed machine epsilon.)
#pragma once

#include <string>
#include <vector>

#include "core/se3.hpp"
#include "eval/eval_options.hpp"

namespace driftlab::eval {

/// p -> scale * R * p + t. A pose maps to rotation R * R_p and translation
/// scale * R * t_p + t, as evo's PosePath3D.align / scale do.
struct SimilarityTransform {
  Mat3 R = Mat3::Identity();
  Vec3 t = Vec3::Zero();
  double scale = 1.0;

  Vec3 apply(const Vec3& p) const { return scale * (R * p) + t; }
  SE3 apply(const SE3& pose) const;
  /// Applies the transform to every pose.
  std::vector<SE3> apply(const std::vector<SE3>& poses) const;
};

/// Rotation and translation by Horn's closed form with unit quaternions (at
/// least 3 points). This is the river paper's alignment (its reference [48]).
SimilarityTransform align_horn(const std::vector<Vec3>& est, const std::vector<Vec3>& gt);

/// Umeyama's SVD solution with the reflection fix (at least 3 points):
/// rotation and translation, plus Umeyama's scale (est -> gt, not symmetric)
/// when `with_scale`. Without scale it gives the same transform as Horn.
SimilarityTransform align_umeyama(const std::vector<Vec3>& est, const std::vector<Vec3>& gt,
                                  bool with_scale);

/// Rotation about the world z axis (yaw) and a 3-D translation, 4 degrees of
/// freedom (at least 2 points): the gauge of an inertial-aided estimate, whose
/// roll and pitch are observable through gravity. Throws when either point set
/// has no horizontal extent, where yaw is undetermined.
SimilarityTransform align_pos_yaw(const std::vector<Vec3>& est, const std::vector<Vec3>& gt);

/// Dispatch by `method` on the first `first_n` pairs (0 or more than there
/// are: all; as evo's --n_to_align). kNone gives the identity without looking
/// at the points. Throws UserError for first_n < 0.
SimilarityTransform compute_alignment(Alignment method, const std::vector<Vec3>& est,
                                      const std::vector<Vec3>& gt, int first_n = 0);

/// An alignment as fitted, with what the geometry left unobservable.
struct AlignmentFit {
  SimilarityTransform transform;
  std::string warning;  ///< empty when every degree of freedom was observable
};

/// compute_alignment that refuses to invent a rotation. A rigid fit (horn, se3, sim3) determines
/// the rotation about the ground-truth track's principal axis only through the track's spread
/// across that axis; on a straight or back-and-forth track that spread is smaller than the
/// estimate's errors (or zero), and the fit turns the estimate about the axis to absorb them.
/// When the RMS distance of the ground truth from its principal axis is below
/// kMinAxisSpreadToResidual times the fit's RMS residual (or zero), the fit falls back to what is
/// observable: the rotation taking the estimate's principal axis onto the truth's (no turn about
/// it), the scale (sim3) and the translation, and says so in `warning`. posyaw and none have no
/// such rotation and are returned as compute_alignment gives them.
AlignmentFit fit_alignment(Alignment method, const std::vector<Vec3>& est,
                           const std::vector<Vec3>& gt, int first_n = 0);

/// The across-axis spread a rigid fit needs, in units of its RMS residual.
inline constexpr double kMinAxisSpreadToResidual = 3.0;

}  // namespace driftlab::eval
