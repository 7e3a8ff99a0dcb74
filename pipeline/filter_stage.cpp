#include "pipeline/filter_stage.hpp"

#include <cmath>
#include <optional>
#include <vector>

#include "core/error.hpp"
#include "fusion/eskf.hpp"
#include "fusion/measurements.hpp"
#include "fusion/ned_filters.hpp"
#include "pipeline/run.hpp"
#include "sim/sensors/clock.hpp"

namespace driftlab::pipeline {

struct FilterTrack::Impl {
  FusionAlgorithm kind;
  const SensorData& sensors;
  SE3 T_B_C;
  std::unique_ptr<fusion::NedKalmanFilter> kf;
  std::unique_ptr<fusion::NedParticleFilter> pf;
  std::unique_ptr<fusion::Eskf> eskf;
  std::vector<fusion::NedEstimate> states;
  double gps_sigma_h = 1.5;
  std::size_t next_imu = 0, next_gps = 0, next_compass = 0;
  bool first = true;
  TimeNs t_prev = 0;

  Impl(FusionAlgorithm k, const SensorData& s) : kind(k), sensors(s) {}

  // The latest compass heading stamped at or before t (NED filters: one per step).
  std::optional<fusion::HeadingMeasurement> heading_until(TimeNs t) {
    std::optional<fusion::HeadingMeasurement> h;
    while (next_compass < sensors.compass.size() && sensors.compass[next_compass].t_ns <= t) {
      const auto& c = sensors.compass[next_compass++];
      h = fusion::HeadingMeasurement{c.t_ns, c.heading_rad};
    }
    return h;
  }

  // ESKF: every IMU, compass and GPS measurement up to t, in time order.
  void eskf_until(TimeNs t) {
    for (;;) {
      const TimeNs ti = next_imu < sensors.imu.size() ? sensors.imu[next_imu].t_ns : INT64_MAX;
      const TimeNs tc =
          next_compass < sensors.compass.size() ? sensors.compass[next_compass].t_ns : INT64_MAX;
      const TimeNs tg =
          next_gps < sensors.gps.size() ? sensors.gps[next_gps].t_valid_ns : INT64_MAX;
      const TimeNs tmin = std::min({ti, tc, tg});
      if (tmin > t || tmin == INT64_MAX) return;
      if (ti == tmin) {
        eskf->propagate(sensors.imu[next_imu++]);
      } else if (tc == tmin) {
        const auto& c = sensors.compass[next_compass++];
        if (c.t_ns >= eskf->state().t_ns) eskf->update_heading({c.t_ns, c.heading_rad});
      } else {
        const auto& g = sensors.gps[next_gps++];
        // HDOP scales the horizontal error; GpsFix carries no VDOP: vertical taken as twice it.
        if (g.fix && g.t_valid_ns >= eskf->state().t_ns && std::isfinite(g.hdop))
          eskf->update_gps(fusion::GpsPositionMeasurement::with_sd(
              g.t_valid_ns, g.p_W, gps_sigma_h * g.hdop / std::sqrt(2.0),
              2.0 * gps_sigma_h * g.hdop / std::sqrt(2.0)));
      }
    }
  }
};

FilterTrack::FilterTrack(FusionAlgorithm kind, const Scenario& sc, const SensorData& sensors,
                         const SE3& T_W_B0, const RngStreams& rng)
    : impl_(std::make_unique<Impl>(kind, sensors)) {
  Impl& s = *impl_;
  s.T_B_C = camera_mount_T_B_C(sc.sensors.camera.mount);
  s.gps_sigma_h = sc.sensors.gps.sigma_horizontal_m;
  const std::string who = "pipeline.fusion: " + std::string(yaml::enum_name(kind));
  if (kind == FusionAlgorithm::kNedKf || kind == FusionAlgorithm::kNedPf) {
    if (sensors.compass.empty())
      throw UserError(who + " needs the compass (sensors.compass.enabled: true)");
    fusion::NedState init;
    init.north_m = T_W_B0.translation().x();
    init.east_m = T_W_B0.translation().y();
    init.heading_rad = sensors.compass.front().heading_rad;  // measured, not the truth
    if (kind == FusionAlgorithm::kNedKf)
      s.kf = std::make_unique<fusion::NedKalmanFilter>(sc.pipeline.ned_kf, init);
    else
      s.pf = std::make_unique<fusion::NedParticleFilter>(sc.pipeline.ned_pf,
                                                         rng.stream("fusion.ned_pf"), init);
  } else if (kind == FusionAlgorithm::kEskf) {
    if (sensors.imu.empty()) throw UserError(who + " needs the IMU (sensors.imu.enabled: true)");
    const SE3 T_B_I = sim::SensorMount::from_options(sc.sensors.imu.mount).T_B_S();
    const Mat3 R_B_M = sim::SensorMount::from_options(sc.sensors.compass.mount).R_B_S;
    const auto& a = sc.sensors.gps.antenna_frd_m;
    fusion::EskfExtrinsics ex;
    ex.T_I_C = T_B_I.inverse() * s.T_B_C;
    ex.p_I_antenna_m = T_B_I.inverse() * Vec3(a[0], a[1], a[2]);
    ex.R_I_M = T_B_I.rotation().transpose() * R_B_M;
    const ImuSample& imu0 = sensors.imu.front();
    const double heading0 = sensors.compass.empty() ? 0.0 : sensors.compass.front().heading_rad;
    fusion::EskfState init;
    init.t_ns = imu0.t_ns;
    init.q_W_I = fusion::attitude_from_gravity_and_heading(imu0.accel_m_s2, heading0, ex.R_I_M);
    init.p_W_m = (T_W_B0 * T_B_I).translation();
    s.eskf = std::make_unique<fusion::Eskf>(sc.pipeline.eskf, ex, init);
  } else {
    throw InternalError("FilterTrack: not a multi-sensor filter");
  }
}

FilterTrack::~FilterTrack() = default;
FilterTrack::FilterTrack(FilterTrack&&) noexcept = default;

SE3 FilterTrack::step(TimeNs t_ns, const vo::VoResult& vo) {
  Impl& s = *impl_;
  const double dt = s.first ? 0.0 : static_cast<double>(t_ns - s.t_prev) * 1e-9;
  s.first = false;
  s.t_prev = t_ns;
  if (s.eskf) {
    s.eskf_until(t_ns);
    if (s.eskf->state().t_ns <= t_ns) s.eskf->update_vo(t_ns, vo);
    return s.eskf->T_W_C();
  }
  const auto m = fusion::body_velocity_from_vo(t_ns, dt, vo, s.T_B_C);
  const auto h = s.heading_until(t_ns);
  const fusion::NedEstimate e = s.kf ? s.kf->step(m, h) : s.pf->step(m, h);
  s.states.push_back(e);
  return e.T_W_B() * s.T_B_C;
}

bool FilterTrack::writes_states() const { return !impl_->eskf; }

FilterCounts FilterTrack::counts() const {
  const Impl& s = *impl_;
  FilterCounts c;
  if (s.eskf) {
    const fusion::EskfStats& e = s.eskf->stats();
    c.nonfinite_guards = e.nonfinite_guards;
    c.counts = {{"imu_samples", e.imu_samples},     {"vo_fused", e.vo_fused},
                {"vo_skipped", e.vo_skipped},       {"vo_gated", e.vo_gated},
                {"gps_fused", e.gps_fused},         {"gps_gated", e.gps_gated},
                {"heading_fused", e.heading_fused}, {"heading_gated", e.heading_gated}};
  } else {
    std::int64_t vo = 0, heading = 0, resampled = 0;
    for (const auto& e : s.states) {
      vo += e.vo_fused;
      heading += e.heading_fused;
      resampled += e.resampled;
    }
    c.nonfinite_guards = s.kf ? s.kf->nonfinite_guards() : s.pf->nonfinite_guards();
    c.counts = {{"steps", static_cast<std::int64_t>(s.states.size())},
                {"vo_fused", vo},
                {"heading_fused", heading}};
    if (s.pf) c.counts["resampled"] = resampled;
  }
  c.counts["nonfinite_guards"] = c.nonfinite_guards;
  return c;
}

void FilterTrack::write_states(const std::filesystem::path& path) const {
  fusion::write_ned_csv(path, impl_->states);
}

}  // namespace driftlab::pipeline
