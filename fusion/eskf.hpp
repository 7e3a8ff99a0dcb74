// Error-state Kalman filter (ESKF) fusing an IMU with VO, GPS and a compass. The nominal state
// is the IMU frame I's pose in the world (q_W_I, p_W), its velocity v_W and the accelerometer and
// gyroscope biases; the filter's Gaussian is over the 15-dimensional error state
//   dx = [dp (0-2), dv (3-5), dtheta (6-8), dba (9-11), dbg (12-14)]
// with p = p^ + dp, v = v^ + dv, q = q^ * Exp(dtheta) (a local, body-frame attitude error),
// ba = ba^ + dba, bg = bg^ + dbg (J. Sola, "Quaternion kinematics for the error-state Kalman
// filter", 2017, Section 5, whose order and local-error convention this follows).
//
// Measurements:
//  - IMU samples drive the propagation (Sola Section 5.4, with a second-order scheme, below).
//  - VO relative poses T_prev_curr of the left camera: a stochastic clone of the pose at the
//    previous frame (6 more error states, dp_c and dtheta_c; Roumeliotis & Burdick 2002,
//    "Stochastic cloning") makes the relative pose a function of the state, so that its noise
//    is fused once and correctly.
//  - GPS antenna positions, when a fix exists.
//  - Compass headings (ZYX yaw of the compass sensor frame).
// World NED is treated as inertial with gravity g_W = (0, 0, +g), as the simulator does.
//
// The river paper's conclusion that inertial sensors constrain pitch and roll, and that even a
// low-cost IMU improves VO position accuracy by more than an order of magnitude, is what this
// filter lets a user test. The filter never sees ground truth.
#pragma once

#include <array>
#include <cstdint>
#include <string>

#include <Eigen/Core>

#include "core/se3.hpp"
#include "core/time.hpp"
#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "fusion/measurements.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::fusion {

using Vec15 = Eigen::Matrix<double, 15, 1>;
using Mat15 = Eigen::Matrix<double, 15, 15>;
using Vec21 = Eigen::Matrix<double, 21, 1>;
using Mat21 = Eigen::Matrix<double, 21, 21>;

/// Offsets of the error-state blocks (each 3 wide).
namespace eskf {
inline constexpr int kP = 0;      ///< position error [m], world
inline constexpr int kV = 3;      ///< velocity error [m/s], world
inline constexpr int kTheta = 6;  ///< attitude error [rad], IMU frame (local)
inline constexpr int kBa = 9;     ///< accelerometer bias error [m/s^2]
inline constexpr int kBg = 12;    ///< gyroscope bias error [rad/s]
inline constexpr int kDim = 15;
inline constexpr int kCloneP = 15;      ///< clone of the position at the previous VO frame
inline constexpr int kCloneTheta = 18;  ///< clone of the attitude at the previous VO frame
inline constexpr int kAugmentedDim = 21;
}  // namespace eskf

/// Noise model and prior. IMU defaults are the simulated MPU-9250's (the basin paper's IMU;
/// sim ImuOptions preset mpu9250: datasheet densities, assumed random walks); replace them with
/// your unit's Kalibr parameters. VO and compass defaults are the sparse VO's per-frame targets
/// and the simulated compass's 1 deg. Priors and gates are ours.
struct EskfOptions {
  double gravity_m_s2 = 9.80665;
  // IMU and compass noise: null (a scenario's default) is filled in by the pipeline from the
  // scenario's sensor models (driftlab vo: the dataset's imu0/sensor.yaml); the filter itself
  // needs numbers.
  std::optional<double> gyro_noise_density_rad_s_sqrt_hz =
      1.7453292519943295e-4;  // 0.01 deg/s/sqrt(Hz)
  std::optional<double> gyro_random_walk_rad_s2_sqrt_hz = 2.0e-5;
  std::optional<double> accel_noise_density_m_s2_sqrt_hz = 2.941995e-3;  // 300 ug/sqrt(Hz)
  std::optional<double> accel_random_walk_m_s3_sqrt_hz = 1.5e-4;
  /// Per-frame VO noise along the left camera's optical axes (x right, y down, z forward):
  /// translation of T_prev_curr [m] and its rotation vector [rad].
  std::array<double, 3> vo_translation_noise_m{0.005, 0.005, 0.005};
  std::array<double, 3> vo_rotation_noise_rad{3.5e-4, 3.5e-4, 3.5e-4};
  std::optional<double> compass_noise_rad = 0.017453292519943295;  // 1 deg
  /// Prior standard deviations around the initial state. Attitude: about the IMU's x and y
  /// axes (roll, pitch, from levelling on gravity) and z (heading, from the compass).
  double initial_position_sd_m = 1.0;
  double initial_velocity_sd_m_s = 0.1;
  double initial_roll_pitch_sd_rad = 0.01;
  double initial_yaw_sd_rad = 0.02;
  double initial_accel_bias_sd_m_s2 = 0.05;
  double initial_gyro_bias_sd_rad_s = 0.005;
  /// Chi-square gates on the normalised innovation squared; 0 = no gating. (E.g. 22.5, 16.3,
  /// 10.8 reject 0.1 % of correct 6-, 3- and 1-dof measurements.)
  double vo_gate_chi2 = 0.0;
  double gps_gate_chi2 = 0.0;
  double heading_gate_chi2 = 0.0;

  template <class A>
  void visit(A& a) {
    a("gravity_m_s2", gravity_m_s2, "Gravity magnitude, along world down [m/s^2]",
      yaml::positive());
    a("gyro_noise_density_rad_s_sqrt_hz", gyro_noise_density_rad_s_sqrt_hz,
      "Gyroscope white-noise density (Kalibr gyroscope_noise_density) [rad/s/sqrt(Hz)]; null: the "
      "scenario's IMU model (sensors.imu)",
      yaml::positive());
    a("gyro_random_walk_rad_s2_sqrt_hz", gyro_random_walk_rad_s2_sqrt_hz,
      "Gyroscope bias random walk (Kalibr gyroscope_random_walk) [rad/s^2/sqrt(Hz)]; null: the "
      "scenario's IMU model (sensors.imu)",
      yaml::positive());
    a("accel_noise_density_m_s2_sqrt_hz", accel_noise_density_m_s2_sqrt_hz,
      "Accelerometer white-noise density (Kalibr accelerometer_noise_density) [m/s^2/sqrt(Hz)]; "
      "null: the scenario's IMU model (sensors.imu)",
      yaml::positive());
    a("accel_random_walk_m_s3_sqrt_hz", accel_random_walk_m_s3_sqrt_hz,
      "Accelerometer bias random walk (Kalibr accelerometer_random_walk) [m/s^3/sqrt(Hz)]; null: "
      "the scenario's IMU model (sensors.imu)",
      yaml::positive());
    a("vo_translation_noise_m", vo_translation_noise_m,
      "Standard deviation of a VO increment's translation per left-camera optical axis [m]",
      yaml::positive());
    a("vo_rotation_noise_rad", vo_rotation_noise_rad,
      "Standard deviation of a VO increment's rotation vector per left-camera optical axis [rad]",
      yaml::positive());
    a("compass_noise_rad", compass_noise_rad,
      "Compass heading noise, standard deviation [rad]; null: from the scenario's compass model",
      yaml::positive());
    a("initial_position_sd_m", initial_position_sd_m,
      "Prior standard deviation of each position component [m]", yaml::positive());
    a("initial_velocity_sd_m_s", initial_velocity_sd_m_s,
      "Prior standard deviation of each velocity component [m/s]", yaml::positive());
    a("initial_roll_pitch_sd_rad", initial_roll_pitch_sd_rad,
      "Prior standard deviation of the attitude about the IMU's x and y axes [rad]",
      yaml::positive());
    a("initial_yaw_sd_rad", initial_yaw_sd_rad,
      "Prior standard deviation of the attitude about the IMU's z axis [rad]", yaml::positive());
    a("initial_accel_bias_sd_m_s2", initial_accel_bias_sd_m_s2,
      "Prior standard deviation of each accelerometer bias component [m/s^2]", yaml::positive());
    a("initial_gyro_bias_sd_rad_s", initial_gyro_bias_sd_rad_s,
      "Prior standard deviation of each gyroscope bias component [rad/s]", yaml::positive());
    a("vo_gate_chi2", vo_gate_chi2,
      "Reject a VO increment whose normalised innovation squared exceeds this (6 dof; 0 = off)",
      yaml::non_negative());
    a("gps_gate_chi2", gps_gate_chi2,
      "Reject a GPS fix whose normalised innovation squared exceeds this (3 dof; 0 = off)",
      yaml::non_negative());
    a("heading_gate_chi2", heading_gate_chi2,
      "Reject a compass heading whose normalised innovation squared exceeds this (1 dof; 0 = "
      "off)",
      yaml::non_negative());
  }

  /// "" when valid, else one "field: got V, expected E" per problem, one per line.
  std::string validate() const { return yaml::validate(*this); }
};

/// Where the sensors sit relative to the IMU frame I (the frame whose pose the filter
/// estimates). From the scenario's mounts: T_I_C = T_B_I^-1 * T_B_C, and so on.
struct EskfExtrinsics {
  SE3 T_I_C;                          ///< left camera, OpenCV optical frame, in I
  Vec3 p_I_antenna_m = Vec3::Zero();  ///< GPS antenna phase centre in I [m]
  Mat3 R_I_M = Mat3::Identity();      ///< compass sensor axes in I
};

/// The nominal state.
struct EskfState {
  TimeNs t_ns = 0;
  Quat q_W_I = Quat::Identity();
  Vec3 p_W_m = Vec3::Zero();            ///< IMU origin, world NED [m]
  Vec3 v_W_m_s = Vec3::Zero();          ///< its velocity, world NED [m/s]
  Vec3 accel_bias_m_s2 = Vec3::Zero();  ///< added to the specific force by the sensor
  Vec3 gyro_bias_rad_s = Vec3::Zero();  ///< added to the angular rate by the sensor
  SE3 T_W_I() const { return SE3(q_W_I, p_W_m); }
};

/// Counts for reports (Ceres' Summary in spirit).
struct EskfStats {
  std::int64_t imu_samples = 0;  ///< samples propagated
  std::int64_t vo_fused = 0;
  std::int64_t vo_skipped = 0;  ///< invalid results and the first frame (no clone yet)
  std::int64_t vo_gated = 0;
  std::int64_t gps_fused = 0;
  std::int64_t gps_gated = 0;
  std::int64_t heading_fused = 0;
  std::int64_t heading_gated = 0;
  std::int64_t nonfinite_guards = 0;  ///< non-finite inputs skipped or steps undone; never expected
  /// "imu 12000, vo 1180 fused / 20 skipped / 0 gated, gps 60 / 0, heading 600 / 0, guards 0".
  std::string brief() const;
};

/// The error-state Kalman filter. Call in time order: IMU samples with propagate(), and each
/// update at its time stamp after the IMU samples up to that time (an update between two IMU
/// samples propagates to its time on the last samples' linear trend).
class Eskf {
 public:
  using Options = EskfOptions;

  /// Starts at `initial` (its t_ns is the filter's time) with the options' prior. Throws
  /// UserError naming the bad field when the options are invalid or the state is not finite.
  Eskf(const Options& options, const EskfExtrinsics& extrinsics, const EskfState& initial);

  /// Propagates to imu.t_ns (Sola Section 5.4, second order: rates and specific
  /// forces interpolated linearly between samples). A non-finite sample is skipped and
  /// counted. Throws UserError when imu.t_ns is before the filter's time.
  void propagate(const ImuSample& imu);

  /// The VO result of the frame at `t_ns` (every frame, valid or not, in order: the VO's
  /// T_prev_curr is relative to the previous frame whatever that was). A valid result updates
  /// the pose against the clone of the previous frame; an invalid one is skipped. Either way the
  /// clone moves to this frame. Returns whether the result was fused.
  bool update_vo(TimeNs t_ns, const vo::VoResult& vo);
  /// A GPS fix (call only with a fix). Throws UserError when its covariance is not symmetric
  /// positive definite. Returns whether it was fused (false: gated or not finite).
  bool update_gps(const GpsPositionMeasurement& gps);
  /// A compass heading. Returns whether it was fused.
  bool update_heading(const HeadingMeasurement& heading);

  const EskfState& state() const { return state_; }
  /// Covariance of the 15-dimensional error state (for NEES: e^T P^-1 e with e =
  /// eskf_error(state(), truth)).
  Mat15 covariance() const { return P_.topLeftCorner<15, 15>(); }
  /// Covariance including the clone of the previous VO frame's pose.
  const Mat21& augmented_covariance() const { return P_; }
  /// Pose of the left camera in the world, T_W_I * T_I_C (what estimates/NAME.tum holds).
  SE3 T_W_C() const { return state_.T_W_I() * extrinsics_.T_I_C; }
  const EskfStats& stats() const { return stats_; }
  const Options& options() const { return options_; }
  const EskfExtrinsics& extrinsics() const { return extrinsics_; }

 private:
  struct Input {
    TimeNs t_ns = 0;
    Vec3 gyro = Vec3::Zero(), accel = Vec3::Zero();
  };
  void require_time(TimeNs t_ns, const char* who) const;
  void propagate_to(TimeNs t_ns, const char* who);
  void propagate_piece(const Input& a, const Input& b);
  void clone_pose();
  template <int M>
  bool fuse(const Eigen::Matrix<double, M, 1>& r, const Eigen::Matrix<double, M, 21>& H,
            const Eigen::Matrix<double, M, M>& R, double gate, std::int64_t* gated);
  void inject(const Vec21& dx);

  Options options_;
  EskfExtrinsics extrinsics_;
  EskfState state_;
  Mat21 P_ = Mat21::Zero();
  Quat clone_q_ = Quat::Identity();
  Vec3 clone_p_ = Vec3::Zero();
  bool has_clone_ = false;
  Input at_state_;  // IMU input at the state's time (a sample, or extrapolated)
  Input last_sample_, prev_sample_;
  int samples_seen_ = 0;
  Eigen::Matrix<double, 6, 6> vo_R_ = Eigen::Matrix<double, 6, 6>::Zero();
  EskfStats stats_;
};

/// The error e with truth = estimate [+] e (same layout as the error state): the position,
/// velocity and bias differences and Log(q_estimate^-1 q_truth).
Vec15 eskf_error(const EskfState& estimate, const EskfState& truth);

/// q_W_I from a specific force measured at rest or in steady motion (gravity's reaction:
/// roll = atan2(-f_y, -f_z), pitch = atan2(f_x, sqrt(f_y^2 + f_z^2))) and a compass heading
/// of the compass frame R_I_M. For the pipeline's initialisation.
Quat attitude_from_gravity_and_heading(const Vec3& f_I_m_s2, double heading_rad,
                                       const Mat3& R_I_M = Mat3::Identity());

namespace detail {
/// Angular rate and specific force at one instant.
struct ImuInput {
  Vec3 gyro_rad_s = Vec3::Zero();
  Vec3 accel_m_s2 = Vec3::Zero();
};

/// The nominal propagation over h seconds with inputs a at the start and b at the end:
///   R1 = R0 Exp(((w_a + w_b) / 2 - bg) h)
///   acc = (R0 (f_a - ba) + R1 (f_b - ba)) / 2 + g
///   v1 = v0 + acc h,  p1 = p0 + v0 h + acc h^2 / 2
/// (trapezoidal, second order), and in F the exact Jacobian of this map on the error state
/// (Sola Section 5.4.3's F_x, here exact instead of first order in h). t_ns is not changed.
EskfState propagate_nominal(const EskfState& s, const ImuInput& a, const ImuInput& b, double h,
                            double gravity_m_s2, Mat15* F);

/// state [+] dx (the error-state convention above; the clone part of a 21-vector is ignored).
EskfState boxplus(const EskfState& s, const Vec15& dx);

/// Predicted VO increment T_Cprev_Ccurr of the camera from the clone (q_c, p_c) and current
/// (q, p) IMU poses, and the Jacobian of the residual [p_meas - p; Log(R^T R_meas)] (6) with
/// respect to the 21-dimensional error state.
SE3 predict_vo(const Quat& q_c, const Vec3& p_c, const Quat& q, const Vec3& p, const SE3& T_I_C,
               Eigen::Matrix<double, 6, 21>* H);
/// Predicted antenna position p + R p_I_antenna and its Jacobian (3x15).
Vec3 predict_gps(const Quat& q, const Vec3& p, const Vec3& p_I_antenna,
                 Eigen::Matrix<double, 3, 15>* H);
/// Predicted compass heading, ZYX yaw of R_W_I R_I_M, and its Jacobian (1x15).
double predict_heading(const Quat& q, const Mat3& R_I_M, Eigen::Matrix<double, 1, 15>* H);
}  // namespace detail

}  // namespace driftlab::fusion
