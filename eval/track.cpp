#include "eval/track.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "core/error.hpp"
#include "core/rotation.hpp"

namespace driftlab::eval {

double path_length_m(const std::vector<SE3>& poses) {
  double s = 0;
  for (std::size_t i = 1; i < poses.size(); ++i)
    s += (poses[i].translation() - poses[i - 1].translation()).norm();
  return s;
}

std::vector<std::size_t> length_sample_indices(const std::vector<SE3>& gt, double spacing_m) {
  std::vector<std::size_t> at;
  if (gt.empty()) return at;
  at.push_back(0);
  double travelled = 0;
  for (std::size_t i = 1; i < gt.size(); ++i) {
    travelled += (gt[i].translation() - gt[i - 1].translation()).norm();
    if (travelled >= spacing_m || i + 1 == gt.size()) {
      at.push_back(i);
      travelled = 0;
    }
  }
  return at;
}

double path_length_m(const std::vector<SE3>& poses, const std::vector<std::size_t>& indices) {
  double s = 0;
  for (std::size_t k = 1; k < indices.size(); ++k)
    s += (poses[indices[k]].translation() - poses[indices[k - 1]].translation()).norm();
  return s;
}

TrackErrors track_errors(const std::vector<SE3>& gt, const std::vector<SE3>& est,
                         double length_sample_m) {
  DRIFTLAB_DEMAND(gt.size() == est.size());
  TrackErrors r;
  r.n = gt.size();
  if (r.n == 0) return r;
  std::vector<double> e2d;
  for (std::size_t i = 0; i < r.n; ++i) {
    const Vec3 d = gt[i].translation() - est[i].translation();
    r.err_3d_m.push_back(d.norm());
    e2d.push_back(d.head<2>().norm());
  }
  const Summary s3 = summarize(r.err_3d_m);
  const Summary s2 = summarize(e2d);
  r.rmse_3d_m = s3.rmse;  // Eq. (14)
  r.max_3d_m = s3.max;
  r.rmse_2d_m = s2.rmse;
  r.max_2d_m = s2.max;
  const std::vector<std::size_t> at = length_sample_indices(gt, length_sample_m);
  r.length_gt_m = path_length_m(gt, at);
  r.length_est_m = path_length_m(est, at);
  if (r.length_gt_m > 0) {
    const double pct = 100.0 / r.length_gt_m;
    r.rmse_3d_pct = r.rmse_3d_m * pct;
    r.max_3d_pct = r.max_3d_m * pct;
    r.rmse_2d_pct = r.rmse_2d_m * pct;
    r.max_2d_pct = r.max_2d_m * pct;
    r.length_error_pct = (r.length_est_m - r.length_gt_m) * pct;
  }
  return r;
}

PlanarStates planar_states(const std::vector<TimeNs>& t_ns, const std::vector<SE3>& T_W_X,
                           bool x_is_camera_optical) {
  DRIFTLAB_DEMAND(t_ns.size() == T_W_X.size());
  const std::size_t n = t_ns.size();
  PlanarStates s;
  const Vec3 forward = x_is_camera_optical ? Vec3::UnitZ() : Vec3::UnitX();
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 p = T_W_X[i].translation();
    const Vec3 f = T_W_X[i].quaternion() * forward;
    s.north_m.push_back(p.x());
    s.east_m.push_back(p.y());
    s.heading_rad.push_back(std::atan2(f.y(), f.x()));
  }
  for (std::size_t i = 0; i < n; ++i) {
    double vn = 0, ve = 0;
    if (n >= 2) {
      const std::size_t a = i == 0 ? 0 : i - 1;
      const std::size_t b = i + 1 == n ? n - 1 : i + 1;
      const double dt = ns_to_seconds(t_ns[b] - t_ns[a]);
      DRIFTLAB_DEMAND(dt > 0);
      vn = (s.north_m[b] - s.north_m[a]) / dt;
      ve = (s.east_m[b] - s.east_m[a]) / dt;
    }
    const double c = std::cos(s.heading_rad[i]), sn = std::sin(s.heading_rad[i]);
    s.surge_m_s.push_back(c * vn + sn * ve);
    s.sway_m_s.push_back(-sn * vn + c * ve);
  }
  return s;
}

BasinTable basin_table(const PlanarStates& ref, const PlanarStates& est) {
  DRIFTLAB_DEMAND(ref.north_m.size() == est.north_m.size());
  auto errors = [](const std::vector<double>& r, const std::vector<double>& e, bool angle) {
    std::vector<double> d;
    for (std::size_t i = 0; i < r.size(); ++i)
      d.push_back(angle ? rad2deg(wrap_angle_rad(e[i] - r[i])) : e[i] - r[i]);
    return summarize(d);
  };
  return {errors(ref.north_m, est.north_m, false), errors(ref.east_m, est.east_m, false),
          errors(ref.surge_m_s, est.surge_m_s, false), errors(ref.sway_m_s, est.sway_m_s, false),
          errors(ref.heading_rad, est.heading_rad, true)};
}

BasinTable basin_table(const PlanarReference& ref, const std::vector<TimeNs>& t,
                       const PlanarStates& est, TimeNs tolerance_ns, std::size_t* pairs) {
  DRIFTLAB_DEMAND(t.size() == est.north_m.size());
  std::array<std::vector<double>, 5> d;
  std::size_t paired = 0;
  for (std::size_t i = 0; i < ref.t_ns.size(); ++i) {
    const auto it = std::lower_bound(t.begin(), t.end(), ref.t_ns[i]);
    std::size_t j = static_cast<std::size_t>(it - t.begin());
    if (j > 0 && (j == t.size() || ref.t_ns[i] - t[j - 1] < t[j] - ref.t_ns[i])) --j;
    if (j >= t.size() || std::abs(t[j] - ref.t_ns[i]) > tolerance_ns) continue;
    ++paired;
    const std::array<std::pair<double, double>, 5> q{
        {{ref.states.north_m[i], est.north_m[j]},
         {ref.states.east_m[i], est.east_m[j]},
         {ref.states.surge_m_s[i], est.surge_m_s[j]},
         {ref.states.sway_m_s[i], est.sway_m_s[j]},
         {ref.states.heading_rad[i], est.heading_rad[j]}}};
    for (std::size_t k = 0; k < 5; ++k) {
      const auto [r, e] = q[k];
      if (!std::isfinite(r)) continue;
      d[k].push_back(k == 4 ? rad2deg(wrap_angle_rad(e - r)) : e - r);
    }
  }
  if (pairs) *pairs = paired;
  return {summarize(d[0]), summarize(d[1]), summarize(d[2]), summarize(d[3]), summarize(d[4])};
}

}  // namespace driftlab::eval
