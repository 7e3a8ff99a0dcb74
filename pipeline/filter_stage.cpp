#include "pipeline/filter_stage.hpp"

#include <cmath>
#include <optional>
#include <vector>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "core/yaml_io.hpp"
#include "fusion/eskf.hpp"
#include "fusion/measurements.hpp"
#include "fusion/ned_filters.hpp"
#include "pipeline/run.hpp"
#include "sim/sensors/clock.hpp"

namespace driftlab::pipeline {

namespace {

std::unique_ptr<fusion::Filter> make_ned_filter(FusionAlgorithm kind, const PipelineOptions& p,
                                                const FilterMounts& mounts,
                                                const SensorData& sensors, const SE3& T_W_B0,
                                                const RngStreams& rng, const std::string& who) {
  if (sensors.compass.empty())
    throw UserError(who + " needs the compass (sensors.compass.enabled: true)");
  fusion::NedState init;
  init.north_m = T_W_B0.translation().x();
  init.east_m = T_W_B0.translation().y();
  init.heading_rad = sensors.compass.front().heading_rad;  // measured, not the truth
  if (kind == FusionAlgorithm::kNedKf)
    return fusion::make_ned_kalman_filter(p.ned_kf, init, mounts.T_B_C, T_W_B0);
  return fusion::make_ned_particle_filter(p.ned_pf, rng.stream("fusion.ned_pf"), init, mounts.T_B_C,
                                          T_W_B0);
}

std::unique_ptr<fusion::Filter> make_eskf_filter(const PipelineOptions& p,
                                                 const FilterMounts& mounts,
                                                 const SensorData& sensors, const SE3& T_W_B0,
                                                 const std::string& who) {
  if (sensors.imu.empty()) throw UserError(who + " needs the IMU (sensors.imu.enabled: true)");
  const SE3& T_B_I = mounts.T_B_I;
  fusion::EskfExtrinsics ex;
  ex.T_I_C = T_B_I.inverse() * mounts.T_B_C;
  ex.p_I_antenna_m = T_B_I.inverse() * mounts.p_B_antenna_m;
  ex.R_I_M = T_B_I.rotation().transpose() * mounts.R_B_M;
  const ImuSample& imu0 = sensors.imu.front();
  const SE3 T_W_I0 = T_W_B0 * T_B_I;
  // Without a compass, the heading of the compass frame's x axis at the anchor.
  const Vec3 x_M = T_W_I0.rotation() * ex.R_I_M.col(0);
  const double heading0 =
      sensors.compass.empty() ? std::atan2(x_M.y(), x_M.x()) : sensors.compass.front().heading_rad;
  fusion::EskfState init;
  init.t_ns = imu0.t_ns;
  init.q_W_I = fusion::attitude_from_gravity_and_heading(imu0.accel_m_s2, heading0, ex.R_I_M);
  init.p_W_m = T_W_I0.translation();
  return fusion::make_eskf(p.eskf, ex, init);
}

}  // namespace

// The compass heading's noise from its model: the heading noise it adds (sigma_deg) and the
// field noise on the horizontal field, through which the heading is computed. Magnetic
// anomalies (steel structures) are slowly varying errors a white-noise model cannot describe and
// are left out.
double compass_heading_noise_rad(const sim::CompassOptions& c) {
  const double horizontal_nt = c.field_intensity_nt * std::cos(deg2rad(c.inclination_deg));
  const double field = horizontal_nt > 0 ? c.field_noise_nt / horizontal_nt : 0.0;
  const double sigma = deg2rad(c.sigma_deg);
  return std::sqrt(sigma * sigma + field * field);
}

PipelineOptions with_sensor_noise(PipelineOptions p, const FilterMounts& m) {
  const double compass =
      m.compass_noise_rad.value_or(*fusion::NedFilterOptions{}.compass_noise_rad);
  for (std::optional<double>* c :
       {&p.ned_kf.compass_noise_rad, &p.ned_pf.compass_noise_rad, &p.eskf.compass_noise_rad})
    if (!*c) *c = compass;
  const fusion::EskfOptions built_in;
  const std::array<double, 4> imu = m.imu_noise.value_or(std::array<double, 4>{
      *built_in.gyro_noise_density_rad_s_sqrt_hz, *built_in.gyro_random_walk_rad_s2_sqrt_hz,
      *built_in.accel_noise_density_m_s2_sqrt_hz, *built_in.accel_random_walk_m_s3_sqrt_hz});
  std::optional<double>* fields[] = {
      &p.eskf.gyro_noise_density_rad_s_sqrt_hz, &p.eskf.gyro_random_walk_rad_s2_sqrt_hz,
      &p.eskf.accel_noise_density_m_s2_sqrt_hz, &p.eskf.accel_random_walk_m_s3_sqrt_hz};
  for (std::size_t i = 0; i < 4; ++i)
    if (!*fields[i]) *fields[i] = imu[i];
  return p;
}

FilterMounts filter_mounts(const Scenario& sc) {
  FilterMounts m;
  const auto& s = sc.sensors;
  if (s.compass.enabled) m.compass_noise_rad = compass_heading_noise_rad(s.compass);
  if (s.imu.enabled)
    m.imu_noise = {s.imu.gyro_noise_density_rad_s_sqrt_hz, s.imu.gyro_random_walk_rad_s2_sqrt_hz,
                   s.imu.accel_noise_density_m_s2_sqrt_hz, s.imu.accel_random_walk_m_s3_sqrt_hz};
  m.T_B_C = camera_mount_T_B_C(sc.sensors.camera.mount);
  m.T_B_I = sim::SensorMount::from_options(sc.sensors.imu.mount).T_B_S();
  m.R_B_M = sim::SensorMount::from_options(sc.sensors.compass.mount).R_B_S;
  const auto& a = sc.sensors.gps.antenna_frd_m;
  m.p_B_antenna_m = Vec3(a[0], a[1], a[2]);
  m.gps_sigma_horizontal_m = sc.sensors.gps.sigma_horizontal_m;
  return m;
}

FilterTrack::FilterTrack(FusionAlgorithm kind, const PipelineOptions& pipeline,
                         const FilterMounts& mounts, const SensorData& sensors, const SE3& T_W_B0,
                         const SE3& T_W_C0, const RngStreams& rng)
    : kind_(kind), sensors_(&sensors), gps_sigma_h_(mounts.gps_sigma_horizontal_m) {
  const std::string who = "pipeline.fusion: " + std::string(yaml::enum_name(kind));
  const PipelineOptions options = with_sensor_noise(pipeline, mounts);
  switch (kind) {
    case FusionAlgorithm::kCaSmoother:
      filter_ = fusion::make_ca_smoother(options.ca_smoother, T_W_C0);
      break;
    case FusionAlgorithm::kNedKf:
    case FusionAlgorithm::kNedPf:
      filter_ = make_ned_filter(kind, options, mounts, sensors, T_W_B0, rng, who);
      break;
    case FusionAlgorithm::kEskf:
      filter_ = make_eskf_filter(options, mounts, sensors, T_W_B0, who);
      break;
  }
  DRIFTLAB_DEMAND_MSG(filter_ != nullptr, "FilterTrack: a fusion algorithm without a filter");
}

FilterTrack::~FilterTrack() = default;
FilterTrack::FilterTrack(FilterTrack&&) noexcept = default;

// Every IMU, compass and GPS measurement up to t, in time order (IMU first on a tie, then the
// compass, then GPS).
void FilterTrack::feed_until(TimeNs t) {
  const SensorData& in = *sensors_;
  for (;;) {
    const TimeNs ti = next_imu_ < in.imu.size() ? in.imu[next_imu_].t_ns : INT64_MAX;
    const TimeNs tc =
        next_compass_ < in.compass.size() ? in.compass[next_compass_].t_ns : INT64_MAX;
    const TimeNs tg = next_gps_ < in.gps.size() ? in.gps[next_gps_].t_valid_ns : INT64_MAX;
    const TimeNs tmin = std::min({ti, tc, tg});
    if (tmin > t || tmin == INT64_MAX) return;
    if (ti == tmin) {
      filter_->imu(in.imu[next_imu_++]);
    } else if (tc == tmin) {
      const auto& c = in.compass[next_compass_++];
      filter_->heading({c.t_ns, c.heading_rad});
    } else {
      const auto& g = in.gps[next_gps_++];
      // HDOP scales the horizontal error; GpsFix carries no VDOP: vertical taken as twice it.
      if (g.fix && std::isfinite(g.hdop))
        filter_->gps(fusion::GpsPositionMeasurement::with_sd(
            g.t_valid_ns, g.p_W, gps_sigma_h_ * g.hdop / std::sqrt(2.0),
            2.0 * gps_sigma_h_ * g.hdop / std::sqrt(2.0)));
    }
  }
}

SE3 FilterTrack::step(TimeNs t_ns, const vo::VoResult& vo) {
  feed_until(t_ns);
  return filter_->vo(t_ns, vo);
}

bool FilterTrack::writes_states() const {
  return kind_ == FusionAlgorithm::kNedKf || kind_ == FusionAlgorithm::kNedPf;
}

FilterCounts FilterTrack::counts() const {
  const fusion::FilterSummary s = filter_->summary();
  FilterCounts c;
  c.nonfinite_guards = s.nonfinite_guards;
  for (const auto& [name, value] : s.counts) c.counts[name] = value;
  return c;
}

void FilterTrack::write_states(const std::filesystem::path& path) const {
  const auto states = filter_->ned_states();
  fusion::write_ned_csv(path, states);
}

}  // namespace driftlab::pipeline
