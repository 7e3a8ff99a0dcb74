// The filters' sensor noise from the scenario's sensor models: what a run's filters are told
// about the compass and the IMU when their options leave it null (the scenario's default).
#include "pipeline/filter_stage.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/rotation.hpp"
#include "pipeline/scenario.hpp"

namespace driftlab::pipeline {
namespace {

TEST(FilterNoise, NullCompassNoiseIsTheCompassModelsHeadingNoise) {
  Scenario sc;
  EXPECT_FALSE(sc.pipeline.ned_kf.compass_noise_rad.has_value());  // the scenario's default
  EXPECT_FALSE(sc.pipeline.eskf.gyro_noise_density_rad_s_sqrt_hz.has_value());
  sc.sensors.compass.sigma_deg = 5.0;
  sc.sensors.compass.field_noise_nt = 0.0;
  PipelineOptions p = with_sensor_noise(sc.pipeline, filter_mounts(sc));
  EXPECT_DOUBLE_EQ(*p.ned_kf.compass_noise_rad, deg2rad(5.0));
  EXPECT_DOUBLE_EQ(*p.ned_pf.compass_noise_rad, deg2rad(5.0));
  EXPECT_DOUBLE_EQ(*p.eskf.compass_noise_rad, deg2rad(5.0));
  // Field noise on the horizontal field F cos(I) = 49000 nT x cos 60 deg = 24500 nT: 245 nT
  // across it turns the heading by 0.01 rad, independent of the heading noise added after.
  sc.sensors.compass.field_intensity_nt = 49000.0;
  sc.sensors.compass.inclination_deg = 60.0;
  sc.sensors.compass.field_noise_nt = 245.0;
  sc.sensors.compass.sigma_deg = rad2deg(0.0075);
  p = with_sensor_noise(sc.pipeline, filter_mounts(sc));
  EXPECT_NEAR(*p.ned_kf.compass_noise_rad, std::hypot(0.0075, 0.01), 1e-12);
  // A number in the options wins.
  sc.pipeline.ned_pf.compass_noise_rad = 0.1;
  p = with_sensor_noise(sc.pipeline, filter_mounts(sc));
  EXPECT_EQ(*p.ned_pf.compass_noise_rad, 0.1);
  EXPECT_NEAR(*p.ned_kf.compass_noise_rad, std::hypot(0.0075, 0.01), 1e-12);
}

TEST(FilterNoise, NullImuNoiseIsTheImuModelsKalibrParameters) {
  Scenario sc;
  sc.sensors.imu.apply_preset(sim::ImuPreset::kIdeal);
  sc.sensors.imu.gyro_noise_density_rad_s_sqrt_hz = 1e-3;
  sc.sensors.imu.gyro_random_walk_rad_s2_sqrt_hz = 2e-4;
  sc.sensors.imu.accel_noise_density_m_s2_sqrt_hz = 3e-2;
  sc.sensors.imu.accel_random_walk_m_s3_sqrt_hz = 4e-3;
  sc.pipeline.eskf.accel_random_walk_m_s3_sqrt_hz = 9e-3;  // set: kept
  const PipelineOptions p = with_sensor_noise(sc.pipeline, filter_mounts(sc));
  EXPECT_EQ(*p.eskf.gyro_noise_density_rad_s_sqrt_hz, 1e-3);
  EXPECT_EQ(*p.eskf.gyro_random_walk_rad_s2_sqrt_hz, 2e-4);
  EXPECT_EQ(*p.eskf.accel_noise_density_m_s2_sqrt_hz, 3e-2);
  EXPECT_EQ(*p.eskf.accel_random_walk_m_s3_sqrt_hz, 9e-3);
  // Sensors off: the filters' own built-in values (the MPU-9250's, 1 deg).
  sc.sensors.imu.enabled = false;
  sc.sensors.compass.enabled = false;
  const PipelineOptions off = with_sensor_noise(sc.pipeline, filter_mounts(sc));
  EXPECT_EQ(*off.eskf.gyro_noise_density_rad_s_sqrt_hz,
            *fusion::EskfOptions{}.gyro_noise_density_rad_s_sqrt_hz);
  EXPECT_EQ(*off.ned_kf.compass_noise_rad, *fusion::NedFilterOptions{}.compass_noise_rad);
}

}  // namespace
}  // namespace driftlab::pipeline

namespace driftlab::pipeline {
namespace {

TEST(FilterNoise, TheNedFiltersVoNoiseIsEstimatedByDefault) {
  // The shipped choice (docs/vo-and-filters.md: the seven basin experiments): ned_kf and ned_pf
  // estimate the VO noise from the VO's results (null), and with_sensor_noise leaves it so; a
  // number set by the user is kept.
  PipelineOptions defaults;
  defaults.ned_kf.vo_increment_noise_m = 0.002;
  const PipelineOptions p = with_sensor_noise(defaults, FilterMounts{});
  for (const fusion::NedFilterOptions* o :
       {static_cast<const fusion::NedFilterOptions*>(&p.ned_pf), &p.ned_kf}) {
    EXPECT_FALSE(o->vo_yaw_increment_noise_rad.has_value());
    EXPECT_EQ(o->validate(), "");
  }
  EXPECT_FALSE(p.ned_pf.vo_increment_noise_m.has_value());
  EXPECT_EQ(p.ned_kf.vo_increment_noise_m, 0.002);
  EXPECT_FALSE(PipelineOptions{}.ned_kf.vo_increment_noise_m.has_value());
}

}  // namespace
}  // namespace driftlab::pipeline
