// The constant-acceleration Kalman filter that smooths the sparse VO trajectory in river paper
// Section 2.3.1 (Kriechbaumer et al. 2015, Eqs. (4)-(5)). State: the camera's twist
// v = [rho_dot; omega] (6, camera optical frame, [m/s; rad/s]) and its rate a (6). Measurement:
// a VO increment over Delta t as a twist, SE3::log(T_prev_curr) / Delta t. Output: the smoothed
// increment exp(v Delta t), which accumulates into the smoothed trajectory by Eq. (3).
//
// "Smooth": the paper runs "a standard Kalman filter", i.e. a causal forward filter, and that
// is what ConstantAccelerationSmoother does, step by step. smooth_trajectory() runs the same
// filter over a whole sequence and, with CaSmootherOptions::rts_backward_pass, adds a
// Rauch-Tung-Striebel backward pass (a fixed-interval smoother, not in the paper).
#pragma once

#include <array>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/se3.hpp"
#include "core/time.hpp"
#include "core/yaml_io.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::fusion {

namespace detail {
/// One axis of Eqs. (4)-(5): state (velocity v, acceleration a), its symmetric covariance, and
/// the gain of the last measurement update.
struct CaAxis {
  double v = 0.0, a = 0.0;
  double p00 = 0.0, p01 = 0.0, p11 = 0.0;
  double k0 = 0.0, k1 = 0.0;
};
}  // namespace detail

/// Noise model of the filter. Axes are the camera optical frame's x (right), y (down),
/// z (forward). The river paper gives no values; the defaults are ours (see each field).
struct CaSmootherOptions {
  /// Process noise epsilon of Eq. (4): white jerk of spectral density q^2 per axis, so that over
  /// a step Delta t, Q = q^2 [Delta t^3 / 3, Delta t^2 / 2; Delta t^2 / 2, Delta t] (velocity,
  /// acceleration). Defaults: a survey vessel heaving 0.1 m and pitching 2 deg at a 4 s wave
  /// period changes its acceleration by ~0.25 m/s^2 and ~0.1 rad/s^2 within a second.
  std::array<double, 3> jerk_noise_linear_m_s3_sqrt_hz{0.5, 0.5, 0.5};
  std::array<double, 3> jerk_noise_angular_rad_s3_sqrt_hz{0.1, 0.1, 0.1};
  /// Measurement noise nu of Eq. (5), given as the standard deviation of one VO increment per
  /// axis (translation part rho [m], rotation vector [rad]); the twist's variance is then
  /// (sd / Delta t)^2. Defaults: the sparse VO's per-frame targets, 5 mm and 0.02 deg.
  std::array<double, 3> increment_noise_linear_m{0.005, 0.005, 0.005};
  std::array<double, 3> increment_noise_angular_rad{3.5e-4, 3.5e-4, 3.5e-4};
  /// Prior of the state at reset (zero mean): standard deviations per axis.
  double initial_velocity_sd_m_s = 5.0;
  double initial_angular_velocity_sd_rad_s = 1.0;
  double initial_acceleration_sd_m_s2 = 2.0;
  double initial_angular_acceleration_sd_rad_s2 = 1.0;
  /// smooth_trajectory() only: add a Rauch-Tung-Striebel backward pass (non-causal).
  bool rts_backward_pass = false;

  template <class A>
  void visit(A& a) {
    a("jerk_noise_linear_m_s3_sqrt_hz", jerk_noise_linear_m_s3_sqrt_hz,
      "Process noise, Eq. (4): jerk noise density of the linear velocity per camera axis "
      "(x, y, z) [m/s^3/sqrt(Hz)]",
      yaml::positive());
    a("jerk_noise_angular_rad_s3_sqrt_hz", jerk_noise_angular_rad_s3_sqrt_hz,
      "Process noise, Eq. (4): jerk noise density of the angular velocity per camera axis "
      "[rad/s^3/sqrt(Hz)]",
      yaml::positive());
    a("increment_noise_linear_m", increment_noise_linear_m,
      "Measurement noise, Eq. (5): standard deviation of a VO increment's translation per "
      "camera axis [m]",
      yaml::positive());
    a("increment_noise_angular_rad", increment_noise_angular_rad,
      "Measurement noise, Eq. (5): standard deviation of a VO increment's rotation vector per "
      "camera axis [rad]",
      yaml::positive());
    a("initial_velocity_sd_m_s", initial_velocity_sd_m_s,
      "Prior standard deviation of each linear velocity component [m/s]", yaml::positive());
    a("initial_angular_velocity_sd_rad_s", initial_angular_velocity_sd_rad_s,
      "Prior standard deviation of each angular velocity component [rad/s]", yaml::positive());
    a("initial_acceleration_sd_m_s2", initial_acceleration_sd_m_s2,
      "Prior standard deviation of each linear acceleration component [m/s^2]", yaml::positive());
    a("initial_angular_acceleration_sd_rad_s2", initial_angular_acceleration_sd_rad_s2,
      "Prior standard deviation of each angular acceleration component [rad/s^2]",
      yaml::positive());
    a("rts_backward_pass", rts_backward_pass,
      "Also write NAME_ca_rts estimates: the forward filter (the paper's, NAME_ca) followed by a "
      "Rauch-Tung-Striebel backward pass over the whole run (not causal: every frame sees the "
      "later ones)");
  }

  /// "" when valid, else one "field: got V, expected E" per problem, one per line.
  std::string validate() const { return yaml::validate(*this); }
};

/// One step of the smoother.
struct SmoothedStep {
  TimeNs t_ns = 0;
  double dt_s = 0.0;      ///< time since the previous update; 0 on the first
  bool measured = false;  ///< a valid VO increment was fused; false: prediction only
  SE3 T_prev_curr;        ///< smoothed motion over the step, exp(v dt); identity on the first
  Vec6 velocity = Vec6::Zero();      ///< smoothed twist [rho_dot (m/s); omega (rad/s)]
  Vec6 acceleration = Vec6::Zero();  ///< its rate [m/s^2; rad/s^2]
  Vec6 velocity_sd = Vec6::Zero();   ///< posterior standard deviation of `velocity`
};

/// The forward constant-acceleration filter of Eqs. (4)-(5). With Eq. (4)'s identity blocks and
/// per-axis noise, the 12-state filter is six independent 2-state (velocity, acceleration)
/// filters; they are run as such, which is exact and avoids 12x12 algebra.
class ConstantAccelerationSmoother {
 public:
  using Options = CaSmootherOptions;

  /// Throws UserError naming the bad field when the options are invalid.
  explicit ConstantAccelerationSmoother(const Options& options);

  /// Back to the prior: zero twist and rate, initial covariance, no previous time.
  void reset();

  /// Advances to time t_ns (the time of the frame `vo` ends at) and fuses the increment when
  /// vo.valid; an invalid result is skipped by predicting only. The first call after reset()
  /// only starts the clock (there is no Delta t yet) and returns the identity. Throws
  /// UserError when t_ns does not increase.
  SmoothedStep update(TimeNs t_ns, const vo::VoResult& vo);

  const Options& options() const { return options_; }
  /// State (velocity, acceleration) of axis i in [0, 6): 0-2 linear, 3-5 angular.
  Eigen::Vector2d axis_state(int i) const;
  /// Covariance of axis i's (velocity, acceleration).
  Eigen::Matrix2d axis_covariance(int i) const;
  /// Kalman gain of axis i at its last measurement update (Eq. (5)); zero before any.
  Eigen::Vector2d axis_gain(int i) const;
  /// Times a non-finite state or measurement was caught and the filter restarted from its
  /// prior (never expected; counted for reports, as docs/design.md asks).
  int nonfinite_guards() const { return nonfinite_guards_; }

 private:
  void restart_from_prior();
  bool state_finite() const;

  Options options_;
  std::array<double, 6> q2_{};  // jerk spectral densities
  std::array<double, 6> increment_var_{};
  std::array<detail::CaAxis, 6> axes_{};
  bool started_ = false;
  TimeNs t_prev_ns_ = 0;
  int nonfinite_guards_ = 0;
};

/// A whole sequence smoothed at once.
struct SmoothedTrajectory {
  std::vector<TimeNs> t_ns;
  std::vector<SE3> T_first_cam;  ///< camera pose in the first camera's frame; [0] = identity
  std::vector<Vec6> velocity;    ///< smoothed twist per frame ([0] = prior)
  int predicted_only = 0;        ///< steps after the first without a valid VO increment
};

/// Runs the forward filter over (t_ns[k], vo[k]) (same length, times increasing) and
/// accumulates the smoothed increments, T_first_cam[k] = T_first_cam[k-1] * exp(v_k dt_k)
/// (Eq. (3) with the smoothed H); with options.rts_backward_pass the twists are first
/// smoothed backwards by Rauch-Tung-Striebel. Throws UserError on bad options or input.
SmoothedTrajectory smooth_trajectory(std::span<const TimeNs> t_ns, std::span<const vo::VoResult> vo,
                                     const CaSmootherOptions& options);

}  // namespace driftlab::fusion
