#include "sim/physics/vessel/vessel_model.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "core/error.hpp"

namespace driftlab::sim {
namespace {

constexpr double kRho = kWaterDensity_kg_m3;
constexpr double kG = kGravity_m_s2;

Vec3 skew_apply(const Vec3& a, const Vec3& b) { return a.cross(b); }

}  // namespace

VesselModel::VesselModel(const VesselOptions& options) : options_(options) {
  yaml::validate_or_throw(options_, "vessel");
  const auto& h = options_.hull;
  const double m = options_.mass_kg;
  const double draft = m / (kRho * h.length_m * h.beam_m);
  if (draft >= h.depth_m)
    throw UserError(
        fmt::format("vessel.mass_kg: got {} kg, expected a mass the {} x {} x {} m hull can float "
                    "(at most {:.1f} kg)",
                    m, h.length_m, h.beam_m, h.depth_m, kRho * h.length_m * h.beam_m * h.depth_m));
  const auto& r = options_.gyration_radii_m;
  inertia_ = Vec3(m * r[0] * r[0], m * r[1] * r[1], m * r[2] * r[2]);
  const auto& A = options_.added_mass;
  const double diag[6] = {
      m + A[0], m + A[1], m + A[2], inertia_.x() + A[3], inertia_.y() + A[4], inertia_.z() + A[5]};
  for (int i = 0; i < 6; ++i) {
    M_(i, i) = diag[i];
    M_inv_(i, i) = 1.0 / diag[i];
  }

  // Panels: bottom cells, side strips (port, starboard), end strips (bow, stern).
  const double L = h.length_m, B = h.beam_m, D = h.depth_m, keel = h.kg_m;
  const int na = h.panels_along, nc = h.panels_across;
  const Vec3 up(0, 0, -D);
  for (int i = 0; i < na; ++i) {
    const double x = -L / 2 + L * (i + 0.5) / na;
    for (int j = 0; j < nc; ++j) {
      const double y = -B / 2 + B * (j + 0.5) / nc;
      panels_.push_back(
          {Vec3(x, y, keel), Vec3::Zero(), Vec3(0, 0, 1), (L / na) * (B / nc), false});
    }
    panels_.push_back({Vec3(x, -B / 2, keel), up, Vec3(0, -1, 0), L / na, true});
    panels_.push_back({Vec3(x, B / 2, keel), up, Vec3(0, 1, 0), L / na, true});
  }
  for (int j = 0; j < nc; ++j) {
    const double y = -B / 2 + B * (j + 0.5) / nc;
    panels_.push_back({Vec3(L / 2, y, keel), up, Vec3(1, 0, 0), B / nc, true});
    panels_.push_back({Vec3(-L / 2, y, keel), up, Vec3(-1, 0, 0), B / nc, true});
  }
}

double VesselModel::design_draft_m() const {
  return options_.mass_kg / (kRho * options_.hull.length_m * options_.hull.beam_m);
}

double VesselModel::design_cg_z_m() const { return design_draft_m() - options_.hull.kg_m; }

double VesselModel::heave_stiffness() const {
  return kRho * kG * options_.hull.length_m * options_.hull.beam_m;
}

// Box hydrostatics: GM = KB + BM - KG with KB = T/2, BM = I_waterplane / volume.
double VesselModel::roll_stiffness() const {
  const auto& h = options_.hull;
  const double T = design_draft_m();
  const double volume = options_.mass_kg / kRho;
  const double gm = T / 2 + (h.length_m * std::pow(h.beam_m, 3) / 12.0) / volume - h.kg_m;
  return kRho * kG * volume * gm;
}

double VesselModel::pitch_stiffness() const {
  const auto& h = options_.hull;
  const double T = design_draft_m();
  const double volume = options_.mass_kg / kRho;
  const double gm = T / 2 + (h.beam_m * std::pow(h.length_m, 3) / 12.0) / volume - h.kg_m;
  return kRho * kG * volume * gm;
}

ForceBreakdown VesselModel::forces(const VesselState& s, const VesselInputs& in,
                                   const Environment& env, double t) const {
  ForceBreakdown f;
  const Mat3 R = s.q_W_B.toRotationMatrix();
  const Mat3 Rt = R.transpose();
  const double m = options_.mass_kg;

  f.gravity.head<3>() = Rt * Vec3(0, 0, m * kG);

  // Pressure over the hull: rho g z + wave dynamic pressure (linear theory),
  // integrated over the wetted part of each panel. Where the total pressure of
  // a point is negative the point is above the water.
  const WaveField* waves = env.waves && !env.waves->is_calm() ? env.waves : nullptr;
  auto pressure = [&](const Vec3& p_W) {
    double p = kRho * kG * p_W.z();
    if (waves) p += waves->dynamic_pressure(p_W, t);
    return p;
  };
  Vec3 F = Vec3::Zero(), Mo = Vec3::Zero();
  for (const Panel& pn : panels_) {
    const Vec3 b_W = s.p_W + R * pn.bottom;
    const double pb = pressure(b_W);
    if (!pn.is_strip) {
      if (pb <= 0) continue;
      const Vec3 force = -pb * pn.width * pn.normal;
      F += force;
      Mo += pn.bottom.cross(force);
      continue;
    }
    if (pb <= 0) continue;  // the strip's lowest point is dry: all of it is
    const double pt = pressure(b_W + R * pn.up);
    // Pressure varies linearly along the strip (exact in calm water); the
    // wetted length ends where it reaches zero.
    double wet_fraction, magnitude, centre_fraction;
    if (pt >= 0) {
      wet_fraction = 1.0;
      magnitude = 0.5 * (pb + pt);
      centre_fraction = (pb + 2 * pt) / (3 * (pb + pt));
    } else {
      wet_fraction = pb / (pb - pt);
      magnitude = 0.5 * pb * wet_fraction;
      centre_fraction = wet_fraction / 3.0;
    }
    const double length = pn.up.norm();
    const Vec3 force = -magnitude * length * pn.width * pn.normal;
    const Vec3 at = pn.bottom + centre_fraction * pn.up;
    F += force;
    Mo += at.cross(force);
  }
  f.pressure << F, Mo;

  // Velocity relative to the current. Wave orbital velocity is left out on
  // purpose: in linear seakeeping the waves excite the hull through pressure
  // (above), and damping acts on the body's own motion; damping against the
  // orbital velocity at a single point would drive heave with waves far
  // shorter than the hull, which average out over it.
  const Vec3 water_W =
      current_velocity(env.current, s.p_W.x(), s.p_W.y(), env.channel_half_width_m);
  const Vec3 vr = s.v_B - Rt * water_W;
  const Vec3& w = s.w_B;
  if (env.damping_enabled) {
    const auto& dl = options_.linear_damping;
    const auto& dq = options_.quadratic_damping;
    Vec6 nur;
    nur << vr, w;
    for (int i = 0; i < 6; ++i) f.damping[i] = -(dl[i] + dq[i] * std::abs(nur[i])) * nur[i];
  }

  // Coriolis-centripetal terms (Fossen Eq. 6.43 about the CG; Eq. 6.46 for the
  // added mass, diagonal here).
  const auto& A = options_.added_mass;
  const Vec3 Iw = inertia_.cwiseProduct(w);
  const Vec3 a(A[0] * vr.x(), A[1] * vr.y(), A[2] * vr.z());
  const Vec3 b(A[3] * w.x(), A[4] * w.y(), A[5] * w.z());
  f.coriolis.head<3>() = -(m * skew_apply(w, s.v_B) + skew_apply(w, a));
  f.coriolis.tail<3>() = -(skew_apply(w, Iw) + skew_apply(vr, a) + skew_apply(w, b));

  // Twin thrusters along body x at the keel.
  const auto& th = options_.thrusters;
  const Vec3 port(th.x_m, -th.lateral_offset_m, options_.hull.kg_m);
  const Vec3 stbd(th.x_m, th.lateral_offset_m, options_.hull.kg_m);
  const Vec3 fp(s.thrust_n[0], 0, 0), fs(s.thrust_n[1], 0, 0);
  f.thrust << fp + fs, port.cross(fp) + stbd.cross(fs);

  if (in.tow_active) {
    const Vec3 r = tow_point_B();
    const Vec3 a_W = s.p_W + R * r;
    const Vec3 carriage = in.tow_carriage_W + t * in.tow_carriage_velocity_W;
    const Vec3 d = carriage - a_W;
    const double dist = d.norm();
    const auto& tow = options_.tow;
    if (dist > tow.rope_length_m) {
      const Vec3 u = d / dist;
      const Vec3 va_W = R * (s.v_B + w.cross(r));
      const double rate = (in.tow_carriage_velocity_W - va_W).dot(u);
      const double tension =
          std::max(0.0, tow.stiffness_n_m * (dist - tow.rope_length_m) + tow.damping_n_s_m * rate);
      const Vec3 fb = Rt * (tension * u);
      f.tow << fb, r.cross(fb);
    }
  }
  return f;
}

VesselStateDot VesselModel::derivative(const VesselState& s, const VesselInputs& in,
                                       const Environment& env, double t,
                                       ForceBreakdown* breakdown) const {
  const ForceBreakdown f = forces(s, in, env, t);
  if (breakdown) *breakdown = f;
  VesselStateDot d;
  d.p_dot = s.q_W_B * s.v_B;
  const Quat omega(0, s.w_B.x(), s.w_B.y(), s.w_B.z());
  d.q_dot = 0.5 * (s.q_W_B * omega).coeffs();
  const Vec6 nu_dot = M_inv_ * f.total();
  d.v_dot = nu_dot.head<3>();
  d.w_dot = nu_dot.tail<3>();
  const auto& th = options_.thrusters;
  for (int i = 0; i < 2; ++i) {
    const double cmd =
        std::clamp(in.thrust_command_n[i], -th.reverse_fraction * th.max_thrust_n, th.max_thrust_n);
    d.thrust_dot[i] = (cmd - s.thrust_n[i]) / th.time_constant_s;
  }
  return d;
}

double VesselModel::calm_water_energy(const VesselState& s, int nu, int nv) const {
  Vec6 nu_vec;
  nu_vec << s.v_B, s.w_B;
  const double kinetic = 0.5 * nu_vec.dot(M_ * nu_vec);
  const double gravity = -options_.mass_kg * kG * s.p_W.z();
  // Hydrostatic potential rho g * integral of depth over the submerged volume,
  // by body-fixed columns: along a column the depth is linear, so each
  // column's integral is exact; the midpoint rule runs over the columns.
  const auto& h = options_.hull;
  const Mat3 R = s.q_W_B.toRotationMatrix();
  const double w_top = h.kg_m - h.depth_m, w_bot = h.kg_m;
  const double du = h.length_m / nu, dv = h.beam_m / nv;
  double integral = 0;
  for (int i = 0; i < nu; ++i) {
    const double u = -h.length_m / 2 + (i + 0.5) * du;
    for (int j = 0; j < nv; ++j) {
      const double v = -h.beam_m / 2 + (j + 0.5) * dv;
      const double z0 = s.p_W.z() + R(2, 0) * u + R(2, 1) * v;  // depth at w = 0
      const double c = R(2, 2);                                 // d depth / d w
      // Submerged where z0 + c w > 0, for w in [w_top, w_bot].
      double lo = w_top, hi = w_bot;
      if (std::abs(c) < 1e-15) {
        if (z0 <= 0) continue;
      } else if (c > 0) {
        lo = std::max(lo, -z0 / c);
      } else {
        hi = std::min(hi, -z0 / c);
      }
      if (hi <= lo) continue;
      integral += (z0 * (hi - lo) + 0.5 * c * (hi * hi - lo * lo)) * du * dv;
    }
  }
  return kinetic + gravity + kRho * kG * integral;
}

}  // namespace driftlab::sim
