// The one interface of fusion/'s filters (the NED Kalman and particle filters of the basin
// paper, the error-state Kalman filter, the river paper's constant-acceleration smoother): a
// run feeds each the measurements of its sensors in time order and, at every camera frame, the
// VO result of that frame, and gets back the left camera's pose. Filters see measurements only,
// never ground truth. tests/fusion/filter_test.cpp is one typed test suite over all of them.
#pragma once

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "core/rng.hpp"
#include "core/se3.hpp"
#include "core/time.hpp"
#include "core/trajectory_io.hpp"
#include "fusion/ca_smoother.hpp"
#include "fusion/eskf.hpp"
#include "fusion/measurements.hpp"
#include "fusion/ned_filters.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::fusion {

/// What a filter did so far (MuJoCo's warning counters, reported): each counter by name, in a
/// fixed order, `nonfinite_guards` last; and the guards alone (inputs skipped or states
/// restarted because something was not finite: never expected, so each one is a warning).
struct FilterSummary {
  std::vector<std::pair<std::string, std::int64_t>> counts;
  std::int64_t nonfinite_guards = 0;
  /// The counter called `name`; -1 when the filter has none of that name.
  std::int64_t count(const std::string& name) const;
};

class Filter {
 public:
  virtual ~Filter() = default;

  /// Measurements between frames, each at its own time, in time order, only those up to the
  /// next frame's time before that frame's vo(). A filter without a model of a sensor ignores
  /// its measurements (the NED filters and the smoother take no IMU or GPS).
  virtual void imu(const ImuSample& sample) { (void)sample; }
  virtual void gps(const GpsPositionMeasurement& fix) { (void)fix; }
  virtual void heading(const HeadingMeasurement& heading) { (void)heading; }

  /// The VO result of the camera frame at t_ns (every delivered frame, valid or not, times
  /// increasing): returns the pose of the left camera in the world after this frame. The first
  /// call only starts the filter (it returns the start pose).
  virtual SE3 vo(TimeNs t_ns, const vo::VoResult& result) = 0;

  /// Counters so far.
  virtual FilterSummary summary() const = 0;
  /// The NED filters' state at each frame (the basin paper's tables read it); empty for others.
  virtual std::span<const NedEstimate> ned_states() const { return {}; }
};

/// The basin paper's Kalman filter (Section 3.1.1) on the VO's body velocities and the compass.
/// `T_B_C`: the left camera's optical frame in body FRD. The filter is planar: the poses it
/// returns take north, east and heading from it, and height, roll and pitch from the VO it
/// follows, chained from `T_W_B0` (the body at the first frame).
std::unique_ptr<Filter> make_ned_kalman_filter(const NedFilterOptions& options,
                                               const NedState& initial, const SE3& T_B_C,
                                               const SE3& T_W_B0);
/// The basin paper's particle filter (Section 3.1.2); draws only from `rng`. Poses as the
/// Kalman filter's.
std::unique_ptr<Filter> make_ned_particle_filter(const NedParticleFilterOptions& options, Rng rng,
                                                 const NedState& initial, const SE3& T_B_C,
                                                 const SE3& T_W_B0);
/// The error-state Kalman filter on the IMU, the VO, the GPS and the compass.
std::unique_ptr<Filter> make_eskf(const EskfOptions& options, const EskfExtrinsics& extrinsics,
                                  const EskfState& initial);
/// The river paper's constant-acceleration smoother (forward pass, Eqs. (4)-(5)) on the VO's
/// increments, chained from `T_W_C0`, the left camera's pose at the first frame (Eq. (3)).
std::unique_ptr<Filter> make_ca_smoother(const CaSmootherOptions& options, const SE3& T_W_C0);

}  // namespace driftlab::fusion
