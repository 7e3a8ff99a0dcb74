// GPS acceptance tests. Expectations come from the test's own code: closed-form
// geodesy, its own ray-plane intersections for the obstructing geometry, and its
// own DOP (explicit 4x4 inverse of H^T H, Misra & Enge Sec. 6.1.2).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "sim/sensors/gps.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

namespace fs = std::filesystem;
using driftlab::test::kDeg;
constexpr double kA = 6378137.0;          // WGS84 semi-major axis [m]
constexpr double kB = 6356752.314245179;  // WGS84 semi-minor axis [m], a (1 - f)
constexpr double kE2 = 6.69437999014e-3;  // WGS84 first eccentricity squared

BodySample body_at(const Vec3& p_W, TimeNs t_ns) {
  BodySample b;
  b.t_ns = t_ns;
  b.state.p_W = p_W;
  return b;
}

// HDOP of unit lines of sight (NED) computed here: rows (e, n, u, 1) in ENU,
// Q = (H^T H)^-1 by Eigen's closed-form 4x4 inverse.
double independent_hdop(const std::vector<Vec3>& los_ned) {
  Eigen::MatrixXd H(los_ned.size(), 4);
  for (std::size_t i = 0; i < los_ned.size(); ++i)
    H.row(static_cast<Eigen::Index>(i)) << los_ned[i].y(), los_ned[i].x(), -los_ned[i].z(), 1.0;
  const Eigen::Matrix4d Q = (H.transpose() * H).inverse();
  return std::sqrt(Q(0, 0) + Q(1, 1));
}

TEST(GpsSensor, GeodesyMatchesClosedFormPointsAndRoundTrips) {
  EXPECT_LT((geodetic_to_ecef({0, 0, 0}) - Vec3(kA, 0, 0)).norm(), 1e-9);
  EXPECT_LT((geodetic_to_ecef({90, 0, 0}) - Vec3(0, 0, kB)).norm(), 1e-6);
  EXPECT_LT((geodetic_to_ecef({0, 90, 100}) - Vec3(0, kA + 100, 0)).norm(), 1e-9);
  Rng rng(11);
  for (int i = 0; i < 2000; ++i) {
    const Geodetic g{rng.uniform(-89.999, 89.999), rng.uniform(-179.99, 179.99),
                     rng.uniform(-500, 20000)};
    const Vec3 e = geodetic_to_ecef(g);
    const Geodetic back = ecef_to_geodetic(e);
    EXPECT_LT((geodetic_to_ecef(back) - e).norm(), 1e-8) << i;
    EXPECT_NEAR(back.lat_deg, g.lat_deg, 1e-12) << i;
    EXPECT_NEAR(back.lon_deg, g.lon_deg, 1e-12) << i;
    EXPECT_NEAR(back.height_m, g.height_m, 1e-8) << i;
  }
  // The poles, where p / cos(lat) would be 0 / 0.
  const Geodetic pole = ecef_to_geodetic(Vec3(0, 0, kB + 50));
  EXPECT_NEAR(pole.lat_deg, 90, 1e-12);
  EXPECT_NEAR(pole.height_m, 50, 1e-8);
}

TEST(GpsSensor, LocalTangentPlaneIsTheDatumsNedFrame) {
  const Geodetic datum{52.1357, -0.4665, 20.0};
  const LocalTangentPlane ltp(datum);
  const Geodetic o = ltp.to_geodetic(Vec3::Zero());
  EXPECT_NEAR(o.lat_deg, datum.lat_deg, 1e-12);
  EXPECT_NEAR(o.lon_deg, datum.lon_deg, 1e-12);
  EXPECT_NEAR(o.height_m, datum.height_m, 1e-8);
  // 1 km north along the plane: latitude grows by 1000 / M (meridian radius of
  // curvature) and the plane rises above the curved ellipsoid by d^2 / (2 M).
  const double s2 = std::pow(std::sin(datum.lat_deg * kDeg), 2);
  const double M = kA * (1 - kE2) / std::pow(1 - kE2 * s2, 1.5);
  const Geodetic n = ltp.to_geodetic(Vec3(1000, 0, 0));
  EXPECT_NEAR((n.lat_deg - datum.lat_deg) * kDeg * (M + datum.height_m), 1000.0, 1e-3);
  EXPECT_NEAR(n.lon_deg, datum.lon_deg, 1e-12);
  EXPECT_NEAR(n.height_m - datum.height_m, 1000.0 * 1000.0 / (2 * M), 2e-3);
  // 5 m down is 5 m lower.
  EXPECT_NEAR(ltp.to_geodetic(Vec3(0, 0, 5)).height_m, datum.height_m - 5, 1e-8);
  // Round trip over a survey-sized area.
  Rng rng(5);
  for (int i = 0; i < 500; ++i) {
    const Vec3 p(rng.uniform(-5000, 5000), rng.uniform(-5000, 5000), rng.uniform(-100, 100));
    EXPECT_LT((ltp.to_ned(ltp.to_geodetic(p)) - p).norm(), 1e-8) << i;
  }
}

TEST(GpsSensor, RayCastsAgainstBoxesAndTriangles) {
  const AxisAlignedBox box{Vec3(5, -1, -3), Vec3(6, 1, 0)};
  EXPECT_NEAR(*ray_box_distance(Vec3::Zero(), Vec3(1, 0, 0), box), 5.0, 1e-15);
  EXPECT_FALSE(ray_box_distance(Vec3::Zero(), Vec3(-1, 0, 0), box));  // behind
  EXPECT_FALSE(ray_box_distance(Vec3::Zero(), Vec3(0, 1, 0), box));
  EXPECT_EQ(*ray_box_distance(Vec3(5.5, 0, -1), Vec3(0, 0, -1), box), 0.0);  // inside
  const Triangle tri{Vec3(0, -1, -10), Vec3(0, 1, -10), Vec3(2, 0, -10)};
  EXPECT_NEAR(*ray_triangle_distance(Vec3(0.5, 0, 0), Vec3(0, 0, -1), tri), 10.0, 1e-12);
  EXPECT_FALSE(ray_triangle_distance(Vec3(0.5, 0, 0), Vec3(0, 0, 1), tri));
  EXPECT_FALSE(ray_triangle_distance(Vec3(5, 0, 0), Vec3(0, 0, -1), tri));
  PrimitiveObstruction scene;
  scene.add_triangle(tri.a, tri.b, tri.c);
  EXPECT_TRUE(scene.blocked(Vec3(0.5, 0, 0), Vec3(0, 0, -1)));
  EXPECT_FALSE(scene.blocked(Vec3(0.5, 0, 0), Vec3(1, 0, 0)));
  EXPECT_THROW(scene.add_box(Vec3(1, 0, 0), Vec3(0, 1, 1)), UserError);
  EXPECT_THROW(scene.add_triangle(Vec3(NAN, 0, 0), Vec3::Zero(), Vec3::Ones()), UserError);
}

TEST(GpsSensor, OpenSkyNeverLosesTheFix) {
  GpsOptions o;
  o.constellation = ConstellationModel::kSphere;  // evenly spread: no orbital holes
  GpsSimulator gps(o, RngStreams(1));
  int outages = 0, min_sats = 100;
  double max_hdop = 0;
  for (int k = 0; k < 3600; ++k) {  // an hour at 1 Hz: the sky turns by 30 deg
    const auto f = gps.measure(body_at(Vec3(10, 20, 0), static_cast<TimeNs>(k) * 1'000'000'000));
    ASSERT_TRUE(f.has_value());
    outages += f->fix ? 0 : 1;
    min_sats = std::min(min_sats, f->satellites);
    max_hdop = std::max(max_hdop, f->hdop);
  }
  std::printf("open sky, 1 h: %d outages, at least %d satellites, HDOP at most %.2f\n", outages,
              min_sats, max_hdop);
  EXPECT_EQ(outages, 0);
  EXPECT_GE(min_sats, 8);
  EXPECT_LT(max_hdop, 2.0);
}

// The orbit model seen from 52 deg N: satellites on 55 deg inclined orbits
// never pass north of 55 deg latitude, so the northern sky below ~85 deg of
// elevation stays empty (a satellite due north at elevation e would sit at a
// latitude 52 + 90 - e - asin(R cos e / a) deg, beyond 55 for every e < 85);
// the southern sky is full. Open sky still keeps a fix with the 31 satellites.
TEST(GpsSensor, OrbitsLeaveTheNorthernHoleAndKeepAFixInOpenSky) {
  GpsOptions o;
  ASSERT_EQ(o.constellation, ConstellationModel::kOrbits);
  GpsSimulator gps(o, RngStreams(1));
  int north = 0, south = 0, min_visible = 100;
  for (int k = 0; k < 24 * 60; ++k) {  // a day, every minute
    const auto dirs = gps.constellation().directions_ned(60.0 * k);
    int visible = 0;
    for (const Vec3& u : dirs) {
      const double el = elevation_rad(u) * 180 / std::numbers::pi;
      const double az = std::atan2(u.y(), u.x()) * 180 / std::numbers::pi;  // from north, east +
      if (el < 10) continue;
      ++visible;
      if (std::abs(az) < 10 && el < 80) ++north;
      if (std::abs(std::abs(az) - 180) < 10 && el < 80) ++south;
    }
    min_visible = std::min(min_visible, visible);
  }
  std::printf(
      "orbits from 52 N, a day: %d sightings due north, %d due south, at least %d above 10 deg\n",
      north, south, min_visible);
  EXPECT_EQ(north, 0);
  EXPECT_GT(south, 100);
  EXPECT_GE(min_visible, 5);
}

TEST(GpsSensor, ReportedHdopMatchesTheVisibleGeometryComputedHere) {
  // A 20 m high wall 5 m east of the antenna, 2 km long: it hides the eastern
  // sky up to atan(19 / 5) = 75 deg of elevation. The antenna is 1 m above the water.
  GpsOptions o;
  o.antenna_frd_m = {0, 0, -1};
  PrimitiveObstruction wall;
  wall.add_box(Vec3(-1000, 5, -20), Vec3(1000, 6, 10));
  GpsSimulator gps(o, RngStreams(9), &wall);
  const Vec3 antenna(0, 0, -1);
  int compared = 0;
  for (int k = 0; k < 600; k += 30) {
    const double t = k;
    const auto f = gps.measure(body_at(Vec3::Zero(), static_cast<TimeNs>(k) * 1'000'000'000));
    ASSERT_TRUE(f.has_value());
    // Visibility decided here: above the 10 deg mask, and the ray either goes
    // west or crosses the wall's face plane (east = 5) above its top.
    std::vector<Vec3> visible;
    int above_mask = 0;
    for (const Vec3& u : gps.constellation().directions_ned(t)) {
      if (-u.z() < std::sin(10 * kDeg)) continue;
      ++above_mask;
      bool blocked = false;
      if (u.y() > 0) {
        const double s = 5.0 / u.y();
        const double down = antenna.z() + s * u.z(), north = antenna.x() + s * u.x();
        blocked = down >= -20 && std::abs(north) <= 1000;
      }
      if (!blocked) visible.push_back(u);
    }
    EXPECT_EQ(f->satellites, static_cast<int>(visible.size())) << "t = " << t;
    EXPECT_LT(f->satellites, above_mask) << "the wall hides none at t = " << t;
    ASSERT_GE(visible.size(), 4u);
    EXPECT_NEAR(f->hdop, independent_hdop(visible), 1e-9 * f->hdop) << "t = " << t;
    // The same sky without the wall has the better geometry.
    std::vector<Vec3> all;
    for (const Vec3& u : gps.constellation().directions_ned(t))
      if (-u.z() >= std::sin(10 * kDeg)) all.push_back(u);
    EXPECT_GT(f->hdop, independent_hdop(all));
    ++compared;
  }
  EXPECT_EQ(compared, 20);
}

TEST(GpsSensor, TotalOutageUnderABridgeDeck) {
  // A 40 m wide road deck across the river (east-west), underside 4 m above
  // the water; the vessel passes under it heading north at 1 m/s. From the
  // middle, the deck edges are atan(3 / 20) = 8.5 deg up: below the 10 deg mask,
  // so no satellite can be seen there.
  GpsOptions o;
  o.rate_hz = 1;
  PrimitiveObstruction bridge;
  bridge.add_box(Vec3(-20, -200, -5), Vec3(20, 200, -4));
  GpsSimulator gps(o, RngStreams(4), &bridge);
  int fixes_far = 0, epochs_far = 0, fixes_under = 0, epochs_under = 0, max_sats_under = 0;
  for (int k = 0; k <= 160; ++k) {
    const double north = -80.0 + k;
    const auto f = gps.measure(body_at(Vec3(north, 0, 0), static_cast<TimeNs>(k) * 1'000'000'000));
    ASSERT_TRUE(f.has_value());
    if (std::abs(north) <= 2) {
      ++epochs_under;
      fixes_under += f->fix;
      max_sats_under = std::max(max_sats_under, f->satellites);
      EXPECT_TRUE(std::isnan(f->hdop));
      EXPECT_TRUE(std::isnan(f->p_W.x()));
    }
    if (std::abs(north) >= 60) {
      ++epochs_far;
      fixes_far += f->fix;
    }
  }
  EXPECT_EQ(fixes_under, 0);
  EXPECT_EQ(max_sats_under, 0);
  EXPECT_EQ(epochs_under, 5);
  EXPECT_EQ(fixes_far, epochs_far);
}

TEST(GpsSensor, NoFixBelowFourSatellitesNorAboveMaxHdop) {
  // Through a narrowing street canyon: walls east and west whose gap shrinks
  // with north, so the visible count falls through 4 to 0.
  GpsOptions o;
  o.constellation_period_s = 0;
  PrimitiveObstruction canyon;
  for (int i = 0; i < 40; ++i) {
    const double gap = 40.0 - i;  // metres between the walls
    canyon.add_box(Vec3(i * 10.0, gap / 2, -30), Vec3(i * 10.0 + 10, gap / 2 + 1, 10));
    canyon.add_box(Vec3(i * 10.0, -gap / 2 - 1, -30), Vec3(i * 10.0 + 10, -gap / 2, 10));
  }
  GpsSimulator gps(o, RngStreams(2), &canyon);
  bool saw_few = false, saw_fix = false;
  for (int k = 0; k < 400; ++k) {
    const auto f =
        gps.measure(body_at(Vec3(k + 0.5, 0, 0), static_cast<TimeNs>(k) * 1'000'000'000));
    ASSERT_TRUE(f.has_value());
    const bool expected = f->satellites >= 4 && std::isfinite(f->hdop) && f->hdop <= o.max_hdop;
    EXPECT_EQ(f->fix, expected) << "north " << k << ", " << f->satellites << " satellites";
    if (f->satellites >= 1 && f->satellites <= 3) {
      saw_few = true;
      EXPECT_FALSE(f->fix);
    }
    saw_fix |= f->fix;
  }
  EXPECT_TRUE(saw_few);
  EXPECT_TRUE(saw_fix);
}

TEST(GpsSensor, ErrorCovarianceIsSigmaSquaredTimesTheDopMatrix) {
  GpsOptions o;
  o.rate_hz = 10;
  o.constellation_period_s = 0;  // fixed sky: one geometry
  o.sigma_horizontal_m = 2.0;
  GpsSimulator gps(o, RngStreams(21));
  const int n = 40000;
  Mat3 S = Mat3::Zero();
  double hdop = 0;
  std::vector<Vec3> los;
  for (int k = 0; k < n; ++k) {
    const auto f = gps.measure(body_at(Vec3(3, 4, 0), static_cast<TimeNs>(k) * 100'000'000));
    ASSERT_TRUE(f && f->fix);
    const Vec3 e = f->p_W - f->p_true_W;
    S += e * e.transpose() / n;
    hdop = f->hdop;
  }
  const auto visible = gps.visible_satellites(Vec3(3, 4, -1), 0.0);
  EXPECT_NEAR(hdop, independent_hdop(visible), 1e-9);
  // Horizontal RMS = sigma * HDOP (the definition of sigma_horizontal_m).
  const double horizontal_rms = std::sqrt(S(0, 0) + S(1, 1));
  std::printf("horizontal RMS %.4f m, sigma * HDOP %.4f m\n", horizontal_rms, 2.0 * hdop);
  EXPECT_NEAR(horizontal_rms / (2.0 * hdop), 1.0, 0.02);
  // Vertical against VDOP from the same independent inverse.
  Eigen::MatrixXd H(visible.size(), 4);
  for (std::size_t i = 0; i < visible.size(); ++i)
    H.row(static_cast<Eigen::Index>(i)) << visible[i].y(), visible[i].x(), -visible[i].z(), 1.0;
  const Eigen::Matrix4d Q = (H.transpose() * H).inverse();
  EXPECT_NEAR(std::sqrt(S(2, 2)) / (2.0 * std::sqrt(Q(2, 2))), 1.0, 0.02);
}

TEST(GpsSensor, LatencyClockOffsetAndCorrelatedError) {
  GpsOptions o;
  o.latency_s = 0.3;
  o.clock.offset_ms = 5;
  o.error_correlation_time_s = 10;
  o.constellation_period_s = 0;
  GpsSimulator gps(o, RngStreams(8));
  std::vector<double> e;
  for (int k = 0; k < 5000; ++k) {
    const TimeNs t = static_cast<TimeNs>(k) * 1'000'000'000;
    const auto f = gps.measure(body_at(Vec3(k * 0.5, 0, 0), t));
    ASSERT_TRUE(f && f->fix);
    EXPECT_EQ(f->t_valid_ns, t);
    EXPECT_EQ(f->t_ns, t + 305'000'000);
    EXPECT_DOUBLE_EQ(f->p_true_W.x(), k * 0.5);
    e.push_back(f->p_W.x() - f->p_true_W.x());
  }
  // First-order Gauss-Markov: lag-1 autocorrelation exp(-dt / T) = exp(-0.1).
  double c0 = 0, c1 = 0;
  for (std::size_t i = 0; i + 1 < e.size(); ++i) {
    c0 += e[i] * e[i];
    c1 += e[i] * e[i + 1];
  }
  EXPECT_NEAR(c1 / c0, std::exp(-0.1), 0.02);
}

TEST(GpsSensor, CsvColumnsAndBadOptions) {
  const fs::path dir = fs::temp_directory_path() / "driftlab_gps_csv_test";
  fs::create_directories(dir);
  GpsFix a;
  a.t_ns = 1'000'000'000;
  a.fix = true;
  a.satellites = 9;
  a.hdop = 0.75;
  a.p_W = Vec3(1.5, -2.25, 0.5);
  a.geodetic = {52.5, -0.25, 19.5};
  GpsFix b;
  b.t_ns = 2'000'000'000;
  b.satellites = 2;
  {
    GpsCsvWriter w(dir / "gps.csv");
    w.write(a);
    w.write(b);
    w.commit();
  }
  std::ifstream in(dir / "gps.csv");
  std::stringstream text;
  text << in.rdbuf();
  EXPECT_EQ(text.str(),
            "#timestamp [ns],fix [0/1],satellites [],hdop [],north [m],east [m],down [m],"
            "latitude [deg],longitude [deg],height [m]\n"
            "1000000000,1,9,0.75,1.5,-2.25,0.5,52.5,-0.25,19.5\n"
            "2000000000,0,2,nan,nan,nan,nan,nan,nan,nan\n");
  fs::remove_all(dir);

  GpsOptions bad;
  bad.rate_hz = 0;
  bad.antenna_frd_m[2] = NAN;
  try {
    GpsSimulator gps(bad, RngStreams(1));
    FAIL() << "expected UserError";
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("sensors.gps.rate_hz: got 0, expected a value in [0.01, 100]"),
              std::string::npos)
        << what;
    EXPECT_NE(what.find("sensors.gps.antenna_frd_m[2]: got nan, expected a finite number"),
              std::string::npos)
        << what;
  }
}

}  // namespace
}  // namespace driftlab::sim
