// The filters of a run (pipeline.fusion: ca_smoother, ned_kf, ned_pf, eskf): each follows one
// VO track frame by frame through fusion::Filter, with the compass, IMU and GPS measurements of
// the sensors stage fed in time order. Filters see measurements only, never ground truth; the
// start position is the run's anchor (the true first pose, as for every VO track, so that the
// estimates overlay), the start attitude comes from the sensors.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>

#include "core/rng.hpp"
#include "core/se3.hpp"
#include "fusion/filter.hpp"
#include "pipeline/scenario.hpp"
#include "pipeline/sensor_stage.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::pipeline {

/// What a filter did over a run (MuJoCo's warning counters, reported): the measurements it
/// fused, skipped and gated, and its non-finite guards (inputs skipped or states restarted;
/// never expected, so each one is a warning).
struct FilterCounts {
  std::int64_t nonfinite_guards = 0;
  std::map<std::string, std::int64_t> counts;  // every counter, nonfinite_guards included
};

/// Where the sensors sit on the body frame B (the frame whose pose is the anchor, and the NED
/// filters' vessel body), and the GPS's horizontal error: what a filter knows of the platform.
struct FilterMounts {
  SE3 T_B_C;                          ///< left camera, OpenCV optical frame
  SE3 T_B_I;                          ///< IMU
  Mat3 R_B_M = Mat3::Identity();      ///< compass sensor axes
  Vec3 p_B_antenna_m = Vec3::Zero();  ///< GPS antenna phase centre
  double gps_sigma_horizontal_m = 1.5;
  /// The sensor models' noise, for the filter options left null: the compass heading's standard
  /// deviation [rad], and the IMU's Kalibr parameters (gyroscope noise density and random walk,
  /// accelerometer noise density and random walk). Absent: that sensor is off.
  std::optional<double> compass_noise_rad;
  std::optional<std::array<double, 4>> imu_noise;
};

/// `options` with every null sensor noise of the NED filters and the ESKF filled in from
/// `mounts` (the filters' own built-in values where the sensor is off).
PipelineOptions with_sensor_noise(PipelineOptions options, const FilterMounts& mounts);

/// The mounts of a scenario's sensors (sensors.*.mount, sensors.gps.antenna_frd_m).
FilterMounts filter_mounts(const Scenario& sc);

class FilterTrack {
 public:
  /// `options`: the filters' options (pipeline.ca_smoother, ned_kf, ned_pf, eskf);
  /// `T_W_B0`: the anchor, the body pose at the first frame; `T_W_C0`: the left camera's pose
  /// there (where the smoother's chain starts). The ESKF's heading comes from the first compass
  /// sample, or from the anchor when there is no compass (as its position does).
  FilterTrack(FusionAlgorithm kind, const PipelineOptions& options, const FilterMounts& mounts,
              const SensorData& sensors, const SE3& T_W_B0, const SE3& T_W_C0,
              const RngStreams& rng);
  ~FilterTrack();
  FilterTrack(FilterTrack&&) noexcept;

  /// Frame at t_ns (times increasing) with its VO result, after every measurement up to t_ns;
  /// returns the left camera's pose.
  SE3 step(TimeNs t_ns, const vo::VoResult& vo);
  /// NED filters: writes their per-step state (N, E, u, v, heading) as CSV at `path`.
  void write_states(const std::filesystem::path& path) const;
  bool writes_states() const;
  /// The filter's counters so far.
  FilterCounts counts() const;

 private:
  void feed_until(TimeNs t_ns);

  FusionAlgorithm kind_;
  const SensorData* sensors_;
  std::unique_ptr<fusion::Filter> filter_;
  double gps_sigma_h_ = 1.5;
  std::size_t next_imu_ = 0, next_gps_ = 0, next_compass_ = 0;
};

}  // namespace driftlab::pipeline
