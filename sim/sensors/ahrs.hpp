// Synthetic attitude and heading reference system (AHRS): the river paper's x-IMU, which
// reports ZYX Euler angles of its own frame from a filter on its own gyroscope,
// accelerometer and magnetometer (Madgwick, Harrison & Vaidyanathan, "Estimation of IMU and
// MARG orientation using a gradient descent algorithm", ICORR 2011, the river paper's [43]).
// The paper compares the VO's angles with these (Eq. (11)), so its attitude "truth" carries
// the filter's errors: tilt pulled towards the apparent gravity while the hull accelerates,
// heading pulled by the magnetometer's noise.
//
// Frames: the filter's earth frame is magnetic NED (world NED turned by the declination); at rest
// and level the accelerometer reads (0, 0, -g) in FRD and the field points north and down. The
// reported yaw is magnetic (no declination applied): the paper uses only its changes.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/sensors/clock.hpp"
#include "sim/sensors/csv_detail.hpp"
#include "sim/sensors/imu.hpp"
#include "sim/sensors/sensor_options.hpp"

namespace driftlab::sim {

/// One update of Madgwick's MARG filter: q_W_S (sensor to world NED) advanced by `dt_s` with
/// the gyroscope rate `gyro_S` [rad/s] and pulled by the gradient of the misfit between
/// the predicted and measured directions of the specific force `accel_S` and of the magnetic
/// field `mag_S` (any units), at rate `beta_rad_s`. The field's reference direction is the
/// measured one levelled into the horizontal north and vertical (the paper's magnetic
/// distortion compensation). A zero accelerometer or magnetometer vector leaves that
/// correction out; the result is unit length.
Quat madgwick_marg_update(const Quat& q_W_S, const Vec3& gyro_S, const Vec3& accel_S,
                          const Vec3& mag_S, double beta_rad_s, double dt_s);

/// One reported sample: the unit's Euler angles and, for the evaluation of the reference
/// itself, the true ones of its frame.
struct AhrsSample {
  TimeNs t_ns = 0;
  EulerZYX euler;       // the filter's ZYX angles of the sensor frame in magnetic NED [rad]
  EulerZYX true_euler;  // ground truth, in the same frame
};

class AhrsSimulator {
 public:
  /// Validates `options` (UserError naming sensors.`name`.FIELD). `earth_field_W_nt` is the
  /// site's field in world NED. Streams: NAME.gyro.*, NAME.accel.* (the unit's IMU),
  /// NAME.magnetometer_noise. The filter starts at the true orientation: a unit switched on
  /// and converged before the run.
  AhrsSimulator(const AhrsOptions& options, const Vec3& earth_field_W_nt, const RngStreams& rng,
                std::string name = "ahrs");

  /// One filter update at b.t_ns (call at every update time, in order); a sample at every
  /// updates_per_sample()-th update, the first included.
  std::optional<AhrsSample> update(const BodySample& b);

  const AhrsOptions& options() const { return options_; }

 private:
  AhrsOptions options_;
  ImuSimulator imu_;
  Vec3 earth_W_;
  Rng mag_noise_;
  Quat q_W_S_ = Quat::Identity();
  double dt_s_;
  long updates_ = 0;
};

/// ahrs.csv, one row per reported sample (the columns of a frame table, as frames.csv, so that
/// `driftlab eval --attitude-reference` reads it):
///   t_ns,roll_deg,pitch_deg,yaw_deg
/// ZYX Euler angles of the AHRS frame in magnetic NED (yaw in (-180, 180]).
/// Nothing appears at PATH unless commit() is called.
class AhrsCsvWriter {
 public:
  explicit AhrsCsvWriter(const std::filesystem::path& path);
  /// Appends one sample; stamps must strictly increase and angles be finite (InternalError).
  void write(const AhrsSample& s);
  void commit() { rows_.commit(); }

 private:
  csv_detail::StampedRows rows_;
};

}  // namespace driftlab::sim
