#include "fusion/filter.hpp"

#include <optional>

#include "core/rotation.hpp"

namespace driftlab::fusion {

std::int64_t FilterSummary::count(const std::string& name) const {
  for (const auto& [n, v] : counts)
    if (n == name) return v;
  return -1;
}

namespace {

// The NED filters: one step per frame with the VO's body velocities (basin paper Section 3.1)
// and the latest compass heading since the previous frame. They are planar (north, east,
// heading); the pose they return takes its height, roll and pitch from the VO they follow,
// chained from the anchor, so that the pose is compared with the truth on what the filter
// estimates and a raw VO's own vertical on the rest.
template <class NedFilter>
class NedFilterAdapter final : public Filter {
 public:
  NedFilterAdapter(NedFilter filter, const SE3& T_B_C, const SE3& T_W_B0, bool particles)
      : filter_(std::move(filter)), T_B_C_(T_B_C), T_W_B_vo_(T_W_B0), particles_(particles) {}

  void heading(const HeadingMeasurement& h) override { heading_ = h; }

  SE3 vo(TimeNs t_ns, const vo::VoResult& result) override {
    const double dt = started_ ? static_cast<double>(t_ns - t_prev_ns_) * 1e-9 : 0.0;
    started_ = true;
    t_prev_ns_ = t_ns;
    // body_velocity_from_vo() makes a non-finite increment an invalid measurement; counted
    // here, as every filter counts the non-finite inputs it skips.
    if (result.valid && !(result.T_prev_curr.translation().allFinite() &&
                          result.T_prev_curr.quaternion().coeffs().allFinite()))
      ++nonfinite_inputs_;
    const BodyVelocityMeasurement m = body_velocity_from_vo(t_ns, dt, result, T_B_C_);
    const NedEstimate e = filter_.step(m, heading_);
    heading_.reset();
    states_.push_back(e);
    if (dt > 0 && m.valid)  // the VO's own body pose (river paper Eq. (3)), for its vertical
      T_W_B_vo_ = T_W_B_vo_ * (T_B_C_ * result.T_prev_curr * T_B_C_.inverse());
    const EulerZYX vo_angles = euler_zyx_from_quat(T_W_B_vo_.quaternion());
    const SE3 T_W_B(quat_from_euler_zyx({vo_angles.roll_rad, vo_angles.pitch_rad, e.heading_rad()}),
                    Vec3(e.north_m(), e.east_m(), T_W_B_vo_.translation().z()));
    return T_W_B * T_B_C_;
  }

  FilterSummary summary() const override {
    std::int64_t vo = 0, heading = 0, resampled = 0;
    for (const auto& e : states_) {
      vo += e.vo_fused;
      heading += e.heading_fused;
      resampled += e.resampled;
    }
    FilterSummary s;
    s.nonfinite_guards = filter_.nonfinite_guards() + nonfinite_inputs_;
    s.counts = {{"steps", static_cast<std::int64_t>(states_.size())},
                {"vo_fused", vo},
                {"heading_fused", heading}};
    if (particles_) s.counts.emplace_back("resampled", resampled);
    s.counts.emplace_back("nonfinite_guards", s.nonfinite_guards);
    return s;
  }

  std::span<const NedEstimate> ned_states() const override { return states_; }

 private:
  NedFilter filter_;
  SE3 T_B_C_;
  SE3 T_W_B_vo_;  // the followed VO's body pose, chained from the anchor
  bool particles_;
  bool started_ = false;
  TimeNs t_prev_ns_ = 0;
  std::optional<HeadingMeasurement> heading_;
  std::vector<NedEstimate> states_;
  std::int64_t nonfinite_inputs_ = 0;
};

// The ESKF: every measurement at its time; one taken before the filter's time (before the
// first IMU sample) is left out.
class EskfAdapter final : public Filter {
 public:
  explicit EskfAdapter(Eskf eskf) : eskf_(std::move(eskf)) {}

  void imu(const ImuSample& sample) override { eskf_.propagate(sample); }
  void gps(const GpsPositionMeasurement& fix) override {
    if (fix.t_ns >= eskf_.state().t_ns) eskf_.update_gps(fix);
  }
  void heading(const HeadingMeasurement& h) override {
    if (h.t_ns >= eskf_.state().t_ns) eskf_.update_heading(h);
  }
  SE3 vo(TimeNs t_ns, const vo::VoResult& result) override {
    if (eskf_.state().t_ns <= t_ns) eskf_.update_vo(t_ns, result);
    return eskf_.T_W_C();
  }

  FilterSummary summary() const override {
    const EskfStats& e = eskf_.stats();
    FilterSummary s;
    s.nonfinite_guards = e.nonfinite_guards;
    s.counts = {{"imu_samples", e.imu_samples},
                {"vo_fused", e.vo_fused},
                {"vo_skipped", e.vo_skipped},
                {"vo_gated", e.vo_gated},
                {"gps_fused", e.gps_fused},
                {"gps_gated", e.gps_gated},
                {"heading_fused", e.heading_fused},
                {"heading_gated", e.heading_gated},
                {"nonfinite_guards", e.nonfinite_guards}};
    return s;
  }

 private:
  Eskf eskf_;
};

// The smoother: the smoothed increments chained from the first pose (river paper Eq. (3)).
class CaSmootherAdapter final : public Filter {
 public:
  CaSmootherAdapter(const CaSmootherOptions& options, const SE3& T_W_C0)
      : smoother_(options), T_W_C_(T_W_C0) {}

  SE3 vo(TimeNs t_ns, const vo::VoResult& result) override {
    const SmoothedStep step = smoother_.update(t_ns, result);  // the first starts the clock
    if (started_) T_W_C_ = T_W_C_ * step.T_prev_curr;
    started_ = true;
    return T_W_C_;
  }

  FilterSummary summary() const override {
    FilterSummary s;
    s.nonfinite_guards = smoother_.nonfinite_guards();
    s.counts = {{"nonfinite_guards", s.nonfinite_guards}};
    return s;
  }

 private:
  ConstantAccelerationSmoother smoother_;
  SE3 T_W_C_;
  bool started_ = false;
};

}  // namespace

std::unique_ptr<Filter> make_ned_kalman_filter(const NedFilterOptions& options,
                                               const NedState& initial, const SE3& T_B_C,
                                               const SE3& T_W_B0) {
  return std::make_unique<NedFilterAdapter<NedKalmanFilter>>(NedKalmanFilter(options, initial),
                                                             T_B_C, T_W_B0, false);
}

std::unique_ptr<Filter> make_ned_particle_filter(const NedParticleFilterOptions& options, Rng rng,
                                                 const NedState& initial, const SE3& T_B_C,
                                                 const SE3& T_W_B0) {
  return std::make_unique<NedFilterAdapter<NedParticleFilter>>(
      NedParticleFilter(options, std::move(rng), initial), T_B_C, T_W_B0, true);
}

std::unique_ptr<Filter> make_eskf(const EskfOptions& options, const EskfExtrinsics& extrinsics,
                                  const EskfState& initial) {
  return std::make_unique<EskfAdapter>(Eskf(options, extrinsics, initial));
}

std::unique_ptr<Filter> make_ca_smoother(const CaSmootherOptions& options, const SE3& T_W_C0) {
  return std::make_unique<CaSmootherAdapter>(options, T_W_C0);
}

}  // namespace driftlab::fusion
