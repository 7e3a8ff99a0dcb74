#include "eval/paper_attitude.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <fmt/format.h>

#include "core/error.hpp"

namespace driftlab::eval {

namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
constexpr std::size_t kNone = static_cast<std::size_t>(-1);

// Index of the reference sample nearest to t, or npos when none is within the tolerance.
std::size_t nearest(const std::vector<TimeNs>& times, TimeNs t, TimeNs tolerance_ns) {
  const auto it = std::lower_bound(times.begin(), times.end(), t);
  std::size_t best = kNone;
  TimeNs gap = tolerance_ns;
  for (auto c : {it, it == times.begin() ? it : std::prev(it)}) {
    if (c == times.end()) continue;
    const TimeNs d = *c > t ? *c - t : t - *c;
    if (d <= gap) {
      gap = d;
      best = static_cast<std::size_t>(c - times.begin());
    }
  }
  return best;
}

}  // namespace

AttitudeReference read_attitude_reference(const std::string& path) {
  const FrameTable table = read_frame_table(path);
  const char* names[3] = {"roll_deg", "pitch_deg", "yaw_deg"};
  const std::vector<double>* cols[3];
  for (int i = 0; i < 3; ++i) {
    cols[i] = table.column(names[i]);
    if (cols[i] == nullptr)
      throw UserError(
          fmt::format("{}: no column '{}', expected roll_deg, pitch_deg and yaw_deg "
                      "(an AHRS's angles, as a run's ahrs.csv)",
                      path, names[i]));
  }
  AttitudeReference out;
  out.t_ns = table.t_ns;
  for (std::size_t r = 0; r < table.t_ns.size(); ++r) {
    double v[3];
    for (int i = 0; i < 3; ++i) {
      v[i] = (*cols[i])[r];
      if (!std::isfinite(v[i]))
        throw UserError(
            fmt::format("{}: data row {} (t_ns {}): {} is missing or not finite, "
                        "expected an angle in degrees",
                        path, r + 1, table.t_ns[r], names[i]));
    }
    out.euler.push_back({deg2rad(v[0]), deg2rad(v[1]), deg2rad(v[2])});
  }
  return out;
}

PaperAttitude paper_attitude(const std::vector<TimeNs>& t_ns, const std::vector<SE3>& T_W_C_est,
                             const std::vector<Section>& sections,
                             const AttitudeReference& reference, TimeNs tolerance_ns) {
  DRIFTLAB_DEMAND(t_ns.size() == T_W_C_est.size());
  DRIFTLAB_DEMAND(reference.t_ns.size() == reference.euler.size());
  PaperAttitude out;
  const std::size_t n = t_ns.size();
  // eps(t) = n_IMU - n_VO per angle, Eq. (11); NaN where no reference sample is near.
  std::vector<Vec3> eps(n, Vec3::Constant(kNaN));
  const SE3 T_C_F(R_optical_frd(), Vec3::Zero());
  const SE3 E0_inv = n > 0 ? (T_W_C_est.front() * T_C_F).inverse() : SE3();
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t r = nearest(reference.t_ns, t_ns[k], tolerance_ns);
    if (r == kNone) continue;
    const EulerZYX vo = euler_zyx_from_quat((E0_inv * T_W_C_est[k] * T_C_F).quaternion());
    const EulerZYX& imu = reference.euler[r];
    eps[k] = Vec3(wrap_angle_rad(imu.roll_rad - vo.roll_rad),
                  wrap_angle_rad(imu.pitch_rad - vo.pitch_rad),
                  wrap_angle_rad(imu.yaw_rad - vo.yaw_rad));
    ++out.pairs;
  }
  // Along the track: the excursion from the first paired value.
  Vec3 start = Vec3::Constant(kNaN), worst = Vec3::Zero();
  for (const Vec3& e : eps) {
    if (!e.allFinite()) continue;
    if (!start.allFinite()) start = e;
    for (int i = 0; i < 3; ++i)
      worst[i] = std::max(worst[i], std::abs(wrap_angle_rad(e[i] - start[i])));
  }
  out.max_abs_rad = {worst[0], worst[1], worst[2]};
  // Per section: the change of eps from its start to its end, per metre, in degrees.
  std::vector<double> roll, pitch, yaw;
  for (const Section& s : sections) {
    DRIFTLAB_DEMAND(s.last < n);
    const Vec3& a = eps[s.first];
    const Vec3& b = eps[s.last];
    if (!a.allFinite() || !b.allFinite()) continue;
    roll.push_back(s.per_m(rad2deg(wrap_angle_rad(b[0] - a[0]))));
    pitch.push_back(s.per_m(rad2deg(wrap_angle_rad(b[1] - a[1]))));
    yaw.push_back(s.per_m(rad2deg(wrap_angle_rad(b[2] - a[2]))));
  }
  out.roll_deg_per_m = summarize(roll);
  out.pitch_deg_per_m = summarize(pitch);
  out.yaw_deg_per_m = summarize(yaw);
  return out;
}

}  // namespace driftlab::eval
