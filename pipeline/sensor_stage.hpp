// The sensors stage of a run: IMU, GPS, compass and AHRS measured from the same ground truth as the
// cameras (sim/sensors), written as imu.csv, gps.csv, compass.csv and ahrs.csv (docs/design.md,
// "Data contract of a run") and kept for the filters. The IMU streams during the physics; GPS and
// compass wait for the scene (the AHRS streams like the IMU) (its meshes hide satellites, its steel
// structures bend the magnetic field), so the body states at their (few) sample times are kept
// until finish().
#pragma once

#include <filesystem>
#include <memory>
#include <optional>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/trajectory_io.hpp"
#include "pipeline/scenario.hpp"
#include "record/run_record.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/render/scene_geometry.hpp"
#include "sim/sensors/ahrs.hpp"
#include "sim/sensors/compass.hpp"
#include "sim/sensors/gps.hpp"
#include "sim/sensors/imu.hpp"

namespace driftlab::pipeline {

/// What the filters read. Measurements only (stamps from each sensor's clock); the GpsFix and
/// CompassSample truth fields are for the evaluation and must not be read by a filter.
struct SensorData {
  std::vector<ImuSample> imu;
  std::vector<sim::GpsFix> gps;
  std::vector<sim::CompassSample> compass;
  std::vector<sim::AhrsSample> ahrs;  ///< the attitude reference (evaluation only, never a filter)
  record::SensorsRecord stats;        ///< per sensor: samples and errors; the GPS's sky statistics
};

class SensorStage {
 public:
  /// Sensors enabled in sc.sensors; CSVs go to `dir` (the run's temporary folder).
  SensorStage(const Scenario& sc, const std::filesystem::path& dir);
  ~SensorStage();

  /// Sample times of every enabled sensor up to end_s, sorted, without duplicates.
  std::vector<TimeNs> sample_times(double end_s) const;
  /// The body at one of sample_times() (call each in time order).
  void on_sample(const sim::BodySample& b);
  /// The IMU's biases at time t_ns: those of the last IMU sample at or before it (the bias
  /// walks once per sample), the first sample's before it; nullopt without an IMU or samples,
  /// and after finish() (which lets the history go).
  std::optional<ImuBias> imu_bias_at(TimeNs t_ns) const;
  /// Measures GPS and compass (scene: sky obstruction and steel anomalies; null: open sky, no
  /// scene anomalies), commits the CSVs and returns everything measured.
  SensorData finish(const sim::SceneGeometry* scene);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace driftlab::pipeline
