#include "sim/sensors/gps.hpp"

#include <fmt/format.h>

#include <Eigen/Cholesky>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "sim/sensors/csv_detail.hpp"

namespace driftlab::sim {
namespace {

// Reciprocal condition number of H^T H below which the geometry counts as
// singular (satellites on one cone: no unique fix).
constexpr double kSingularGeometry = 1e-10;

}  // namespace

Constellation::Constellation(int size, double period_s, double latitude_deg, Rng rng)
    : period_s_(period_s) {
  DRIFTLAB_DEMAND(size >= 1);
  // Uniformly random orientation: a normalised 4-D Gaussian is uniform on the
  // unit quaternions (Shoemake, "Uniform random rotations", Graphics Gems III).
  Eigen::Vector4d g;
  for (int i = 0; i < 4; ++i) g[i] = rng.normal();
  const Quat turn = Quat(g[3], g[0], g[1], g[2]).normalized();
  // Fibonacci lattice: equal-area bands in z, golden-angle steps in longitude.
  const double golden = std::numbers::pi * (3.0 - std::sqrt(5.0));
  for (int i = 0; i < size; ++i) {
    const double z = 1.0 - (2.0 * i + 1.0) / size;
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    const double phi = golden * i;
    base_.push_back(turn * Vec3(r * std::cos(phi), r * std::sin(phi), z));
  }
  const double lat = deg2rad(latitude_deg);
  axis_ned_ = Vec3(std::cos(lat), 0.0, -std::sin(lat));  // north celestial pole at elevation = lat
}

Constellation Constellation::orbits(int size, double period_s, double latitude_deg,
                                    double longitude_deg, Rng rng) {
  DRIFTLAB_DEMAND(size >= 1);
  constexpr int kPlanes = 6;
  constexpr double kInclination = 55.0 * std::numbers::pi / 180.0;
  const double two_pi = 2.0 * std::numbers::pi;
  Constellation c;
  c.period_s_ = period_s;
  // Random orientation of the pattern: node offset, slot offset, Earth angle.
  const double node0 = rng.uniform(0.0, two_pi), u00 = rng.uniform(0.0, two_pi);
  c.earth_angle0_rad_ = rng.uniform(0.0, two_pi);
  for (int k = 0; k < size; ++k) {
    const int plane = k % kPlanes, slot = k / kPlanes;
    const int per_plane = (size - plane + kPlanes - 1) / kPlanes;  // slots in this plane
    Orbit o;
    o.node_rad = node0 + two_pi * plane / kPlanes;
    o.inclination_rad = kInclination;
    o.u0_rad = u00 + two_pi * slot / per_plane + two_pi * plane / size;  // Walker phasing F = 1
    c.orbits_.push_back(o);
  }
  const double lat = deg2rad(latitude_deg), lon = deg2rad(longitude_deg);
  c.receiver_ecef_m_ = kEarthRadius_m * Vec3(std::cos(lat) * std::cos(lon),
                                             std::cos(lat) * std::sin(lon), std::sin(lat));
  // Rows: north, east, down in ECEF.
  c.R_ned_ecef_ << -std::sin(lat) * std::cos(lon), -std::sin(lat) * std::sin(lon), std::cos(lat),
      -std::sin(lon), std::cos(lon), 0.0, -std::cos(lat) * std::cos(lon),
      -std::cos(lat) * std::sin(lon), -std::sin(lat);
  return c;
}

std::vector<Vec3> Constellation::directions_ned(double t_s) const {
  if (!orbits_.empty()) {
    // Circular orbits in the inertial frame, then into the Earth-fixed frame
    // turned by the Earth's rotation since t = 0.
    const double n = period_s_ > 0 ? 2.0 * std::numbers::pi / period_s_ : 0.0;
    // period 0: a fixed sky (satellites and Earth both still).
    const double theta = earth_angle0_rad_ + (period_s_ > 0 ? kEarthSiderealRate_rad_s * t_s : 0.0);
    std::vector<Vec3> out;
    out.reserve(orbits_.size());
    for (const Orbit& o : orbits_) {
      const double u = o.u0_rad + n * t_s;
      const double cu = std::cos(u), su = std::sin(u), cO = std::cos(o.node_rad),
                   sO = std::sin(o.node_rad), ci = std::cos(o.inclination_rad),
                   si = std::sin(o.inclination_rad);
      const Vec3 eci =
          kGpsOrbitRadius_m * Vec3(cO * cu - sO * su * ci, sO * cu + cO * su * ci, su * si);
      const Vec3 ecef(std::cos(theta) * eci.x() + std::sin(theta) * eci.y(),
                      -std::sin(theta) * eci.x() + std::cos(theta) * eci.y(), eci.z());
      out.push_back((R_ned_ecef_ * (ecef - receiver_ecef_m_)).normalized());
    }
    return out;
  }
  if (period_s_ <= 0) return base_;
  // The Earth turns east about the polar axis, so the sky turns west: a
  // negative angle about the axis pointing at the celestial pole.
  const Quat q(Eigen::AngleAxisd(-2.0 * std::numbers::pi * t_s / period_s_, axis_ned_));
  std::vector<Vec3> out;
  out.reserve(base_.size());
  for (const Vec3& u : base_) out.push_back(q * u);
  return out;
}

Dop dilution_of_precision(const std::vector<Vec3>& los_ned) {
  Dop d;
  if (los_ned.size() < 4) return d;
  Eigen::Matrix4d HtH = Eigen::Matrix4d::Zero();
  for (const Vec3& u : los_ned) {
    const Vec3 enu = LocalTangentPlane::ned_to_enu(u);
    const Eigen::Vector4d h(-enu.x(), -enu.y(), -enu.z(), 1.0);
    HtH += h * h.transpose();
  }
  const Eigen::LDLT<Eigen::Matrix4d> ldlt(HtH);
  if (ldlt.info() != Eigen::Success || !(ldlt.rcond() > kSingularGeometry)) return d;
  const Eigen::Matrix4d Q = ldlt.solve(Eigen::Matrix4d::Identity());
  d.valid = true;
  d.hdop = std::sqrt(Q(0, 0) + Q(1, 1));
  d.vdop = std::sqrt(Q(2, 2));
  d.pdop = std::sqrt(Q(0, 0) + Q(1, 1) + Q(2, 2));
  d.tdop = std::sqrt(Q(3, 3));
  d.gdop = std::sqrt(Q.trace());
  // ENU -> NED: N = n, E = e, D = -u.
  Mat3 T;
  T << 0, 1, 0,  //
      1, 0, 0,   //
      0, 0, -1;
  d.position_cov_ned = T * Q.topLeftCorner<3, 3>() * T.transpose();
  return d;
}

GpsSimulator::GpsSimulator(const GpsOptions& options, const RngStreams& rng,
                           const SkyObstruction* sky, std::string name)
    // Validated before any member uses a field (members initialise in order).
    : options_((validate_sensor_options(options, "sensors." + name), options)),
      sky_(sky ? sky : &open_sky_),
      plane_({options.datum_lat_lon_h[0], options.datum_lat_lon_h[1], options.datum_lat_lon_h[2]}),
      constellation_(
          options.constellation == ConstellationModel::kOrbits
              ? Constellation::orbits(options.constellation_size, options.constellation_period_s,
                                      options.datum_lat_lon_h[0], options.datum_lat_lon_h[1],
                                      rng.stream(name + ".constellation"))
              : Constellation(options.constellation_size, options.constellation_period_s,
                              options.datum_lat_lon_h[0], rng.stream(name + ".constellation"))),
      noise_(rng.stream(name + ".noise")),
      clock_(options.clock, rng, name),
      antenna_B_(options.antenna_frd_m[0], options.antenna_frd_m[1], options.antenna_frd_m[2]) {}

std::vector<Vec3> GpsSimulator::visible_satellites(const Vec3& antenna_W, double t_s) const {
  const double mask = deg2rad(options_.elevation_mask_deg);
  std::vector<Vec3> out;
  for (const Vec3& u : constellation_.directions_ned(t_s))
    if (elevation_rad(u) >= mask && !sky_->blocked(antenna_W, u)) out.push_back(u);
  return out;
}

std::optional<GpsFix> GpsSimulator::measure(const BodySample& b) {
  GpsFix f;
  f.t_valid_ns = b.t_ns;
  f.p_true_W = b.state.p_W + b.state.q_W_B * antenna_B_;
  const std::vector<Vec3> los = visible_satellites(f.p_true_W, ns_to_seconds(b.t_ns));
  const Dop dop = dilution_of_precision(los);
  f.satellites = static_cast<int>(los.size());
  f.hdop = dop.hdop;

  // First-order Gauss-Markov in standard-normal units, stationary from the
  // first epoch: x_k = a x_{k-1} + sqrt(1 - a^2) w_k, a = exp(-dt / T).
  Vec3 w;
  for (int i = 0; i < 3; ++i) w[i] = noise_.normal();
  const double tau = options_.error_correlation_time_s;
  const double a = (first_ || tau <= 0) ? 0.0 : std::exp(-1.0 / (options_.rate_hz * tau));
  unit_error_ = a * unit_error_ + std::sqrt(1.0 - a * a) * w;
  first_ = false;

  f.fix = f.satellites >= options_.min_satellites && dop.valid &&
          (options_.max_hdop <= 0 || dop.hdop <= options_.max_hdop);
  if (f.fix) {
    // Error covariance sigma^2 Q: colour the unit error with Q's Cholesky factor.
    const Eigen::LLT<Mat3> llt(dop.position_cov_ned);
    DRIFTLAB_DEMAND_MSG(llt.info() == Eigen::Success, "GPS: DOP covariance not positive definite");
    const Vec3 coloured = llt.matrixL() * unit_error_;
    f.p_W = f.p_true_W + options_.sigma_horizontal_m * coloured;
    f.geodetic = plane_.to_geodetic(f.p_W);
  }
  const SampleTime t = clock_.stamp(b.t_ns + seconds_to_ns(options_.latency_s));
  if (t.dropped) return std::nullopt;
  f.t_ns = t.t_stamp_ns;
  return f;
}

GpsCsvWriter::GpsCsvWriter(const std::filesystem::path& path)
    : rows_(path,
            "#timestamp [ns],fix [0/1],satellites [],hdop [],north [m],east [m],down [m],"
            "latitude [deg],longitude [deg],height [m]\n",
            "GPS") {}

void GpsCsvWriter::write(const GpsFix& f) {
  std::string* line = rows_.begin_row(f.t_ns);
  *line += f.fix ? ",1," : ",0,";
  csv_detail::append_int(line, f.satellites);
  csv_detail::append_double(line, f.hdop);
  const bool fix = f.fix;
  for (int i = 0; i < 3; ++i) csv_detail::append_double(line, fix ? f.p_W[i] : kGpsNaN);
  csv_detail::append_double(line, fix ? f.geodetic.lat_deg : kGpsNaN);
  csv_detail::append_double(line, fix ? f.geodetic.lon_deg : kGpsNaN);
  csv_detail::append_double(line, fix ? f.geodetic.height_m : kGpsNaN);
  rows_.end_row();
}

}  // namespace driftlab::sim
