// Synthetic GPS receiver: position fixes of the antenna, degraded by the sky the
// scene leaves open. A synthetic constellation gives satellite directions; a
// satellite counts when it is above the elevation mask and its line of sight
// clears the scene (SkyObstruction). With fewer than min_satellites there is no
// fix; otherwise the error has covariance sigma^2 (H^T H)^-1 of the visible
// geometry, so its horizontal RMS is sigma * HDOP (Misra & Enge, "Global
// Positioning System", 2nd ed., Sec. 6.1.2: DOP from the geometry matrix).
#pragma once

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/atomic_file.hpp"
#include "core/rng.hpp"
#include "core/time.hpp"
#include "sim/physics/vessel/simulator.hpp"
#include "sim/sensors/clock.hpp"
#include "sim/sensors/csv_detail.hpp"
#include "sim/sensors/geodesy.hpp"
#include "sim/sensors/sensor_options.hpp"
#include "sim/sensors/sky.hpp"

namespace driftlab::sim {

inline constexpr double kGpsNaN = std::numeric_limits<double>::quiet_NaN();
inline constexpr double kGpsOrbitRadius_m = 26'559'700.0;  // semi-major axis of GPS orbits
inline constexpr double kEarthRadius_m = 6'371'000.0;      // mean radius (spherical Earth)
inline constexpr double kEarthSiderealRate_rad_s = 7.2921151467e-5;  // WGS84

/// A deterministic synthetic constellation: `size` satellites spread evenly over
/// the whole sky sphere (a Fibonacci lattice, so that no seed leaves a hole),
/// turned by a random rotation from `rng` (the stream NAME.constellation) and
/// then rotating about the Earth's axis with `period_s`, the way the sky turns
/// over a receiver. Not orbits: enough for counts and DOP to vary realistically.
class Constellation {
 public:
  Constellation(int size, double period_s, double latitude_deg, Rng rng);
  /// GPS-like orbits: `size` satellites on circular orbits of radius
  /// kGpsOrbitRadius_m in 6 planes at 55 deg inclination, ascending nodes 60 deg
  /// apart, slots evenly spaced in each plane with a 360 / size deg phase step
  /// between neighbouring planes (a Walker delta constellation size/6/1, the
  /// layout of GPS's nominal 24 slots, ICD-GPS-200 / Spilker 1996), orbital
  /// period `period_s`, the whole pattern turned by random angles from `rng`.
  /// Seen from the receiver at (lat, lon) on a spherical Earth that turns at
  /// the sidereal rate: above 52 deg N no satellite rises near the north
  /// celestial pole, so the northern sky is emptier than the southern.
  static Constellation orbits(int size, double period_s, double latitude_deg, double longitude_deg,
                              Rng rng);

  /// Unit vectors from the receiver towards each satellite at `t_s`, world NED.
  std::vector<Vec3> directions_ned(double t_s) const;
  int size() const { return static_cast<int>(orbits_.empty() ? base_.size() : orbits_.size()); }

 private:
  Constellation() = default;
  std::vector<Vec3> base_;  // directions at t = 0, NED (sphere model)
  Vec3 axis_ned_;           // towards the celestial pole
  double period_s_ = 0;
  // Orbits model: per satellite, the plane's ascending node and inclination
  // and the argument of latitude at t = 0 [rad]; empty for the sphere model.
  struct Orbit {
    double node_rad = 0, inclination_rad = 0, u0_rad = 0;
  };
  std::vector<Orbit> orbits_;
  double earth_angle0_rad_ = 0;
  Vec3 receiver_ecef_m_ = Vec3::Zero();
  Mat3 R_ned_ecef_ = Mat3::Identity();
};

/// Elevation [rad] of a unit direction in NED (positive above the horizon).
inline double elevation_rad(const Vec3& u_ned) {
  return std::asin(std::clamp(-u_ned.z(), -1.0, 1.0));
}

/// Dilution of precision of a set of lines of sight (unit vectors, NED).
struct Dop {
  bool valid = false;  // at least 4 satellites and a non-singular geometry
  double gdop = kGpsNaN, pdop = kGpsNaN, hdop = kGpsNaN, vdop = kGpsNaN, tdop = kGpsNaN;
  Mat3 position_cov_ned = Mat3::Constant(kGpsNaN);  // position block of (H^T H)^-1, NED axes
};

/// DOP from the geometry matrix H with rows [-e, -n, -u, 1] (local ENU unit
/// vectors towards the satellites): Q = (H^T H)^-1, HDOP = sqrt(Q_ee + Q_nn),
/// VDOP = sqrt(Q_uu), PDOP, TDOP = sqrt(Q_tt), GDOP = sqrt(trace Q).
Dop dilution_of_precision(const std::vector<Vec3>& los_ned);

/// One epoch of the receiver.
struct GpsFix {
  TimeNs t_ns = 0;        // stamp: t_valid + latency, then the receiver clock's offset and jitter
  TimeNs t_valid_ns = 0;  // the instant the position describes
  bool fix = false;
  int satellites = 0;     // visible: above the mask and unobstructed
  double hdop = kGpsNaN;  // of the visible set; NaN with fewer than 4 or a singular geometry
  Vec3 p_W = Vec3::Constant(kGpsNaN);  // reported antenna position, world NED [m]; NaN without fix
  Geodetic geodetic{kGpsNaN, kGpsNaN, kGpsNaN};  // the same on WGS84; NaN without fix
  Vec3 p_true_W = Vec3::Zero();                  // true antenna position (ground truth)
};

class GpsSimulator {
 public:
  /// Validates `options` (UserError naming `name`.FIELD). `sky` (not owned, may
  /// be null for an open sky) must outlive the simulator. Streams:
  /// NAME.constellation, NAME.noise, NAME.clock.*.
  GpsSimulator(const GpsOptions& options, const RngStreams& rng,
               const SkyObstruction* sky = nullptr, std::string name = "gps");

  /// The epoch whose position is valid at b.t_ns (call in time order, once per
  /// fix time); nullopt when the clock drops it. The error process advances on
  /// every call, dropped or without fix, so its draws do not depend on the sky.
  std::optional<GpsFix> measure(const BodySample& b);

  /// Lines of sight (unit, NED) of the satellites usable from `antenna_W` at `t_s`.
  std::vector<Vec3> visible_satellites(const Vec3& antenna_W, double t_s) const;

  const Constellation& constellation() const { return constellation_; }
  const LocalTangentPlane& plane() const { return plane_; }
  const GpsOptions& options() const { return options_; }

 private:
  GpsOptions options_;
  const SkyObstruction* sky_;
  OpenSky open_sky_;
  LocalTangentPlane plane_;
  Constellation constellation_;
  Rng noise_;
  SensorClock clock_;
  Vec3 antenna_B_;
  Vec3 unit_error_ = Vec3::Zero();  // standard-normal error state (Gauss-Markov)
  bool first_ = true;
};

/// gps.csv, one row per reported epoch (EuRoC-style header, units in brackets):
///   #timestamp [ns],fix [0/1],satellites [],hdop [],north [m],east [m],down [m],
///   latitude [deg],longitude [deg],height [m]
/// timestamp: the receiver's stamp (the position is valid latency_s earlier);
/// satellites: visible count; hdop: of the visible set (nan below 4);
/// north/east/down: antenna position in the world NED frame; latitude/longitude:
/// WGS84 [deg]; height: above the WGS84 ellipsoid. Without a fix (fix 0) the
/// position columns are nan. Nothing appears at PATH unless commit() is called.
class GpsCsvWriter {
 public:
  explicit GpsCsvWriter(const std::filesystem::path& path);
  /// Appends one epoch; stamps must strictly increase (InternalError).
  void write(const GpsFix& fix);
  void commit() { rows_.commit(); }

 private:
  csv_detail::StampedRows rows_;
};

}  // namespace driftlab::sim
