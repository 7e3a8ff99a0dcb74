#include "fusion/eskf.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include <fmt/format.h>
#include <Eigen/Dense>

#include "core/error.hpp"
#include "core/rotation.hpp"

namespace driftlab::fusion {

using namespace eskf;

namespace {

bool finite(const Quat& q) { return q.coeffs().allFinite() && q.norm() > 0.0; }

bool finite(const EskfState& s) {
  return finite(s.q_W_I) && s.p_W_m.allFinite() && s.v_W_m_s.allFinite() &&
         s.accel_bias_m_s2.allFinite() && s.gyro_bias_rad_s.allFinite();
}

std::string matrix_text(const Mat3& M) {
  return fmt::format("[[{}, {}, {}], [{}, {}, {}], [{}, {}, {}]]", M(0, 0), M(0, 1), M(0, 2),
                     M(1, 0), M(1, 1), M(1, 2), M(2, 0), M(2, 1), M(2, 2));
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Models (detail), each with its Jacobian; tests/fusion/eskf_test.cpp checks every one by finite
// differences.

namespace detail {

EskfState propagate_nominal(const EskfState& s, const ImuInput& a, const ImuInput& b, double h,
                            double gravity_m_s2, Mat15* F) {
  // Sola Section 5.4.1 (nominal kinematics) integrated with the rate averaged over the interval and
  // the trapezoidal rule on the world-frame acceleration: second order in h, where Eq. (260)'s
  // Euler steps are first order.
  const Vec3 w = 0.5 * (a.gyro_rad_s + b.gyro_rad_s) - s.gyro_bias_rad_s;
  const Vec3 phi = w * h;
  const Quat dq = so3_exp(phi);
  const Mat3 R0 = s.q_W_I.toRotationMatrix();
  const Mat3 Gamma = dq.toRotationMatrix();
  const Mat3 R1 = R0 * Gamma;
  const Vec3 f0 = a.accel_m_s2 - s.accel_bias_m_s2;
  const Vec3 f1 = b.accel_m_s2 - s.accel_bias_m_s2;
  const Vec3 acc = 0.5 * (R0 * f0 + R1 * f1) + Vec3(0.0, 0.0, gravity_m_s2);
  EskfState o = s;
  o.q_W_I = (s.q_W_I * dq).normalized();
  o.v_W_m_s = s.v_W_m_s + acc * h;
  o.p_W_m = s.p_W_m + s.v_W_m_s * h + (0.5 * h * h) * acc;
  if (F != nullptr) {
    // Sola Section 5.4.3's F_x, exact for this map: with R = R^ Exp(dtheta) and bg = bg^ + dbg,
    // R1 = R^1 Exp(Gamma^T dtheta - J_r(phi) h dbg), and acc moves with both rotations and ba.
    const Mat3 I = Mat3::Identity();
    const Mat3 Jr = so3_left_jacobian(-phi);  // right Jacobian J_r(phi) = J_l(-phi)
    const Mat3 dacc_dtheta = -0.5 * (R0 * hat(f0) + R1 * hat(f1) * Gamma.transpose());
    const Mat3 dacc_dbg = (0.5 * h) * R1 * hat(f1) * Jr;
    const Mat3 dacc_dba = -0.5 * (R0 + R1);
    F->setIdentity();
    const double hh = 0.5 * h * h;
    F->block<3, 3>(kP, kV) = h * I;
    F->block<3, 3>(kP, kTheta) = hh * dacc_dtheta;
    F->block<3, 3>(kP, kBa) = hh * dacc_dba;
    F->block<3, 3>(kP, kBg) = hh * dacc_dbg;
    F->block<3, 3>(kV, kTheta) = h * dacc_dtheta;
    F->block<3, 3>(kV, kBa) = h * dacc_dba;
    F->block<3, 3>(kV, kBg) = h * dacc_dbg;
    F->block<3, 3>(kTheta, kTheta) = Gamma.transpose();
    F->block<3, 3>(kTheta, kBg) = -h * Jr;
  }
  return o;
}

EskfState boxplus(const EskfState& s, const Vec15& dx) {
  EskfState o = s;
  o.p_W_m += dx.segment<3>(kP);
  o.v_W_m_s += dx.segment<3>(kV);
  o.q_W_I = (s.q_W_I * so3_exp(dx.segment<3>(kTheta))).normalized();
  o.accel_bias_m_s2 += dx.segment<3>(kBa);
  o.gyro_bias_rad_s += dx.segment<3>(kBg);
  return o;
}

SE3 predict_vo(const Quat& q_c, const Vec3& p_c, const Quat& q, const Vec3& p, const SE3& T_I_C,
               Eigen::Matrix<double, 6, 21>* H) {
  // T_Cprev_Ccurr = T_I_C^-1 (T_W_Iprev^-1 T_W_Icurr) T_I_C.
  const Mat3 Rc_T = q_c.toRotationMatrix().transpose();
  const Mat3 R_ic = T_I_C.rotation();
  const Vec3& p_ic = T_I_C.translation();
  const Quat q_rel = q_c.conjugate() * q;
  const Mat3 R_rel = q_rel.toRotationMatrix();
  const Vec3 p_rel = Rc_T * (p - p_c);
  const Quat q_cc = T_I_C.quaternion().conjugate() * q_rel * T_I_C.quaternion();
  const Vec3 p_cc = R_ic.transpose() * (R_rel * p_ic + p_rel - p_ic);
  if (H != nullptr) {
    // With phi = dtheta - R_rel^T dtheta_c the relative rotation is R_rel Exp(phi), and
    // p_rel moves by Rc^T (dp - dp_c) + [p_rel]x dtheta_c.
    const Mat3 A = R_ic.transpose();
    H->setZero();
    H->block<3, 3>(0, kP) = A * Rc_T;
    H->block<3, 3>(0, kTheta) = -A * R_rel * hat(p_ic);
    H->block<3, 3>(0, kCloneP) = -A * Rc_T;
    H->block<3, 3>(0, kCloneTheta) = A * (R_rel * hat(p_ic) * R_rel.transpose() + hat(p_rel));
    H->block<3, 3>(3, kTheta) = A;
    H->block<3, 3>(3, kCloneTheta) = -A * R_rel.transpose();
  }
  return SE3(q_cc, p_cc);
}

Vec3 predict_gps(const Quat& q, const Vec3& p, const Vec3& p_I_antenna,
                 Eigen::Matrix<double, 3, 15>* H) {
  const Mat3 R = q.toRotationMatrix();
  if (H != nullptr) {
    H->setZero();
    H->block<3, 3>(0, kP) = Mat3::Identity();
    H->block<3, 3>(0, kTheta) = -R * hat(p_I_antenna);
  }
  return p + R * p_I_antenna;
}

double predict_heading(const Quat& q, const Mat3& R_I_M, Eigen::Matrix<double, 1, 15>* H) {
  // Heading = ZYX yaw = atan2(R10, R00) of R_W_M = R_W_I R_I_M; a local rotation phi of R_W_M
  // (phi = R_I_M^T dtheta) changes column 0 by R [phi]x e_x = R (0, phi_z, -phi_y).
  const Mat3 R = q.toRotationMatrix() * R_I_M;
  if (H != nullptr) {
    const double d = R(0, 0) * R(0, 0) + R(1, 0) * R(1, 0);
    Eigen::RowVector3d h_phi(0.0, (R(1, 0) * R(0, 2) - R(0, 0) * R(1, 2)) / d,
                             (R(0, 0) * R(1, 1) - R(1, 0) * R(0, 1)) / d);
    H->setZero();
    H->block<1, 3>(0, kTheta) = h_phi * R_I_M.transpose();
  }
  return std::atan2(R(1, 0), R(0, 0));
}

}  // namespace detail

// ---------------------------------------------------------------------------------------------

Vec15 eskf_error(const EskfState& estimate, const EskfState& truth) {
  Vec15 e;
  e.segment<3>(kP) = truth.p_W_m - estimate.p_W_m;
  e.segment<3>(kV) = truth.v_W_m_s - estimate.v_W_m_s;
  e.segment<3>(kTheta) = so3_log(estimate.q_W_I.conjugate() * truth.q_W_I);
  e.segment<3>(kBa) = truth.accel_bias_m_s2 - estimate.accel_bias_m_s2;
  e.segment<3>(kBg) = truth.gyro_bias_rad_s - estimate.gyro_bias_rad_s;
  return e;
}

Quat attitude_from_gravity_and_heading(const Vec3& f_I_m_s2, double heading_rad,
                                       const Mat3& R_I_M) {
  const Vec3& f = f_I_m_s2;
  const double roll = std::atan2(-f.y(), -f.z());
  const double pitch = std::atan2(f.x(), std::hypot(f.y(), f.z()));
  // A turn about world z adds to the azimuth of the compass frame's x axis, so the IMU's yaw is
  // the heading minus the azimuth that roll, pitch and the mount alone give it.
  const Mat3 A = quat_from_euler_zyx({roll, pitch, 0.0}).toRotationMatrix() * R_I_M;
  const double yaw = heading_rad - std::atan2(A(1, 0), A(0, 0));
  return quat_from_euler_zyx({roll, pitch, wrap_angle_rad(yaw)});
}

std::string EskfStats::brief() const {
  return fmt::format(
      "imu {}, vo {} fused / {} skipped / {} gated, gps {} fused / {} gated, heading {} fused / "
      "{} gated, guards {}",
      imu_samples, vo_fused, vo_skipped, vo_gated, gps_fused, gps_gated, heading_fused,
      heading_gated, nonfinite_guards);
}

// ---------------------------------------------------------------------------------------------

Eskf::Eskf(const Options& options, const EskfExtrinsics& extrinsics, const EskfState& initial)
    : options_(options), extrinsics_(extrinsics), state_(initial) {
  yaml::validate_or_throw(options_, "Eskf");
  for (const auto& [name, value] :
       {std::pair{"gyro_noise_density_rad_s_sqrt_hz", options_.gyro_noise_density_rad_s_sqrt_hz},
        std::pair{"gyro_random_walk_rad_s2_sqrt_hz", options_.gyro_random_walk_rad_s2_sqrt_hz},
        std::pair{"accel_noise_density_m_s2_sqrt_hz", options_.accel_noise_density_m_s2_sqrt_hz},
        std::pair{"accel_random_walk_m_s3_sqrt_hz", options_.accel_random_walk_m_s3_sqrt_hz},
        std::pair{"compass_noise_rad", options_.compass_noise_rad}})
    if (!value)
      throw UserError(fmt::format(
          "Eskf: {}: got null, expected a number (the pipeline fills null from the sensors)",
          name));
  if (!finite(state_)) throw UserError("Eskf: the initial state must be finite and q non-zero");
  if (!vo::detail::is_finite(extrinsics_.T_I_C) || !extrinsics_.p_I_antenna_m.allFinite() ||
      !extrinsics_.R_I_M.allFinite() ||
      (extrinsics_.R_I_M.transpose() * extrinsics_.R_I_M - Mat3::Identity()).norm() > 1e-6 ||
      extrinsics_.R_I_M.determinant() < 0.0) {
    throw UserError(
        "Eskf: the extrinsics must be finite and R_I_M a rotation matrix, got R_I_M = " +
        matrix_text(extrinsics_.R_I_M));
  }
  state_.q_W_I.normalize();
  const auto sq = [](double x) { return x * x; };
  const double rp = sq(options_.initial_roll_pitch_sd_rad);
  Vec21 d = Vec21::Zero();
  d.segment<3>(kP).setConstant(sq(options_.initial_position_sd_m));
  d.segment<3>(kV).setConstant(sq(options_.initial_velocity_sd_m_s));
  d.segment<3>(kTheta) << rp, rp, sq(options_.initial_yaw_sd_rad);
  d.segment<3>(kBa).setConstant(sq(options_.initial_accel_bias_sd_m_s2));
  d.segment<3>(kBg).setConstant(sq(options_.initial_gyro_bias_sd_rad_s));
  P_ = d.asDiagonal();
  for (int i = 0; i < 3; ++i) {
    vo_R_(i, i) = sq(options_.vo_translation_noise_m[static_cast<std::size_t>(i)]);
    vo_R_(i + 3, i + 3) = sq(options_.vo_rotation_noise_rad[static_cast<std::size_t>(i)]);
  }
}

void Eskf::require_time(TimeNs t_ns, const char* who) const {
  if (t_ns < state_.t_ns) {
    throw UserError(
        fmt::format("Eskf::{}: measurements must come in time order: got t = {} s after t = {} s",
                    who, format_seconds(t_ns), format_seconds(state_.t_ns)));
  }
}

void Eskf::propagate_piece(const Input& a, const Input& b) {
  const double h = ns_to_seconds(b.t_ns - state_.t_ns);
  Mat15 F;
  EskfState next = detail::propagate_nominal(state_, {a.gyro, a.accel}, {b.gyro, b.accel}, h,
                                             options_.gravity_m_s2, &F);
  next.t_ns = b.t_ns;
  // Sola Section 5.4.3's Q_i: white noise on velocity and attitude, random walks on the biases
  // (variances density^2 h), plus the position part of the integrated accelerometer noise.
  const auto sq = [](double x) { return x * x; };
  const double na = sq(*options_.accel_noise_density_m_s2_sqrt_hz);
  const double ng = sq(*options_.gyro_noise_density_rad_s_sqrt_hz);
  const double wa = sq(*options_.accel_random_walk_m_s3_sqrt_hz);
  const double wg = sq(*options_.gyro_random_walk_rad_s2_sqrt_hz);
  const Mat3 I = Mat3::Identity();
  Mat15 Q = Mat15::Zero();
  Q.block<3, 3>(kP, kP) = (na * h * h * h / 3.0) * I;
  Q.block<3, 3>(kP, kV) = (na * h * h / 2.0) * I;
  Q.block<3, 3>(kV, kP) = (na * h * h / 2.0) * I;
  Q.block<3, 3>(kV, kV) = (na * h) * I;
  Q.block<3, 3>(kTheta, kTheta) = (ng * h) * I;
  Q.block<3, 3>(kBa, kBa) = (wa * h) * I;
  Q.block<3, 3>(kBg, kBg) = (wg * h) * I;
  Mat21 P;
  P.topLeftCorner<15, 15>() = F * P_.topLeftCorner<15, 15>() * F.transpose() + Q;
  P.topRightCorner<15, 6>() = F * P_.topRightCorner<15, 6>();
  P.bottomLeftCorner<6, 15>() = P.topRightCorner<15, 6>().transpose();
  P.bottomRightCorner<6, 6>() = P_.bottomRightCorner<6, 6>();
  if (!finite(next) || !P.allFinite()) {
    ++stats_.nonfinite_guards;
    state_.t_ns = b.t_ns;
    return;
  }
  state_ = next;
  P_ = 0.5 * (P + P.transpose());
}

void Eskf::propagate(const ImuSample& imu) {
  if (!imu.gyro_rad_s.allFinite() || !imu.accel_m_s2.allFinite()) {
    ++stats_.nonfinite_guards;
    return;
  }
  require_time(imu.t_ns, "propagate");
  const Input in{imu.t_ns, imu.gyro_rad_s, imu.accel_m_s2};
  if (imu.t_ns > state_.t_ns) {
    if (samples_seen_ == 0) {
      Input held = in;  // nothing before the first sample: hold it back to the state's time
      held.t_ns = state_.t_ns;
      propagate_piece(held, in);
    } else {
      propagate_piece(at_state_, in);
    }
  }
  // A sample at the state's own time replaces whatever input was extrapolated there.
  at_state_ = in;
  if (samples_seen_ > 0 && imu.t_ns == last_sample_.t_ns) {
    last_sample_ = in;
  } else {
    prev_sample_ = last_sample_;
    last_sample_ = in;
    samples_seen_ = std::min(samples_seen_ + 1, 2);
  }
  ++stats_.imu_samples;
}

void Eskf::propagate_to(TimeNs t_ns, const char* who) {
  require_time(t_ns, who);
  if (t_ns == state_.t_ns) return;
  if (samples_seen_ == 0) {
    throw UserError(
        fmt::format("Eskf::{}: no IMU sample before t = {} s: propagate() the IMU samples up to a "
                    "measurement's time first",
                    who, format_seconds(t_ns)));
  }
  // Continue the last two samples' linear trend (first-order hold, at most one sample interval
  // ahead), so that the piece after the next sample is still interpolated linearly.
  Input target = last_sample_;
  target.t_ns = t_ns;
  if (samples_seen_ >= 2) {
    const double span = ns_to_seconds(last_sample_.t_ns - prev_sample_.t_ns);
    const double s = std::min(ns_to_seconds(t_ns - last_sample_.t_ns), span) / span;
    target.gyro += s * (last_sample_.gyro - prev_sample_.gyro);
    target.accel += s * (last_sample_.accel - prev_sample_.accel);
  }
  propagate_piece(at_state_, target);
  at_state_ = target;
}

void Eskf::clone_pose() {
  // The clone's error is the current pose error: copy its rows and columns.
  clone_q_ = state_.q_W_I;
  clone_p_ = state_.p_W_m;
  const Eigen::Matrix<double, 3, 21> rows_p = P_.block<3, 21>(kP, 0);
  const Eigen::Matrix<double, 3, 21> rows_theta = P_.block<3, 21>(kTheta, 0);
  P_.block<3, 21>(kCloneP, 0) = rows_p;
  P_.block<3, 21>(kCloneTheta, 0) = rows_theta;
  const Eigen::Matrix<double, 21, 3> cols_p = P_.block<21, 3>(0, kP);
  const Eigen::Matrix<double, 21, 3> cols_theta = P_.block<21, 3>(0, kTheta);
  P_.block<21, 3>(0, kCloneP) = cols_p;
  P_.block<21, 3>(0, kCloneTheta) = cols_theta;
  has_clone_ = true;
}

void Eskf::inject(const Vec21& dx) {
  // Sola Section 6 (injection of the error, then reset): the error's mean goes into the nominal
  // state and the covariance follows the reset Jacobian G = I - [dtheta / 2]x on each attitude.
  state_.p_W_m += dx.segment<3>(kP);
  state_.v_W_m_s += dx.segment<3>(kV);
  state_.q_W_I = (state_.q_W_I * so3_exp(dx.segment<3>(kTheta))).normalized();
  state_.accel_bias_m_s2 += dx.segment<3>(kBa);
  state_.gyro_bias_rad_s += dx.segment<3>(kBg);
  clone_p_ += dx.segment<3>(kCloneP);
  clone_q_ = (clone_q_ * so3_exp(dx.segment<3>(kCloneTheta))).normalized();
  Mat21 G = Mat21::Identity();
  G.block<3, 3>(kTheta, kTheta) -= 0.5 * hat(dx.segment<3>(kTheta));
  G.block<3, 3>(kCloneTheta, kCloneTheta) -= 0.5 * hat(dx.segment<3>(kCloneTheta));
  P_ = G * P_ * G.transpose();
  P_ = 0.5 * (P_ + P_.transpose());
}

template <int M>
bool Eskf::fuse(const Eigen::Matrix<double, M, 1>& r, const Eigen::Matrix<double, M, 21>& H,
                const Eigen::Matrix<double, M, M>& R, double gate, std::int64_t* gated) {
  using MatM = Eigen::Matrix<double, M, M>;
  const Eigen::Matrix<double, 21, M> PHt = P_ * H.transpose();
  MatM S = H * PHt + R;
  S = 0.5 * (S + S.transpose());
  const Eigen::LLT<MatM> llt(S);
  if (llt.info() != Eigen::Success || !r.allFinite()) {
    ++stats_.nonfinite_guards;
    return false;
  }
  const double nis = r.dot(llt.solve(r));
  if (!std::isfinite(nis)) {
    ++stats_.nonfinite_guards;
    return false;
  }
  if (gate > 0.0 && nis > gate) {
    ++*gated;
    return false;
  }
  // K = P H^T S^-1; Joseph form (I - K H) P (I - K H)^T + K R K^T.
  const Eigen::Matrix<double, 21, M> K = llt.solve(PHt.transpose()).transpose();
  const Vec21 dx = K * r;
  const Mat21 A = Mat21::Identity() - K * H;
  const Mat21 P = A * P_ * A.transpose() + K * R * K.transpose();
  if (!dx.allFinite() || !P.allFinite()) {
    ++stats_.nonfinite_guards;
    return false;
  }
  P_ = P;
  inject(dx);
  return true;
}

bool Eskf::update_vo(TimeNs t_ns, const vo::VoResult& vo) {
  propagate_to(t_ns, "update_vo");
  bool fused = false;
  if (!vo.valid || !has_clone_) {
    ++stats_.vo_skipped;
  } else if (!vo::detail::is_finite(vo.T_prev_curr)) {
    ++stats_.nonfinite_guards;
  } else {
    Eigen::Matrix<double, 6, 21> H;
    const SE3 pred =
        detail::predict_vo(clone_q_, clone_p_, state_.q_W_I, state_.p_W_m, extrinsics_.T_I_C, &H);
    Vec6 r;
    r.head<3>() = vo.T_prev_curr.translation() - pred.translation();
    r.tail<3>() = so3_log(pred.quaternion().conjugate() * vo.T_prev_curr.quaternion());
    fused = fuse<6>(r, H, vo_R_, options_.vo_gate_chi2, &stats_.vo_gated);
    if (fused) ++stats_.vo_fused;
  }
  clone_pose();
  return fused;
}

bool Eskf::update_gps(const GpsPositionMeasurement& gps) {
  const Mat3& C = gps.covariance_m2;
  const double scale = std::max(1.0, C.cwiseAbs().maxCoeff());
  bool ok = C.allFinite() && (C - C.transpose()).cwiseAbs().maxCoeff() <= 1e-9 * scale;
  if (ok) ok = Eigen::SelfAdjointEigenSolver<Mat3>(C, Eigen::EigenvaluesOnly).eigenvalues()(0) > 0;
  if (!ok) {
    throw UserError(
        "Eskf::update_gps: the fix's covariance must be symmetric positive definite, "
        "got " +
        matrix_text(C) + " m^2 at t = " + format_seconds(gps.t_ns) + " s");
  }
  propagate_to(gps.t_ns, "update_gps");
  if (!gps.p_W_m.allFinite()) {
    ++stats_.nonfinite_guards;
    return false;
  }
  Eigen::Matrix<double, 3, 15> H15;
  const Vec3 pred =
      detail::predict_gps(state_.q_W_I, state_.p_W_m, extrinsics_.p_I_antenna_m, &H15);
  Eigen::Matrix<double, 3, 21> H = Eigen::Matrix<double, 3, 21>::Zero();
  H.leftCols<15>() = H15;
  const Vec3 r = gps.p_W_m - pred;
  const bool fused = fuse<3>(r, H, C, options_.gps_gate_chi2, &stats_.gps_gated);
  if (fused) ++stats_.gps_fused;
  return fused;
}

bool Eskf::update_heading(const HeadingMeasurement& heading) {
  propagate_to(heading.t_ns, "update_heading");
  if (!std::isfinite(heading.heading_rad)) {
    ++stats_.nonfinite_guards;
    return false;
  }
  Eigen::Matrix<double, 1, 15> H15;
  const double pred = detail::predict_heading(state_.q_W_I, extrinsics_.R_I_M, &H15);
  Eigen::Matrix<double, 1, 21> H = Eigen::Matrix<double, 1, 21>::Zero();
  H.leftCols<15>() = H15;
  Eigen::Matrix<double, 1, 1> r, R;
  r(0) = wrap_angle_rad(heading.heading_rad - pred);
  R(0) = *options_.compass_noise_rad * *options_.compass_noise_rad;
  const bool fused = fuse<1>(r, H, R, options_.heading_gate_chi2, &stats_.heading_gated);
  if (fused) ++stats_.heading_fused;
  return fused;
}

}  // namespace driftlab::fusion
