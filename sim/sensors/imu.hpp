// Synthetic IMU: angular rate and specific force of the IMU frame S at its
// mount, from the exact body kinematics, with Kalibr's error model.
//
// Frames: world NED treated as inertial (flat, non-rotating Earth: the vessel
// model integrates in it, so Earth rate and transport rate are absent from the
// truth and from the IMU alike); gravity g_W = (0, 0, +kGravity_m_s2).
// Specific force f = a - g: at rest and level the accelerometer reads
// (0, 0, -9.80665) m/s^2 in FRD.
//
// Error model per triad (Kalibr wiki "IMU Noise Model"; the turn-on bias, scale
// factor and misalignment as in its "IMU Noise Model and Intrinsics"):
//   y_k = clip( M (true_k) + b_k + sigma / sqrt(dt) * n_k , +-range )
//   b_k = b_{k-1} + sigma_b * sqrt(dt) * w_k,  b_0 ~ N(0, turn_on^2)
//   M   = I + diag(scale) + off-diagonal misalignment, drawn once at switch-on
// with dt = 1 / rate_hz. Each source draws from its own named stream
// (NAME.gyro.noise, NAME.gyro.bias_walk, NAME.gyro.turn_on, NAME.gyro.intrinsics,
// and the same for accel), so that changing one source leaves the others' draws.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/rng.hpp"
#include "core/trajectory_io.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/sensors/clock.hpp"
#include "sim/sensors/csv_detail.hpp"
#include "sim/sensors/sensor_options.hpp"

namespace driftlab::sim {

/// Exact angular rate of S in S [rad/s] and specific force at the mount point
/// in S [m/s^2], stamped b.t_ns. The inertial acceleration of the mount point,
/// in body axes, is the CG's v_dot_B + w_B x v_B (transport theorem) plus the
/// lever-arm terms w_dot_B x r + w_B x (w_B x r).
ImuSample ideal_imu(const BodySample& b, const SensorMount& mount);

/// Errors of one triad at the current sample (ground truth for estimators).
struct ImuTriadState {
  Vec3 bias = Vec3::Zero();   // current bias [rad/s or m/s^2]
  Mat3 M = Mat3::Identity();  // scale and misalignment matrix, fixed at switch-on
};

class ImuSimulator {
 public:
  /// Validates `options` (UserError naming `name`.FIELD) and draws the switch-on
  /// errors. `name` prefixes the random streams and messages ("imu").
  ImuSimulator(const ImuOptions& options, const RngStreams& rng, std::string name = "imu");

  /// Measures the body sample `b` (call once per IMU time, in order: the bias
  /// walks one step of 1 / rate_hz per call). The sample's stamp comes from
  /// the IMU's clock; nullopt when the clock drops it (the noise still advances).
  std::optional<ImuSample> measure(const BodySample& b);

  const SensorMount& mount() const { return mount_; }
  const ImuOptions& options() const { return options_; }
  /// Bias and intrinsics that produced the last measurement.
  const ImuTriadState& gyro() const { return gyro_.state; }
  const ImuTriadState& accel() const { return accel_.state; }

 private:
  struct Triad {
    ImuTriadOptions o;
    ImuTriadState state;
    Rng noise, walk;
    Triad(const ImuTriadOptions& options, const RngStreams& rng, const std::string& prefix);
    Vec3 apply(const Vec3& truth, double dt, bool first);
  };

  ImuOptions options_;
  SensorMount mount_;
  double dt_s_;
  Triad gyro_, accel_;
  SensorClock clock_;
  bool first_ = true;
};

/// imu.csv, EuRoC/ASL columns (same as write_euroc_imu()), written as the run streams:
///   #timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],
///   a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]
/// timestamp: the IMU clock's stamp; w: angular rate of S in S; a: specific force in S.
/// Nothing appears at PATH unless commit() is called (AtomicFile).
class ImuCsvWriter {
 public:
  explicit ImuCsvWriter(const std::filesystem::path& path);
  /// Appends one row; stamps must strictly increase and values be finite (InternalError).
  void write(const ImuSample& s);
  void commit() { rows_.commit(); }

 private:
  csv_detail::StampedRows rows_;
};

}  // namespace driftlab::sim
