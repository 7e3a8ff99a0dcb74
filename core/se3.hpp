// Rigid-body transforms on Eigen: SO(3) helpers and the SE3 pose type.
// A pose T_a_b maps points from frame b into frame a: p_a = T_a_b * p_b (docs/design.md,
// "Frames").
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace driftlab {

using Vec3 = Eigen::Vector3d;
using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat3 = Eigen::Matrix3d;
using Mat4 = Eigen::Matrix4d;
using Quat = Eigen::Quaterniond;

/// 3x3 skew-symmetric matrix with hat(a) * b = a.cross(b).
Mat3 hat(const Vec3& w);
/// Inverse of hat() for a skew-symmetric matrix.
Vec3 vee(const Mat3& W);

/// SO(3) exponential (Rodrigues): rotation vector [rad] -> unit quaternion.
Quat so3_exp(const Vec3& w);
/// SO(3) logarithm: unit quaternion -> rotation vector [rad] with |w| <= pi.
Vec3 so3_log(const Quat& q);
/// Left Jacobian of SO(3), J_l(w), used by the SE(3) exponential.
Mat3 so3_left_jacobian(const Vec3& w);
/// Inverse of so3_left_jacobian().
Mat3 so3_left_jacobian_inverse(const Vec3& w);

/// A rigid transform with value semantics: unit quaternion + translation [m].
class SE3 {
 public:
  /// Identity.
  SE3() : q_(Quat::Identity()), t_(Vec3::Zero()) {}
  /// From a rotation (normalised here) and a translation [m].
  SE3(const Quat& q, const Vec3& t);
  /// From a rotation matrix (must be orthonormal, det +1) and a translation [m].
  SE3(const Mat3& R, const Vec3& t);
  /// From a 4x4 homogeneous matrix (bottom row 0 0 0 1).
  explicit SE3(const Mat4& T);

  static SE3 identity() { return SE3(); }
  static SE3 from_translation(const Vec3& t) { return SE3(Quat::Identity(), t); }
  static SE3 from_rotation(const Quat& q) { return SE3(q, Vec3::Zero()); }

  const Quat& quaternion() const { return q_; }
  Mat3 rotation() const { return q_.toRotationMatrix(); }
  const Vec3& translation() const { return t_; }
  Mat4 matrix() const;

  /// Composition: (T_a_b * T_b_c) = T_a_c.
  SE3 operator*(const SE3& other) const;
  /// Point action p_a = T_a_b * p_b.
  Vec3 operator*(const Vec3& p) const { return q_ * p + t_; }
  SE3 inverse() const;

  /// SE(3) exponential of a twist xi = [rho (translation part); phi (rotation vector)].
  static SE3 exp(const Vec6& xi);
  /// SE(3) logarithm, xi = [rho; phi], inverse of exp() for |phi| < pi.
  Vec6 log() const;

  /// Geodesic interpolation a * exp(s * log(a^-1 * b)), s in [0, 1].
  static SE3 interpolate(const SE3& a, const SE3& b, double s);
  /// Interpolation of rotation (slerp) and translation (linear) separately, s in [0, 1].
  /// This is what pose-by-time interpolation of trajectories uses.
  static SE3 interpolate_decoupled(const SE3& a, const SE3& b, double s);

  /// True when translations differ by < tol_m and rotations by < tol_rad (quaternion sign ignored).
  bool is_approx(const SE3& other, double tol_m = 1e-9, double tol_rad = 1e-9) const;

 private:
  Quat q_;
  Vec3 t_;
};

/// Angle [rad] of the rotation between two quaternions, in [0, pi], sign-agnostic.
double angle_between(const Quat& a, const Quat& b);

}  // namespace driftlab
