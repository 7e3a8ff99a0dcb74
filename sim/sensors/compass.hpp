// Synthetic compass / 3-axis magnetometer: the Earth's field (from intensity,
// inclination, declination), local anomalies of steel structures (the river
// paper names steel sheet piling as a source of compass bias), then hard- and
// soft-iron errors of the installation and white noise, in the sensor frame.
// The heading is what a tilt-compensated compass computes from that distorted
// field, levelled with the roll and pitch that `levelling` names (the true ones, the
// apparent gravity of the compass's own accelerometer, or none), with the declination
// applied (so a clean, truly levelled compass reports true heading), plus heading noise
// of sigma_deg.
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "core/time.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/sensors/clock.hpp"
#include "sim/sensors/csv_detail.hpp"
#include "sim/sensors/sensor_options.hpp"

namespace driftlab::sim {

/// The Earth's field in world NED [nT]: horizontal F cos(I) towards the
/// declination, vertical F sin(I) (down for a positive inclination).
Vec3 earth_field_ned_nt(const CompassOptions& options);

/// Sum of the anomalies' perturbations at `p_W` (world NED) [nT]: each one's
/// field_ned_nt scaled by 1 / (1 + (d / decay_length_m)^decay_exponent), with d
/// the distance from p_W to the anomaly's segment.
Vec3 anomaly_field_ned_nt(const std::vector<MagneticAnomalyOptions>& anomalies, const Vec3& p_W);

/// Heading [rad] in (-pi, pi] of the sensor's x axis from a field measured in
/// the sensor frame, levelled with the sensor's roll and pitch (ZYX), plus the
/// declination: atan2(-m_level.y, m_level.x) + declination.
double tilt_compensated_heading_rad(const Vec3& field_S, double roll_rad, double pitch_rad,
                                    double declination_rad);

struct CompassSample {
  TimeNs t_ns = 0;                 // the compass clock's stamp
  double heading_rad = 0.0;        // true heading of the sensor x axis, (-pi, pi]
  Vec3 field_S_nt = Vec3::Zero();  // measured field in the sensor frame [nT]
  double true_heading_rad = 0.0;   // ground truth: yaw of the sensor frame
};

class CompassSimulator {
 public:
  /// Validates `options` (UserError naming `name`.FIELD). Streams:
  /// NAME.field_noise, NAME.heading_noise, NAME.clock.*.
  CompassSimulator(const CompassOptions& options, const RngStreams& rng,
                   std::string name = "compass");

  /// Measures at b.t_ns (call in time order); nullopt when the clock drops it.
  std::optional<CompassSample> measure(const BodySample& b);

  const CompassOptions& options() const { return options_; }
  const SensorMount& mount() const { return mount_; }

 private:
  struct Levelling {
    double roll_rad, pitch_rad;
  };
  /// The roll and pitch that level the field (CompassOptions::levelling); `truth`: the
  /// sensor's true angles.
  Levelling levelling(const BodySample& b, const EulerZYX& truth) const;

  CompassOptions options_;
  SensorMount mount_;
  Vec3 earth_W_;
  Mat3 soft_iron_;
  Vec3 hard_iron_;
  Rng field_noise_, heading_noise_;
  SensorClock clock_;
};

/// compass.csv, one row per reported sample (EuRoC-style header):
///   #timestamp [ns],heading [deg],m_S_x [nT],m_S_y [nT],m_S_z [nT]
/// timestamp: the compass clock's stamp; heading: true heading of the sensor's
/// x axis in [0, 360), clockwise from true north; m_S: measured magnetic field
/// in the sensor frame (FRD at zero mount angles). Nothing appears at PATH
/// unless commit() is called.
class CompassCsvWriter {
 public:
  explicit CompassCsvWriter(const std::filesystem::path& path);
  /// Appends one sample; stamps must strictly increase and values be finite (InternalError).
  void write(const CompassSample& s);
  void commit() { rows_.commit(); }

 private:
  csv_detail::StampedRows rows_;
};

}  // namespace driftlab::sim
