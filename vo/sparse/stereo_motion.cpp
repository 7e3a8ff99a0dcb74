#include "vo/sparse/stereo_motion.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <Eigen/Cholesky>

namespace driftlab::vo::sparse {

namespace {

// pi^(l), pi^(r) of Eq. (2) for a point p = (X, Y, Z) already in the current left frame, and,
// if J is given, the rows d(pixel)/d(xi) for the left perturbation exp(xi) * T, xi = [rho; phi]:
// dp/dxi = [I, -hat(p)], so with du/dp = (a, 0, c) and dv/dp = (0, b, e):
//   du/dxi = (a, 0, c,  c Y,        a Z - c X, -a Y)
//   dv/dxi = (0, b, e, -b Z + e Y, -e X,        b X)
// Shared by project_stereo() (whose Jacobian the finite-difference test checks) and the
// Gauss-Newton loop, so the loop's Jacobian is the tested one.
inline void stereo_rows(double fx, double fy, double cx, double cy, double baseline, double X,
                        double Y, double Z, double* px, double (*J)[6]) {
  const double inv_z = 1.0 / Z;
  const double xr = X - baseline;  // the right camera sits at +B along x
  px[0] = fx * X * inv_z + cx;
  px[1] = fy * Y * inv_z + cy;
  px[2] = fx * xr * inv_z + cx;
  px[3] = px[1];
  if (J == nullptr) return;
  const double a = fx * inv_z, b = fy * inv_z;
  const double c = -fx * X * inv_z * inv_z, cr = -fx * xr * inv_z * inv_z;
  const double e = -fy * Y * inv_z * inv_z;
  const double ju[6] = {a, 0.0, c, c * Y, a * Z - c * X, -a * Y};
  const double jv[6] = {0.0, b, e, -b * Z + e * Y, -e * X, b * X};
  const double jr[6] = {a, 0.0, cr, cr * Y, a * Z - cr * X, -a * Y};
  for (int k = 0; k < 6; ++k) {
    J[0][k] = ju[k];
    J[1][k] = jv[k];
    J[2][k] = jr[k];
    J[3][k] = jv[k];
  }
}

}  // namespace

bool project_stereo(const StereoRig& rig, const Mat3& R_curr_prev, const Vec3& t_curr_prev,
                    const Vec3& p_prev, Vec4* pixels, Mat46* J) {
  const Vec3 p = R_curr_prev * p_prev + t_curr_prev;
  if (!(p.z() > kMinProjectionDepthM)) return false;
  double px[4];
  double rows[4][6];
  stereo_rows(rig.camera.fx, rig.camera.fy, rig.camera.cx, rig.camera.cy, rig.baseline_m, p.x(),
              p.y(), p.z(), px, J != nullptr ? rows : nullptr);
  *pixels << px[0], px[1], px[2], px[3];
  if (J != nullptr)
    for (int i = 0; i < 4; ++i)
      for (int k = 0; k < 6; ++k) (*J)(i, k) = rows[i][k];
  return true;
}

std::pair<double, double> reprojection_errors(const StereoRig& rig, const Mat3& R, const Vec3& t,
                                              const StereoPointMatch& m) {
  Vec4 px;
  if (!project_stereo(rig, R, t, m.p_prev, &px, nullptr)) {
    const double inf = std::numeric_limits<double>::infinity();
    return {inf, inf};
  }
  return {std::hypot(m.u_l - px(0), m.v_l - px(1)), std::hypot(m.u_r - px(2), m.v_r - px(3))};
}

StereoMotionEstimator::StereoMotionEstimator(const StereoRig& rig, const SparseVoOptions& options)
    : rig_(rig), options_(options) {}

bool StereoMotionEstimator::gauss_newton(std::span<const StereoPointMatch> matches,
                                         std::span<const int> indices, SE3* T_curr_prev) const {
  // Eq. (2), Kriechbaumer 2015: e = sum_i |p_i^(l) - pi^(l)(P_i; R, T)|^2
  //                                     + |p_i^(r) - pi^(r)(P_i; R, T)|^2,
  // linearised about T, solved for the left-multiplied twist xi, T <- exp(xi) T.
  const double fx = rig_.camera.fx, fy = rig_.camera.fy, cx = rig_.camera.cx, cy = rig_.camera.cy,
               B = rig_.baseline_m;
  SE3 T = *T_curr_prev;
  for (int it = 0; it < options_.gauss_newton_max_iterations; ++it) {
    const Mat3 R = T.rotation();
    const Vec3 t = T.translation();
    double H[6][6] = {};  // upper triangle of J^T J
    double g[6] = {};     // J^T r
    int used = 0;
    for (const int i : indices) {
      const StereoPointMatch& m = matches[static_cast<std::size_t>(i)];
      const Vec3 p = R * m.p_prev + t;
      if (!(p.z() > kMinProjectionDepthM)) continue;
      double px[4];
      double J[4][6];
      stereo_rows(fx, fy, cx, cy, B, p.x(), p.y(), p.z(), px, J);
      // Rows 1 and 3 (v in the left and the right image) are the same row: one outer product
      // weighted 2, with the residuals summed.
      const double ru = m.u_l - px[0], rr = m.u_r - px[2];
      const double rv = (m.v_l - px[1]) + (m.v_r - px[3]);
      const double* ju = J[0];
      const double* jv = J[1];
      const double* jr = J[2];
      for (int a = 0; a < 6; ++a) {
        g[a] += ju[a] * ru + jv[a] * rv + jr[a] * rr;
        const double ua = ju[a], va2 = 2.0 * jv[a], ra = jr[a];
        for (int b = a; b < 6; ++b) H[a][b] += ua * ju[b] + va2 * jv[b] + ra * jr[b];
      }
      ++used;
    }
    if (3 * used < 6) return false;  // 6 unknowns need at least 2 points' worth of rows
    Eigen::Matrix<double, 6, 6> Hm;
    Vec6 gm;
    for (int a = 0; a < 6; ++a) {
      gm(a) = g[a];
      for (int b = a; b < 6; ++b) Hm(a, b) = Hm(b, a) = H[a][b];
    }
    const Eigen::LDLT<Eigen::Matrix<double, 6, 6>> ldlt(Hm);
    if (ldlt.info() != Eigen::Success || !ldlt.isPositive()) return false;
    // Degenerate geometry (e.g. three collinear points) leaves a direction unconstrained.
    const auto d = ldlt.vectorD();
    if (!(d.minCoeff() > 1e-12 * d.maxCoeff())) return false;
    const Vec6 xi = ldlt.solve(gm);
    if (!xi.allFinite()) return false;
    T = SE3::exp(xi) * T;
    if (xi.norm() < options_.gauss_newton_step_tolerance) break;
  }
  if (!T.translation().allFinite() || !T.quaternion().coeffs().allFinite()) return false;
  *T_curr_prev = T;
  return true;
}

void StereoMotionEstimator::load(std::span<const StereoPointMatch> matches) {
  const std::size_t n = matches.size();
  for (auto* v : {&X_, &Y_, &Z_, &ul_, &vl_, &ur_, &vr_}) v->resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    X_[i] = matches[i].p_prev.x();
    Y_[i] = matches[i].p_prev.y();
    Z_[i] = matches[i].p_prev.z();
    ul_[i] = matches[i].u_l;
    vl_[i] = matches[i].v_l;
    ur_[i] = matches[i].u_r;
    vr_[i] = matches[i].v_r;
  }
}

// The hot loop of RANSAC (iterations x matches projections), over the matches as structure of
// arrays (X, Y, Z, u_l, v_l, u_r, v_r): no Eigen temporaries, squared distances.
class StereoMotionEstimator::SquaredErrors {
 public:
  SquaredErrors(const StereoRig& rig, const SE3& T, const std::array<const double*, 7>& matches)
      : R_(T.rotation()), t_(T.translation()), rig_(rig), m_(matches) {}

  // Match i's squared reprojection errors in the left and the right image; false when the
  // point is not in front.
  bool operator()(int i, double* left2, double* right2) const {
    const auto& [X, Y, Z, ul, vl, ur, vr] = m_;
    const double x = R_(0, 0) * X[i] + R_(0, 1) * Y[i] + R_(0, 2) * Z[i] + t_.x();
    const double y = R_(1, 0) * X[i] + R_(1, 1) * Y[i] + R_(1, 2) * Z[i] + t_.y();
    const double z = R_(2, 0) * X[i] + R_(2, 1) * Y[i] + R_(2, 2) * Z[i] + t_.z();
    if (!(z > kMinProjectionDepthM)) return false;
    const PinholeCamera& c = rig_.camera;
    const double inv_z = 1.0 / z;
    const double du = ul[i] - (c.fx * x * inv_z + c.cx);
    const double v = c.fy * y * inv_z + c.cy;
    const double dvl = vl[i] - v;
    const double dur = ur[i] - (c.fx * (x - rig_.baseline_m) * inv_z + c.cx);
    const double dvr = vr[i] - v;
    *left2 = du * du + dvl * dvl;
    *right2 = dur * dur + dvr * dvr;
    return true;
  }

 private:
  Mat3 R_;
  Vec3 t_;
  const StereoRig& rig_;
  std::array<const double*, 7> m_;
};

StereoMotionEstimator::SquaredErrors StereoMotionEstimator::squared_errors(
    const SE3& T_curr_prev) const {
  return SquaredErrors(
      rig_, T_curr_prev,
      {X_.data(), Y_.data(), Z_.data(), ul_.data(), vl_.data(), ur_.data(), vr_.data()});
}

int StereoMotionEstimator::collect_inliers(const SE3& T_curr_prev, int to_beat,
                                           std::vector<int>* out) const {
  // Gives up, returning -1, once even all remaining matches could not make more than to_beat
  // inliers.
  out->clear();
  const double thr2 = options_.inlier_threshold_px * options_.inlier_threshold_px;
  const SquaredErrors errors = squared_errors(T_curr_prev);
  const int n = static_cast<int>(X_.size());
  double left2 = 0.0, right2 = 0.0;
  for (int i = 0; i < n; ++i) {
    if (static_cast<int>(out->size()) + (n - i) <= to_beat) return -1;
    if (errors(i, &left2, &right2) && left2 <= thr2 && right2 <= thr2) out->push_back(i);
  }
  return static_cast<int>(out->size());
}

double StereoMotionEstimator::msac_cost(const SE3& T_curr_prev, double to_beat) const {
  // MSAC's cost (Torr and Zisserman 2000, Eq. 10): sum_i min(e_i^2, tau^2), e_i the larger of
  // match i's left and right reprojection errors (the inlier test bounds both) and tau the
  // inlier threshold. Gives up, returning infinity, once the sum reaches to_beat.
  const double thr2 = options_.inlier_threshold_px * options_.inlier_threshold_px;
  const SquaredErrors errors = squared_errors(T_curr_prev);
  const int n = static_cast<int>(X_.size());
  double cost = 0.0, left2 = 0.0, right2 = 0.0;
  for (int i = 0; i < n && cost < to_beat; ++i)
    cost += errors(i, &left2, &right2) ? std::min(std::max(left2, right2), thr2) : thr2;
  return cost < to_beat ? cost : std::numeric_limits<double>::infinity();
}

double StereoMotionEstimator::msac_cost(std::span<const StereoPointMatch> matches,
                                        const SE3& T_curr_prev) {
  load(matches);
  return msac_cost(T_curr_prev, std::numeric_limits<double>::infinity());
}

void StereoMotionEstimator::inliers(std::span<const StereoPointMatch> matches,
                                    const SE3& T_curr_prev, std::vector<int>* out) {
  load(matches);
  collect_inliers(T_curr_prev, -1, out);
}

StereoMotionEstimator::Result StereoMotionEstimator::estimate(
    std::span<const StereoPointMatch> matches, Rng* rng, const SE3& initial) {
  Result result;
  const int n = static_cast<int>(matches.size());
  const int s = options_.ransac_sample_size;
  if (n < s || n < options_.min_inliers) {
    result.failure = "too few matches (" + std::to_string(n) + ")";
    return result;
  }
  load(matches);
  best_.clear();
  SE3 best_T;
  const bool msac = options_.ransac_score == RansacScore::kMsac;
  double best_cost = std::numeric_limits<double>::infinity();
  bool have_best = false;
  for (int it = 0; it < options_.ransac_iterations; ++it) {
    sample_.clear();
    while (static_cast<int>(sample_.size()) < s) {
      const int k = static_cast<int>(rng->uniform_int(static_cast<std::uint64_t>(n)));
      if (std::find(sample_.begin(), sample_.end(), k) == sample_.end()) sample_.push_back(k);
    }
    SE3 T = initial;
    if (!gauss_newton(matches, sample_, &T)) continue;
    // Strictly better wins, so the first of equally good hypotheses is kept.
    if (msac) {
      const double cost = msac_cost(T, best_cost);
      if (cost < best_cost) {
        best_cost = cost;
        best_T = T;
        have_best = true;
      }
    } else if (collect_inliers(T, static_cast<int>(best_.size()), &candidate_) >
               static_cast<int>(best_.size())) {
      best_.swap(candidate_);
      best_T = T;
    }
  }
  if (msac && have_best) collect_inliers(best_T, -1, &best_);
  if (static_cast<int>(best_.size()) < options_.min_inliers) {
    result.failure =
        "too few inliers (" + std::to_string(best_.size()) + " of " + std::to_string(n) + ")";
    return result;
  }
  if (options_.final_refinement) {
    // The river paper's final optimisation over the winner's inliers, repeated while it
    // changes the inlier set (a refined motion usually admits a few more), at most 3 times.
    for (int round = 0; round < 3; ++round) {
      SE3 T = best_T;
      if (!gauss_newton(matches, best_, &T)) break;
      best_T = T;
      collect_inliers(T, -1, &refined_);
      if (refined_ == best_ || static_cast<int>(refined_.size()) < options_.min_inliers) break;
      best_.swap(refined_);
    }
  }
  result.ok = true;
  result.T_curr_prev = best_T;
  result.inliers = &best_;
  return result;
}

}  // namespace driftlab::vo::sparse
