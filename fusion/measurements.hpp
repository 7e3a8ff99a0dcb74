// Small measurement types the filters of fusion/ consume, built from what the pipeline has:
// VO results, compass samples, GPS fixes (the filters never see ground truth).
#pragma once

#include <cstddef>
#include <deque>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "core/se3.hpp"
#include "core/time.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::fusion {

/// A compass heading: yaw (ZYX, Fossen) of the compass sensor's x axis, clockwise from true
/// north [rad]. Any value is accepted; the filters wrap it.
struct HeadingMeasurement {
  TimeNs t_ns = 0;           ///< the instant the heading describes
  double heading_rad = 0.0;  ///< true heading (declination already applied) [rad]
};

/// The body-frame motion of one VO step as the basin paper reads it (Section 3.1): the
/// translation t_k as surge and sway velocities and the yaw of R_k as a yaw rate, both of the
/// body FRD frame at the centre of gravity.
struct BodyVelocityMeasurement {
  TimeNs t_ns = 0;              ///< time of the frame the step ends at
  bool valid = false;           ///< false: no usable VO motion for this step (skipped)
  double dt_s = 0.0;            ///< time between the two frames [s]
  double surge_m_s = 0.0;       ///< u: mean velocity along the bow over the step [m/s]
  double sway_m_s = 0.0;        ///< v: mean velocity towards starboard over the step [m/s]
  double yaw_rate_rad_s = 0.0;  ///< yaw (ZYX) of the step's body rotation / dt_s [rad/s]
};

/// The body motion of a VO increment. `T_B_C` is the pose of the left camera's OpenCV optical
/// frame in body FRD (e.g. SE3(R_frd_optical(), lever arm)): the body's own increment is
/// T_B_C * vo.T_prev_curr * T_B_C^-1, whose translation over `dt_s` gives u and v (the lever
/// arm's rotation-induced motion removed) and whose ZYX yaw over `dt_s` the yaw rate.
/// valid = false when vo.valid is false, dt_s <= 0, or anything is not finite.
BodyVelocityMeasurement body_velocity_from_vo(TimeNs t_ns, double dt_s, const vo::VoResult& vo,
                                              const SE3& T_B_C);

/// A GPS position fix of the antenna, world NED, with its error covariance. Only fixes with
/// fix = true become measurements.
struct GpsPositionMeasurement {
  TimeNs t_ns = 0;                        ///< the instant the position describes (stamp - latency)
  Vec3 p_W_m = Vec3::Zero();              ///< antenna position, world NED [m]
  Mat3 covariance_m2 = Mat3::Identity();  ///< error covariance [m^2]; symmetric positive definite

  /// Independent errors: sd_horizontal_m on north and east, sd_vertical_m on down.
  static GpsPositionMeasurement with_sd(TimeNs t_ns, const Vec3& p_W_m, double sd_horizontal_m,
                                        double sd_vertical_m);
};

/// A running estimate of the white noise on sampled signals whose true values change little from
/// one sample to the next (ours; the NED filters' VO measurement noise from the VO's own
/// results). Each channel's second differences d_k = x_k - 2 x_{k-1} + x_{k-2} are pooled over
/// the last `window`; for white noise of standard deviation sigma, d has variance 6 sigma^2, so
/// sigma = median|d| / (0.6745 sqrt(6)): the median keeps a VO's occasional wrong motion out.
/// A smooth true signal adds its own second difference (a 0.05 m/s surge oscillation of 0.8 s
/// sampled at 20 Hz: 0.008 m/s), small against a VO's noise.
class SecondDifferenceNoise {
 public:
  SecondDifferenceNoise(std::size_t channels, std::size_t window = 200,
                        std::size_t min_differences = 2);
  /// The next sample of `channel`.
  void add(std::size_t channel, double x);
  /// A missing sample: every channel's differences start again (none spans the gap).
  void gap();
  /// sigma, once min_differences second differences are pooled; nullopt before.
  std::optional<double> sigma() const;
  void reset();

 private:
  struct Chain {
    double x1 = 0.0, x2 = 0.0;  // the last two samples, newest first
    int n = 0;                  // samples since the last gap (capped at 2)
  };
  std::vector<Chain> chains_;
  std::size_t window_, min_differences_;
  std::deque<double> abs_differences_;
};

}  // namespace driftlab::fusion
