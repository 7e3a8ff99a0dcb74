#include "eval/align.hpp"

#include <fmt/format.h>

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <string_view>

#include "core/error.hpp"

namespace driftlab::eval {

namespace {

// A point set whose RMS spread about its centroid is below this fraction of
// its largest coordinate magnitude is one point to double precision:
// centring alone leaves ~eps * |p| of rounding in every coordinate.
constexpr double kCoincidentRelTol = 1e-12;

struct Centred {
  Vec3 mean = Vec3::Zero();
  std::vector<Vec3> points;  // p_i - mean
  double variance = 0.0;     // mean of |p_i - mean|^2
};

Centred centre(const std::vector<Vec3>& p) {
  Centred c;
  for (const Vec3& x : p) c.mean += x;
  c.mean /= static_cast<double>(p.size());
  c.points.reserve(p.size());
  for (const Vec3& x : p) {
    c.points.push_back(x - c.mean);
    c.variance += c.points.back().squaredNorm();
  }
  c.variance /= static_cast<double>(p.size());
  return c;
}

void check_finite(const std::vector<Vec3>& p, std::string_view method, std::string_view which) {
  for (std::size_t i = 0; i < p.size(); ++i) {
    if (!p[i].allFinite()) {
      throw UserError(fmt::format("{} alignment: {} position {} is not finite: ({}, {}, {})",
                                  method, which, i, p[i].x(), p[i].y(), p[i].z()));
    }
  }
}

void check_inputs(const std::vector<Vec3>& est, const std::vector<Vec3>& gt, std::size_t min_points,
                  std::string_view method) {
  DRIFTLAB_DEMAND_MSG(est.size() == gt.size(),
                      "alignment needs one ground-truth position per estimate position");
  if (est.size() < min_points) {
    throw UserError(fmt::format("{} alignment needs at least {} associated poses, got {}", method,
                                min_points, est.size()));
  }
  check_finite(est, method, "estimate");
  check_finite(gt, method, "ground-truth");
}

// `spread_sq` is the mean squared distance from the centroid of whatever part
// of the points the method uses (all three axes, or the horizontal plane).
void check_spread(const std::vector<Vec3>& p, double spread_sq, std::string_view method,
                  std::string_view which, std::string_view extent) {
  double max_abs = 0.0;
  for (const Vec3& x : p) max_abs = std::max(max_abs, x.cwiseAbs().maxCoeff());
  if (std::sqrt(spread_sq) <= kCoincidentRelTol * max_abs) {
    throw UserError(fmt::format(
        "{} alignment is undetermined: all {} {} positions coincide{} (first at ({}, {}, {}))",
        method, p.size(), which, extent, p.front().x(), p.front().y(), p.front().z()));
  }
}

void check_spread_3d(const std::vector<Vec3>& est, const Centred& ce, const std::vector<Vec3>& gt,
                     const Centred& cg, std::string_view method) {
  check_spread(est, ce.variance, method, "estimate", "");
  check_spread(gt, cg.variance, method, "ground-truth", "");
}

}  // namespace

SE3 SimilarityTransform::apply(const SE3& pose) const {
  return SE3(Quat(R) * pose.quaternion(), scale * (R * pose.translation()) + t);
}

std::vector<SE3> SimilarityTransform::apply(const std::vector<SE3>& poses) const {
  std::vector<SE3> out;
  out.reserve(poses.size());
  for (const SE3& p : poses) out.push_back(apply(p));
  return out;
}

SimilarityTransform align_horn(const std::vector<Vec3>& est, const std::vector<Vec3>& gt) {
  check_inputs(est, gt, 3, "Horn");
  const Centred ce = centre(est);
  const Centred cg = centre(gt);
  check_spread_3d(est, ce, gt, cg, "Horn");

  // Horn 1987, "Closed-form solution of absolute orientation using unit
  // quaternions", Sec. 4: with M = sum a_i b_i^T (a = centred estimate, the
  // set to be rotated; b = centred ground truth; S_xy = M(x, y)), the rotation
  // maximising sum b_i . R a_i is the unit quaternion (w, x, y, z) along the
  // eigenvector of the largest eigenvalue of the symmetric 4x4 matrix N below.
  // The optimal translation then maps the estimate centroid onto the ground-truth one.
  Mat3 M = Mat3::Zero();
  for (std::size_t i = 0; i < est.size(); ++i) M += ce.points[i] * cg.points[i].transpose();
  const double Sxx = M(0, 0), Sxy = M(0, 1), Sxz = M(0, 2);
  const double Syx = M(1, 0), Syy = M(1, 1), Syz = M(1, 2);
  const double Szx = M(2, 0), Szy = M(2, 1), Szz = M(2, 2);
  Eigen::Matrix4d N;
  N << Sxx + Syy + Szz, Syz - Szy, Szx - Sxz, Sxy - Syx,  //
      Syz - Szy, Sxx - Syy - Szz, Sxy + Syx, Szx + Sxz,   //
      Szx - Sxz, Sxy + Syx, -Sxx + Syy - Szz, Syz + Szy,  //
      Sxy - Syx, Szx + Sxz, Syz + Szy, -Sxx - Syy + Szz;
  // Eigen sorts the eigenvalues of a self-adjoint matrix in increasing order.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix4d> eig(N);
  DRIFTLAB_DEMAND_MSG(eig.info() == Eigen::Success, "Horn alignment: eigen-decomposition failed");
  const Eigen::Vector4d v = eig.eigenvectors().col(3);
  const Quat q = Quat(v(0), v(1), v(2), v(3)).normalized();

  SimilarityTransform T;
  T.R = q.toRotationMatrix();
  T.t = cg.mean - T.R * ce.mean;
  return T;
}

SimilarityTransform align_umeyama(const std::vector<Vec3>& est, const std::vector<Vec3>& gt,
                                  bool with_scale) {
  const std::string_view method = with_scale ? "Sim3 (Umeyama)" : "SE3 (Umeyama)";
  check_inputs(est, gt, 3, method);
  const Centred ce = centre(est);
  const Centred cg = centre(gt);
  check_spread_3d(est, ce, gt, cg, method);

  // Umeyama 1991, "Least-squares estimation of transformation parameters
  // between two point patterns": Sigma = 1/n sum b_i a_i^T (Eq. 38) = U D V^T;
  // R = U S V^T (Eq. 40) with S = diag(1, 1, -1) when det(U) det(V) < 0, so
  // that a reflection is never returned (Eq. 39/43: this form also covers a
  // rank-2 Sigma, i.e. planar points); c = tr(D S) / sigma_a^2 (Eq. 42);
  // t = mu_b - c R mu_a (Eq. 41).
  Mat3 Sigma = Mat3::Zero();
  for (std::size_t i = 0; i < est.size(); ++i) Sigma += cg.points[i] * ce.points[i].transpose();
  Sigma /= static_cast<double>(est.size());
  const Eigen::JacobiSVD<Mat3> svd(Sigma, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Vec3 s(1.0, 1.0, 1.0);
  if (svd.matrixU().determinant() * svd.matrixV().determinant() < 0.0) s(2) = -1.0;

  SimilarityTransform T;
  T.R = svd.matrixU() * s.asDiagonal() * svd.matrixV().transpose();
  if (with_scale) T.scale = svd.singularValues().dot(s) / ce.variance;
  T.t = cg.mean - T.scale * (T.R * ce.mean);
  return T;
}

SimilarityTransform align_pos_yaw(const std::vector<Vec3>& est, const std::vector<Vec3>& gt) {
  constexpr std::string_view method = "Position+yaw";
  check_inputs(est, gt, 2, method);
  const Centred ce = centre(est);
  const Centred cg = centre(gt);

  // With R = Rz(psi) the cost sum |b_i - R a_i|^2 depends on psi only through
  // -2 sum b_i . R a_i = -2 (C cos psi + S sin psi) + const, where C and S are
  // the summed dot and cross products of the horizontal parts; its minimum is
  // at psi = atan2(S, C). (The vertical parts enter only the constant.)
  double C = 0.0, S = 0.0, est_h = 0.0, gt_h = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) {
    const Vec3& a = ce.points[i];
    const Vec3& b = cg.points[i];
    C += a.x() * b.x() + a.y() * b.y();
    S += a.x() * b.y() - a.y() * b.x();
    est_h += a.head<2>().squaredNorm();
    gt_h += b.head<2>().squaredNorm();
  }
  const double n = static_cast<double>(est.size());
  check_spread(est, est_h / n, method, "estimate", " in the horizontal plane");
  check_spread(gt, gt_h / n, method, "ground-truth", " in the horizontal plane");

  SimilarityTransform T;
  T.R = Eigen::AngleAxisd(std::atan2(S, C), Vec3::UnitZ()).toRotationMatrix();
  T.t = cg.mean - T.R * ce.mean;
  return T;
}

SimilarityTransform compute_alignment(Alignment method, const std::vector<Vec3>& est,
                                      const std::vector<Vec3>& gt, int first_n) {
  DRIFTLAB_DEMAND_MSG(est.size() == gt.size(),
                      "alignment needs one ground-truth position per estimate position");
  if (first_n < 0) throw UserError(fmt::format("align_first_n must be >= 0, got {}", first_n));
  if (method == Alignment::kNone) return {};
  std::vector<Vec3> e = est;
  std::vector<Vec3> g = gt;
  if (first_n > 0 && static_cast<std::size_t>(first_n) < e.size()) {
    e.resize(static_cast<std::size_t>(first_n));
    g.resize(static_cast<std::size_t>(first_n));
  }
  switch (method) {
    case Alignment::kHorn:
      return align_horn(e, g);
    case Alignment::kSe3:
      return align_umeyama(e, g, false);
    case Alignment::kSim3:
      return align_umeyama(e, g, true);
    case Alignment::kPosYaw:
      return align_pos_yaw(e, g);
    case Alignment::kNone:
      break;
  }
  return {};
}

namespace {

// Unit principal axis (largest eigenvalue of the scatter) and the eigenvalues, decreasing.
struct Principal {
  Vec3 axis = Vec3::UnitX();
  Vec3 eigenvalues = Vec3::Zero();  // of the mean scatter (1/n) sum p p^T [m^2]
};

Principal principal(const Centred& c) {
  Mat3 C = Mat3::Zero();
  for (const Vec3& p : c.points) C += p * p.transpose();
  C /= static_cast<double>(c.points.size());
  const Eigen::SelfAdjointEigenSolver<Mat3> eig(C);
  DRIFTLAB_DEMAND_MSG(eig.info() == Eigen::Success, "alignment: eigen-decomposition failed");
  Principal out;
  out.axis = eig.eigenvectors().col(2);
  out.eigenvalues = Vec3(eig.eigenvalues()(2), eig.eigenvalues()(1), eig.eigenvalues()(0));
  return out;
}

double rms_residual(const SimilarityTransform& T, const std::vector<Vec3>& est,
                    const std::vector<Vec3>& gt) {
  double sum = 0.0;
  for (std::size_t i = 0; i < est.size(); ++i) sum += (gt[i] - T.apply(est[i])).squaredNorm();
  return std::sqrt(sum / static_cast<double>(est.size()));
}

// The observable part of a rigid fit on a (nearly) collinear track: the smallest rotation taking
// the estimate's principal axis onto the truth's, then scale (sim3) and translation.
SimilarityTransform axis_alignment(const Centred& ce, const Centred& cg, const Vec3& gt_axis,
                                   bool with_scale) {
  Vec3 est_axis = principal(ce).axis;
  double along = 0.0;  // the axes point the same way when the positions along them correlate
  for (std::size_t i = 0; i < ce.points.size(); ++i)
    along += est_axis.dot(ce.points[i]) * gt_axis.dot(cg.points[i]);
  if (along < 0.0) est_axis = -est_axis;
  SimilarityTransform T;
  T.R = Quat::FromTwoVectors(est_axis, gt_axis).toRotationMatrix();
  if (with_scale) {
    double num = 0.0;
    for (std::size_t i = 0; i < ce.points.size(); ++i) num += cg.points[i].dot(T.R * ce.points[i]);
    T.scale = num / (ce.variance * static_cast<double>(ce.points.size()));
  }
  T.t = cg.mean - T.scale * (T.R * ce.mean);
  return T;
}

}  // namespace

AlignmentFit fit_alignment(Alignment method, const std::vector<Vec3>& est,
                           const std::vector<Vec3>& gt, int first_n) {
  AlignmentFit fit{compute_alignment(method, est, gt, first_n), {}};
  if (method == Alignment::kNone || method == Alignment::kPosYaw) return fit;
  const std::size_t n =
      first_n > 0 ? std::min(est.size(), static_cast<std::size_t>(first_n)) : est.size();
  const std::vector<Vec3> e(est.begin(), est.begin() + static_cast<std::ptrdiff_t>(n));
  const std::vector<Vec3> g(gt.begin(), gt.begin() + static_cast<std::ptrdiff_t>(n));
  const Centred ce = centre(e);
  const Centred cg = centre(g);
  const Principal pg = principal(cg);
  // RMS distance of the truth from its principal axis: the lever arm of a turn about the axis.
  const double across = std::sqrt(std::max(0.0, pg.eigenvalues(1) + pg.eigenvalues(2)));
  const double residual = rms_residual(fit.transform, e, g);
  const bool collinear = across <= 1e-9 * std::sqrt(pg.eigenvalues(0));
  if (!collinear && across > kMinAxisSpreadToResidual * residual) return fit;
  fit.transform = axis_alignment(ce, cg, pg.axis, method == Alignment::kSim3);
  fit.warning = fmt::format(
      "{} alignment: the ground-truth track is nearly straight ({:.3g} m RMS off its axis, "
      "against a fit residual of {:.3g} m RMS), so the rotation about the track's axis is "
      "unobservable; aligned the axis direction{} and the position only",
      yaml::enum_name(method), across, residual, method == Alignment::kSim3 ? ", the scale" : "");
  return fit;
}

}  // namespace driftlab::eval
