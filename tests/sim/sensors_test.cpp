// Sensor options (strict YAML, presets, clear errors), the IMU's switch-on
// errors, saturation and streams, the compass, sensor clocks, the CSV writers
// and byte-for-byte determinism. The IMU's strapdown and Allan acceptance tests
// are in imu_sensor_test.cpp, GPS in gps_sensor_test.cpp, camera effects in
// camera_sensor_test.cpp.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "sim/sensors/compass.hpp"
#include "sim/sensors/gps.hpp"
#include "sim/sensors/imu.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

using test::slurp;

namespace fs = std::filesystem;
using driftlab::test::kDeg;
constexpr double kSensorsG = 9.80665;

// Reads `text` as the `sensors` section; returns "" or the UserError message.
std::string read_error(const std::string& text, SensorOptions* out = nullptr) {
  SensorOptions o;
  try {
    yaml::read_into(yaml::load_string(text, "sensors.yaml"), {"sensors.yaml", true}, &o);
  } catch (const UserError& e) {
    return e.what();
  }
  if (out) *out = o;
  return "";
}

std::string user_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const UserError& e) {
    return e.what();
  }
  return "";
}

BodySample pose(double roll, double pitch, double yaw, const Vec3& p = Vec3::Zero(),
                TimeNs t_ns = 0) {
  BodySample b;
  b.t_ns = t_ns;
  b.state.p_W = p;
  b.state.q_W_B = quat_from_euler_zyx({roll, pitch, yaw});
  return b;
}

// --- Options -------------------------------------------------------------

TEST(SensorOptions, DefaultsAreValidAndRoundTripThroughYaml) {
  const SensorOptions defaults;
  EXPECT_EQ(yaml::validate(defaults), "");
  SensorOptions back;
  ASSERT_EQ(read_error(yaml::to_yaml(defaults), &back), "");
  EXPECT_EQ(yaml::to_yaml(back), yaml::to_yaml(defaults));
  // Every field has a doc string (the scenario reference needs them).
  for (const auto& row : yaml::schema_of(defaults)) EXPECT_FALSE(row.doc.empty()) << row.key_path;
}

TEST(SensorOptions, ImuPresetSetsTheNoiseFieldsAndLaterKeysOverride) {
  // The in-class defaults are the mpu9250 preset, field for field.
  EXPECT_EQ(yaml::to_yaml(ImuOptions{}),
            yaml::to_yaml(ImuOptions::preset_defaults(ImuPreset::kMpu9250)));
  const ImuOptions mpu;
  EXPECT_DOUBLE_EQ(mpu.gyro_noise_density_rad_s_sqrt_hz, 0.01 * kDeg);         // datasheet
  EXPECT_DOUBLE_EQ(mpu.accel_noise_density_m_s2_sqrt_hz, 300e-6 * kSensorsG);  // datasheet
  SensorOptions o;
  ASSERT_EQ(read_error("imu: {preset: adis16448, rate_hz: 200}\n", &o), "");
  EXPECT_DOUBLE_EQ(o.imu.gyro_noise_density_rad_s_sqrt_hz, 1.6968e-4);  // EuRoC sensor.yaml
  EXPECT_DOUBLE_EQ(o.imu.gyro_random_walk_rad_s2_sqrt_hz, 1.9393e-5);
  EXPECT_DOUBLE_EQ(o.imu.accel_noise_density_m_s2_sqrt_hz, 2.0e-3);
  EXPECT_DOUBLE_EQ(o.imu.accel_random_walk_m_s3_sqrt_hz, 3.0e-3);
  EXPECT_DOUBLE_EQ(o.imu.rate_hz, 200);
  ASSERT_EQ(read_error("imu: {preset: adis16448, gyro_turn_on_bias_rad_s: 0.01}\n", &o), "");
  EXPECT_DOUBLE_EQ(o.imu.gyro_turn_on_bias_rad_s, 0.01);
  EXPECT_DOUBLE_EQ(o.imu.gyro_noise_density_rad_s_sqrt_hz, 1.6968e-4);
  ASSERT_EQ(read_error("imu: {preset: ideal, rate_hz: 100}\n", &o), "");
  EXPECT_EQ(o.imu.gyro_noise_density_rad_s_sqrt_hz, 0.0);
  EXPECT_EQ(o.imu.accel_range_m_s2, 0.0);
  EXPECT_DOUBLE_EQ(o.imu.rate_hz, 100);
}

TEST(SensorOptions, BadValuesNameFileLineKeyAndExpectation) {
  const std::string neg = read_error("imu:\n  gyro_noise_density_rad_s_sqrt_hz: -1e-4\n");
  EXPECT_NE(neg.find("sensors.yaml:2:37: imu.gyro_noise_density_rad_s_sqrt_hz: got -1e-04, "
                     "expected a value in [0, 1] (1000 x a consumer MEMS gyro)"),
            std::string::npos)
      << neg;
  const std::string rate = read_error("imu: {rate_hz: 0}\n");
  EXPECT_NE(rate.find("imu.rate_hz: got 0, expected a value in [1, 10000]"), std::string::npos)
      << rate;
  const std::string nan = read_error("imu:\n  mount: {position_frd_m: [0.1, .nan, 0]}\n");
  EXPECT_NE(nan.find("imu.mount.position_frd_m[1]: got '.nan', expected a finite number"),
            std::string::npos)
      << nan;
  const std::string unknown = read_error("compass: {sigma_degs: 1}\n");
  EXPECT_NE(unknown.find("compass.sigma_degs: unknown key (did you mean 'compass.sigma_deg'?)"),
            std::string::npos)
      << unknown;
  const std::string jitter = read_error("gps: {rate_hz: 10, clock: {jitter_ms: 20}}\n");
  EXPECT_NE(jitter.find("gps.clock: got the value given, expected a jitter_ms below one sixth"),
            std::string::npos)
      << jitter;
  const std::string sats = read_error("gps: {min_satellites: 3}\n");
  EXPECT_NE(sats.find("gps.min_satellites: got 3, expected a value in [4, 64]"), std::string::npos)
      << sats;
}

TEST(SensorOptions, SimulatorsRejectBadOptionsBuiltInCode) {
  ImuOptions imu;
  imu.gyro_noise_density_rad_s_sqrt_hz = -1;
  imu.rate_hz = 0;
  imu.mount.position_frd_m[0] = std::nan("");
  const std::string e = user_error_of([&] { ImuSimulator s(imu, RngStreams(1)); });
  EXPECT_NE(e.find("sensors.imu: invalid options:"), std::string::npos) << e;
  EXPECT_NE(e.find("sensors.imu.gyro_noise_density_rad_s_sqrt_hz: got -1, expected a value in [0, "
                   "1] (1000 x a consumer MEMS gyro)"),
            std::string::npos)
      << e;
  EXPECT_NE(e.find("sensors.imu.rate_hz: got 0, expected a value in [1, 10000]"), std::string::npos)
      << e;
  EXPECT_NE(e.find("sensors.imu.mount.position_frd_m[0]: got nan, expected a finite number"),
            std::string::npos)
      << e;
  CompassOptions compass;
  compass.anomalies.push_back({});
  compass.anomalies[0].decay_length_m = 0;
  const std::string c = user_error_of([&] { CompassSimulator s(compass, RngStreams(1)); });
  EXPECT_NE(c.find("sensors.compass.anomalies[0].decay_length_m: got 0, expected a value in (0, "
                   "10000] (10 km: no local anomaly)"),
            std::string::npos)
      << c;
}

// --- IMU error model ----------------------------------------------------------

TEST(ImuErrors, TurnOnBiasScaleAndMisalignmentAreFixedAndApplied) {
  ImuOptions o = ImuOptions::preset_defaults(ImuPreset::kIdeal);
  o.gyro_turn_on_bias_rad_s = 0.01;
  o.gyro_scale_factor_ppm = 5000;
  o.gyro_misalignment_mrad = 3;
  o.accel_turn_on_bias_m_s2 = 0.05;
  o.accel_scale_factor_ppm = 2000;
  o.accel_misalignment_mrad = 1;
  ImuSimulator imu(o, RngStreams(17));
  const Mat3 Mg = imu.gyro().M, Ma = imu.accel().M;
  const Vec3 bg = imu.gyro().bias, ba = imu.accel().bias;
  EXPECT_GT((Mg - Mat3::Identity()).norm(), 1e-4);
  EXPECT_GT(bg.norm(), 1e-4);
  Rng rng(2);
  for (int k = 0; k < 50; ++k) {
    BodySample b = pose(rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), rng.uniform(-3, 3));
    b.t_ns = TimeNs{k} * 5'000'000;
    b.state.w_B = Vec3(rng.normal(), rng.normal(), rng.normal());
    b.v_dot_B = Vec3(rng.normal(), rng.normal(), rng.normal());
    const ImuSample truth = ideal_imu(b, imu.mount());
    const auto s = imu.measure(b);
    ASSERT_TRUE(s);
    // No white noise and no random walk: exactly M * truth + b, every sample.
    EXPECT_LT((s->gyro_rad_s - (Mg * truth.gyro_rad_s + bg)).norm(), 1e-12);
    EXPECT_LT((s->accel_m_s2 - (Ma * truth.accel_m_s2 + ba)).norm(), 1e-12);
  }
  EXPECT_EQ(imu.gyro().bias, bg);
  EXPECT_EQ(imu.gyro().M, Mg);
  // The draws have the configured spread: over many switch-ons, the sample
  // standard deviation of bias, scale and misalignment entries.
  double sb = 0, ss = 0, sm = 0;
  const int n = 2000;
  for (int seed = 0; seed < n; ++seed) {
    ImuSimulator u(o, RngStreams(static_cast<std::uint64_t>(seed)));
    sb += u.gyro().bias.squaredNorm() / 3;
    ss += (u.gyro().M.diagonal() - Vec3::Ones()).squaredNorm() / 3;
    sm += (u.gyro().M.squaredNorm() - u.gyro().M.diagonal().squaredNorm()) / 6;
  }
  EXPECT_NEAR(std::sqrt(sb / n) / 0.01, 1.0, 0.03);
  EXPECT_NEAR(std::sqrt(ss / n) / 5000e-6, 1.0, 0.03);
  EXPECT_NEAR(std::sqrt(sm / n) / 3e-3, 1.0, 0.03);
}

TEST(ImuErrors, OutputsSaturateAtTheRange) {
  ImuOptions o = ImuOptions::preset_defaults(ImuPreset::kIdeal);
  o.gyro_range_rad_s = 1.0;
  o.accel_range_m_s2 = 2 * kSensorsG;
  ImuSimulator imu(o, RngStreams(1));
  BodySample b;
  b.state.w_B = Vec3(3.0, -0.5, -7.0);
  b.v_dot_B = Vec3(40.0, 0.0, 0.0);  // 4 g surge (a slam)
  const auto s = imu.measure(b);
  EXPECT_EQ(s->gyro_rad_s, Vec3(1.0, -0.5, -1.0));
  EXPECT_EQ(s->accel_m_s2.x(), 2 * kSensorsG);
  EXPECT_NEAR(s->accel_m_s2.z(), -kSensorsG, 1e-12);
}

TEST(ImuErrors, EachNoiseSourceHasItsOwnStream) {
  // Changing the accelerometer's noise leaves the gyro's samples unchanged,
  // and dropping samples leaves the noise of those that remain unchanged.
  auto gyro_run = [](const ImuOptions& o) {
    ImuSimulator imu(o, RngStreams(42));
    std::vector<std::optional<ImuSample>> out;
    for (int k = 0; k < 200; ++k)
      out.push_back(imu.measure(pose(0, 0, 0, Vec3::Zero(), TimeNs{k} * 5'000'000)));
    return out;
  };
  ImuOptions a = ImuOptions::preset_defaults(ImuPreset::kAdis16448);
  a.gyro_turn_on_bias_rad_s = 0.001;
  ImuOptions b = a;
  b.accel_noise_density_m_s2_sqrt_hz *= 3;
  b.accel_turn_on_bias_m_s2 = 0.2;
  ImuOptions c = a;
  c.clock.drop_probability = 0.3;
  const auto ra = gyro_run(a), rb = gyro_run(b), rc = gyro_run(c);
  int dropped = 0;
  for (std::size_t k = 0; k < ra.size(); ++k) {
    EXPECT_EQ(ra[k]->gyro_rad_s, rb[k]->gyro_rad_s);
    EXPECT_NE(ra[k]->accel_m_s2, rb[k]->accel_m_s2);
    if (!rc[k]) {
      ++dropped;
      continue;
    }
    EXPECT_EQ(ra[k]->gyro_rad_s, rc[k]->gyro_rad_s);
    EXPECT_EQ(ra[k]->accel_m_s2, rc[k]->accel_m_s2);
  }
  EXPECT_GT(dropped, 30);
  EXPECT_LT(dropped, 90);
}

// --- Compass ------------------------------------------------------------------

// A compass without noise, at the given declination and a dip of 66 deg.
CompassOptions noise_free_compass(double declination_deg) {
  CompassOptions o;
  o.sigma_deg = 0;
  o.field_noise_nt = 0;
  o.declination_deg = declination_deg;
  o.inclination_deg = 66;
  return o;
}

TEST(CompassSensor, CleanCompassReportsTrueHeadingAtAnyTilt) {
  CompassOptions o = noise_free_compass(7.5);
  o.mount.rpy_deg = {0, 0, 0};
  CompassSimulator compass(o, RngStreams(1));
  Rng rng(3);
  for (int k = 0; k < 500; ++k) {
    const double roll = rng.uniform(-0.5, 0.5), pitch = rng.uniform(-0.5, 0.5),
                 yaw = rng.uniform(-3.1, 3.1);
    const auto s = compass.measure(pose(roll, pitch, yaw, Vec3::Zero(), TimeNs{k} * 100'000'000));
    ASSERT_TRUE(s);
    EXPECT_NEAR(wrap_angle_rad(s->heading_rad - yaw), 0.0, 1e-9) << k;
    EXPECT_NEAR(s->field_S_nt.norm(), 49000.0, 1e-6);
    // The field in the sensor frame is the Earth's, rotated: written out here.
    const double h = 49000 * std::cos(66 * kDeg);
    const Vec3 m_W(h * std::cos(7.5 * kDeg), h * std::sin(7.5 * kDeg), 49000 * std::sin(66 * kDeg));
    const Mat3 R =
        (Eigen::AngleAxisd(yaw, Vec3::UnitZ()) * Eigen::AngleAxisd(pitch, Vec3::UnitY()) *
         Eigen::AngleAxisd(roll, Vec3::UnitX()))
            .toRotationMatrix();
    EXPECT_LT((s->field_S_nt - R.transpose() * m_W).norm(), 1e-8);
  }
}

TEST(CompassSensor, AStrapdownCompassLevelsWithTheApparentGravity) {
  // Level, heading east, accelerating forward at a: the accelerometer's apparent gravity
  // reads a pitch of atan(a / g), and levelling with it turns the vertical field Z into the
  // heading: atan2(H, Z sin(theta)) instead of 90 deg (written out by hand). Levelled with
  // the true attitude, or at rest, the heading is exact; a compass that does not level at all
  // reads the same on a level hull.
  CompassOptions o = noise_free_compass(0);
  BodySample b = pose(0, 0, 90 * kDeg, Vec3::Zero());
  const double a = 0.3;
  b.v_dot_B = Vec3(a, 0, 0);
  const double H = 49000 * std::cos(66 * kDeg), Z = 49000 * std::sin(66 * kDeg);
  const double theta = std::atan(a / kSensorsG);
  o.levelling = CompassLevelling::kAccelerometer;
  EXPECT_NEAR(CompassSimulator(o, RngStreams(1)).measure(b)->heading_rad,
              std::atan2(H, Z * std::sin(theta)), 1e-9);
  EXPECT_LT(std::atan2(H, Z * std::sin(theta)), 89 * kDeg);  // over a degree off
  EXPECT_NEAR(
      CompassSimulator(o, RngStreams(1)).measure(pose(0, 0, 90 * kDeg, Vec3::Zero()))->heading_rad,
      90 * kDeg, 1e-9);
  o.levelling = CompassLevelling::kTrueAttitude;
  EXPECT_NEAR(CompassSimulator(o, RngStreams(1)).measure(b)->heading_rad, 90 * kDeg, 1e-9);
  o.levelling = CompassLevelling::kNone;
  EXPECT_NEAR(CompassSimulator(o, RngStreams(1)).measure(b)->heading_rad, 90 * kDeg, 1e-9);
  // ... but a heeled one reads the vertical field as horizontal: rolled 5 deg, heading north,
  // the sensor's y axis dips and sees Z sin(5 deg).
  const double roll = 5 * kDeg;
  EXPECT_NEAR(
      CompassSimulator(o, RngStreams(1)).measure(pose(roll, 0, 0, Vec3::Zero()))->heading_rad,
      std::atan2(-Z * std::sin(roll), H), 1e-9);
}

TEST(CompassSensor, HardAndSoftIronDistortTheFieldAndTheHeading) {
  CompassOptions o;
  o.sigma_deg = 0;
  o.field_noise_nt = 0;
  o.hard_iron_nt = {2000, -1000, 500};
  o.soft_iron = {1.05, 0.02, 0, 0.02, 0.97, 0, 0, 0, 1.0};
  CompassSimulator compass(o, RngStreams(1));
  const BodySample b = pose(0, 0, 0.8);
  const auto s = compass.measure(b);
  const Mat3 C = (Mat3() << 1.05, 0.02, 0, 0.02, 0.97, 0, 0, 0, 1.0).finished();
  const Vec3 m_S = b.state.q_W_B.conjugate() * earth_field_ned_nt(o);
  EXPECT_LT((s->field_S_nt - (C * m_S + Vec3(2000, -1000, 500))).norm(), 1e-8);
  // Level: the heading is atan2 of the distorted horizontal field, plus declination.
  const Vec3 d = C * m_S + Vec3(2000, -1000, 500);
  EXPECT_NEAR(s->heading_rad, wrap_angle_rad(std::atan2(-d.y(), d.x()) + o.declination_deg * kDeg),
              1e-12);
  EXPECT_GT(std::abs(s->heading_rad - 0.8), 1 * kDeg);
}

TEST(CompassSensor, SheetPilingBiasesTheHeadingAndDecaysWithDistance) {
  // A quay wall of steel sheet piling along the east bank (east = 10 m, 200 m
  // long) whose induced field adds 3000 nT eastwards at the wall. The vessel
  // heads north, level, at increasing distance from the wall.
  CompassOptions o;
  o.sigma_deg = 0;
  o.field_noise_nt = 0;
  o.declination_deg = 0;
  MagneticAnomalyOptions wall;
  wall.name = "quay_wall";
  wall.from_ned_m = {-100, 10, 0};
  wall.to_ned_m = {100, 10, 0};
  wall.field_ned_nt = {0, 3000, 0};
  wall.decay_length_m = 2.0;
  wall.decay_exponent = 2.0;
  o.anomalies = {wall};
  CompassSimulator compass(o, RngStreams(1));
  const double h = 49000 * std::cos(66.5 * kDeg);  // horizontal intensity
  double previous = 1e9;
  for (const double d : {0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 40.0}) {
    const auto s = compass.measure(pose(0, 0, 0, Vec3(0, 10 - d, 0)));
    // Expected here: east component 3000 / (1 + (d / 2)^2) turns magnetic north
    // east, so a north-heading compass reads west of north by atan(dE / H).
    const double de = 3000 / (1 + (d / 2) * (d / 2));
    const double expected = -std::atan2(de, h);
    EXPECT_NEAR(s->heading_rad, expected, 1e-9) << d;
    EXPECT_LT(std::abs(s->heading_rad), previous);
    previous = std::abs(s->heading_rad);
  }
  EXPECT_GT(std::abs(compass.measure(pose(0, 0, 0, Vec3(50, 9.5, 0)))->heading_rad), 5 * kDeg);
  EXPECT_LT(std::abs(compass.measure(pose(0, 0, 0, Vec3(0, -30, 0)))->heading_rad), 0.1 * kDeg);
  // Beyond the wall's end the distance is to the end point.
  EXPECT_NEAR(anomaly_field_ned_nt(o.anomalies, Vec3(103, 10, 4)).y(), 3000 / (1 + 25.0 / 4), 1e-9);
}

TEST(CompassSensor, HeadingNoiseHasTheConfiguredSpread) {
  CompassOptions o;
  o.sigma_deg = 2.0;
  o.field_noise_nt = 80;
  CompassSimulator compass(o, RngStreams(7));
  double sh = 0, sf = 0;
  const int n = 20000;
  const Vec3 clean = earth_field_ned_nt(o);
  for (int k = 0; k < n; ++k) {
    const auto s = compass.measure(pose(0, 0, 0, Vec3::Zero(), TimeNs{k} * 100'000'000));
    sh += s->heading_rad * s->heading_rad / n;
    sf += (s->field_S_nt - clean).squaredNorm() / (3 * n);
  }
  EXPECT_NEAR(std::sqrt(sh) / (2.0 * kDeg), 1.0, 0.03);
  EXPECT_NEAR(std::sqrt(sf) / 80.0, 1.0, 0.03);
}

// --- Writers and determinism ---------------------------------------------------

// A few seconds of all three sensors on a moving, rolling body, through the
// CSV writers into `dir`.
void write_all(const fs::path& dir, std::uint64_t seed) {
  const RngStreams rng(seed);
  ImuOptions io;
  io.gyro_turn_on_bias_rad_s = 0.002;
  io.clock.jitter_ms = 0.1;
  ImuSimulator imu(io, rng);
  GpsOptions go;
  go.rate_hz = 5;
  GpsSimulator gps(go, rng);
  CompassOptions co;
  co.anomalies.push_back({});
  CompassSimulator compass(co, rng);
  ImuCsvWriter iw(dir / "imu.csv");
  GpsCsvWriter gw(dir / "gps.csv");
  CompassCsvWriter cw(dir / "compass.csv");
  for (int k = 0; k < 1000; ++k) {  // 5 s at 200 Hz
    const double t = k * 0.005;
    BodySample b = pose(0.1 * std::sin(t), 0.05 * std::cos(2 * t), 0.3 * t, Vec3(t, 0.2 * t, 0.01),
                        TimeNs{k} * 5'000'000);
    b.state.v_B = Vec3(1, 0.2, 0);
    b.state.w_B = Vec3(0.1 * std::cos(t), -0.1 * std::sin(2 * t), 0.3);
    if (auto s = imu.measure(b)) iw.write(*s);
    if (k % 40 == 0)
      if (auto f = gps.measure(b)) gw.write(*f);
    if (k % 20 == 0)
      if (auto c = compass.measure(b)) cw.write(*c);
  }
  iw.commit();
  gw.commit();
  cw.commit();
}

TEST(SensorFiles, SameSeedSameBytesAndImuCsvReadsBackAsEuroc) {
  const fs::path base = fs::temp_directory_path() / "driftlab_sensor_files_test";
  fs::remove_all(base);
  for (const char* d : {"a", "b", "c"}) fs::create_directories(base / d);
  write_all(base / "a", 99);
  write_all(base / "b", 99);
  write_all(base / "c", 100);
  for (const char* f : {"imu.csv", "gps.csv", "compass.csv"}) {
    EXPECT_EQ(slurp(base / "a" / f), slurp(base / "b" / f)) << f;
    EXPECT_NE(slurp(base / "a" / f), slurp(base / "c" / f)) << f;
  }
  // imu.csv is an EuRoC IMU file: the strict reader of core accepts it.
  const auto samples = read_euroc_imu(base / "a" / "imu.csv");
  EXPECT_EQ(samples.size(), 1000u);
  const std::string compass = slurp(base / "a" / "compass.csv");
  EXPECT_EQ(compass.substr(0, compass.find('\n')),
            "#timestamp [ns],heading [deg],m_S_x [nT],m_S_y [nT],m_S_z [nT]");
  EXPECT_EQ(std::count(compass.begin(), compass.end(), '\n'), 51);
  const std::string gps = slurp(base / "a" / "gps.csv");
  EXPECT_EQ(std::count(gps.begin(), gps.end(), '\n'), 26);
  fs::remove_all(base);
}

TEST(SensorFiles, CompassCsvWritesHeadingsInZeroTo360) {
  const fs::path dir = fs::temp_directory_path() / "driftlab_compass_csv_test";
  fs::create_directories(dir);
  {
    CompassCsvWriter w(dir / "compass.csv");
    w.write({.t_ns = 10, .heading_rad = -std::numbers::pi / 2, .field_S_nt = Vec3(1, 2.5, -3)});
    w.write({.t_ns = 20, .heading_rad = std::numbers::pi / 4, .field_S_nt = Vec3(0, 0, 0)});
    w.commit();
  }
  EXPECT_EQ(slurp(dir / "compass.csv"),
            "#timestamp [ns],heading [deg],m_S_x [nT],m_S_y [nT],m_S_z [nT]\n"
            "10,270,1,2.5,-3\n"
            "20,45,0,0,0\n");
  // A writer that is not committed leaves nothing behind.
  { CompassCsvWriter w(dir / "never.csv"); }
  EXPECT_FALSE(fs::exists(dir / "never.csv"));
  fs::remove_all(dir);
}

TEST(SensorClocks, StampsCarryOffsetAndTruncatedJitter) {
  ClockOptions c;
  c.offset_ms = -2.5;
  c.jitter_ms = 1.0;
  std::vector<TimeNs> t;
  for (int k = 0; k < 20000; ++k) t.push_back(static_cast<TimeNs>(k) * 10'000'000);
  const auto s = stamp_times(t, c, RngStreams(3), "imu");
  double sum = 0, sum2 = 0, worst = 0;
  for (const auto& x : s) {
    const double d = static_cast<double>(x.t_stamp_ns - x.t_true_ns) * 1e-6 + 2.5;
    sum += d;
    sum2 += d * d;
    worst = std::max(worst, std::abs(d));
    EXPECT_FALSE(x.dropped);
  }
  EXPECT_NEAR(sum / static_cast<double>(s.size()), 0.0, 0.03);
  // A standard normal clamped to [-3, 3] has a standard deviation of 0.9975.
  EXPECT_NEAR(std::sqrt(sum2 / static_cast<double>(s.size())), 0.9975, 0.02);
  EXPECT_LE(worst, 3.0 + 1e-6);
}

}  // namespace
}  // namespace driftlab::sim
