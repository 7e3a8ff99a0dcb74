// Options of the sensors carried by the vessel (scenario section `sensors`).
//
// Noise parameters follow Kalibr's continuous-time IMU model (Kalibr wiki,
// "IMU Noise Model"): white-noise densities and bias random walks, which the
// simulators discretise as sigma / sqrt(dt) and sigma * sqrt(dt).
#pragma once

#include <array>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "core/yaml_io.hpp"
#include "sim/sensors/overhead_options.hpp"

namespace driftlab::sim {

/// Rigid mount of a sensor on the body: lever arm in body FRD and orientation.
struct MountOptions {
  std::array<double, 3> position_frd_m{0.0, 0.0, 0.0};
  std::array<double, 3> rpy_deg{0.0, 0.0, 0.0};

  template <class A>
  void visit(A& a) {
    a("position_frd_m", position_frd_m,
      "Lever arm from the centre of gravity, body FRD (x bow, y starboard, z down) [m]",
      yaml::plausible(-500, 500, "inside the largest vessel"));
    a("rpy_deg", rpy_deg,
      "Roll, pitch, yaw (ZYX) of the sensor relative to its nominal forward-looking mounting [deg]",
      yaml::in_range(-360, 360));
  }
};

/// A sensor's time stamps: what its clock writes next to each measurement.
/// The measurement itself is taken at the nominal time; only the stamp moves.
struct ClockOptions {
  double offset_ms = 0.0;
  double jitter_ms = 0.0;
  double drop_probability = 0.0;

  template <class A>
  void visit(A& a) {
    a("offset_ms", offset_ms,
      "Constant offset of the sensor's stamps from true time (stamp = true + offset) [ms]",
      yaml::in_range(-10000, 10000));
    a("jitter_ms", jitter_ms,
      "Standard deviation of Gaussian stamp jitter, truncated at 3 sigma [ms]",
      yaml::in_range(0, 1000));
    a("drop_probability", drop_probability,
      "Probability that a sample is lost (independent per sample)", yaml::in_range(0, 0.99));
  }

  /// Rule shared by every sensor: jitter so small that stamps keep their order
  /// (6 sigma, the full width of the truncated jitter, below one period).
  template <class A>
  static void require_ordered(A& a, const ClockOptions& clock, double rate_hz) {
    a.require(6.0 * clock.jitter_ms * 1e-3 * rate_hz < 1.0, "clock",
              "a jitter_ms below one sixth of the sample period, so that stamps stay in order");
  }
};

/// Photon shot noise and read noise of the image sensor (EMVA 1288's linear
/// camera model). The input 8-bit image is the scene as recorded at
/// reference_exposure_ms and unit gain; exposure and gain scale the electrons
/// and the digital numbers.
struct CameraNoiseOptions {
  bool enabled = true;
  double full_well_e = 10000.0;
  double read_noise_e = 5.0;
  double analog_gain = 1.0;
  double reference_exposure_ms = 5.0;

  template <class A>
  void visit(A& a) {
    a("enabled", enabled, "Add shot and read noise to the rendered images");
    a("full_well_e", full_well_e,
      "Electrons that give 255 DN at unit gain (the system gain is 255 / full_well_e DN/e-) [e-]",
      yaml::in_range(1, 1e7));
    a("read_noise_e", read_noise_e, "Read noise standard deviation [e-]", yaml::in_range(0, 1e4));
    a("analog_gain", analog_gain, "Analog gain: multiplies DN per electron [-]",
      yaml::in_range(0.01, 1000));
    a("reference_exposure_ms", reference_exposure_ms,
      "Exposure at which the renderer's image brightness holds; the camera's exposure_ms "
      "scales the electrons by exposure_ms / reference_exposure_ms [ms]",
      yaml::positive() & yaml::at_most(10000));
  }
};

/// Difference between the stereo rig that renders the images and the nominal
/// one the VO is given (a miscalibration).
struct StereoCalibrationErrorOptions {
  double baseline_error_m = 0.0;
  std::array<double, 3> right_rotation_error_deg{0.0, 0.0, 0.0};

  template <class A>
  void visit(A& a) {
    a("baseline_error_m", baseline_error_m,
      "True baseline minus the nominal baseline_m (the VO sees the nominal one) [m]",
      yaml::in_range(-10, 10));
    a("right_rotation_error_deg", right_rotation_error_deg,
      "Rotation vector of the true right camera relative to its nominal parallel orientation, "
      "about the left optical axes (x right, y down, z forward) [deg]",
      yaml::in_range(-10, 10));
  }
};

/// Auto exposure: after each frame the exposure moves towards the one that
/// would give the left image a mean of target_mean_dn, by a fraction
/// `response` of the step in log exposure (a first-order loop, as camera
/// firmware does over a few frames), within [min_exposure_ms, max_exposure_ms].
/// Both cameras of the pair share the exposure.
struct AutoExposureOptions {
  bool enabled = false;
  double target_mean_dn = 110.0;
  double response = 0.5;
  double min_exposure_ms = 0.05;
  double max_exposure_ms = 20.0;

  template <class A>
  void visit(A& a) {
    a("enabled", enabled, "Adjust exposure_ms frame by frame towards target_mean_dn");
    a("target_mean_dn", target_mean_dn, "Mean left-image value the loop aims at [DN]",
      yaml::in_range(1, 254));
    a("response", response,
      "Fraction of the log-exposure step taken per frame (1 = jump to the estimate)",
      yaml::in_range(0.01, 1));
    a("min_exposure_ms", min_exposure_ms, "Shortest exposure [ms]", yaml::positive());
    a("max_exposure_ms", max_exposure_ms, "Longest exposure [ms]", yaml::positive());
    a.require(min_exposure_ms <= max_exposure_ms, "max_exposure_ms",
              "max_exposure_ms >= min_exposure_ms");
  }
};

/// Lens distortion of both cameras (Brown-Conrady, OpenCV's order k1, k2, p1,
/// p2, k3 on normalised coordinates) and the rectification that removes it
/// again with the calibrated coefficients (true + calibration_error), so that
/// the stream the VO sees is rectified but resampled twice and, with a
/// calibration error, carries residual distortion.
struct LensDistortionOptions {
  bool enabled = false;
  std::array<double, 5> coefficients{-0.30, 0.10, 0.0, 0.0, 0.0};
  std::array<double, 5> calibration_error{0.0, 0.0, 0.0, 0.0, 0.0};

  template <class A>
  void visit(A& a) {
    a("enabled", enabled, "Distort the rendered images and rectify them again (OpenCV remap)");
    a("coefficients", coefficients,
      "True lens distortion k1, k2, p1, p2, k3 (OpenCV order; the default is a Bumblebee2-like "
      "wide lens)",
      yaml::in_range(-2, 2));
    a("calibration_error", calibration_error,
      "Calibrated minus true coefficients, k1..k3: the rectification uses true + error",
      yaml::in_range(-1, 1));
  }
};

/// How the image sensor exposes its rows: all at once (a CCD, or a CMOS sensor
/// with a global shutter) or one after another (a rolling-shutter CMOS sensor).
enum class Shutter { kGlobal, kRolling };
constexpr auto enum_table(Shutter) {
  return std::array{std::pair{Shutter::kGlobal, "global"}, std::pair{Shutter::kRolling, "rolling"}};
}

/// Stereo cameras of the source papers. `custom` leaves every field as given.
enum class CameraPreset { kCustom, kBumblebee2, kPs3Eye };
constexpr auto enum_table(CameraPreset) {
  return std::array{std::pair{CameraPreset::kCustom, "custom"},
                    std::pair{CameraPreset::kBumblebee2, "bumblebee2"},
                    std::pair{CameraPreset::kPs3Eye, "ps3_eye"}};
}

/// Rectified pinhole stereo camera (river paper Eq. (1) uses fx, cx, cy and the baseline).
struct CameraOptions {
  CameraPreset preset = CameraPreset::kCustom;
  int width_px = 640;
  int height_px = 480;
  double fx_px = 500.0;
  double fy_px = 500.0;
  double cx_px = 319.5;
  double cy_px = 239.5;
  double baseline_m = 0.12;
  double rate_hz = 13.0;
  double exposure_ms = 5.0;
  Shutter shutter = Shutter::kGlobal;
  double line_delay_us = 0.0;
  double right_offset_ms = 0.0;
  double right_offset_spread_ms = 0.0;
  double right_offset_jitter_ms = 0.0;
  MountOptions mount;
  CameraNoiseOptions noise;
  double vignetting_strength = 0.0;
  AutoExposureOptions auto_exposure;
  StereoCalibrationErrorOptions calibration_error;
  LensDistortionOptions lens_distortion;
  ClockOptions clock;

  /// Sets the image size, intrinsics, baseline and frame rate to a preset's
  /// (the other fields keep their values); kCustom changes nothing.
  void apply_preset(CameraPreset p);

  template <class A>
  void visit(A& a) {
    a("preset", preset,
      "A source paper's camera; setting it resets width_px, height_px, fx_px, fy_px, cx_px, "
      "cy_px, baseline_m and rate_hz to the preset's values, which keys given after it override. "
      "bumblebee2 (river paper, Kriechbaumer et al. 2015, Sec. 2.1): 1024x768 px, baseline "
      "0.12 m, 8.2 Hz (the paper's average frame rate), grey; fx = fy = 817 px, the 3.8 mm "
      "lens on the 4.65 um pixels of its Sony ICX204 sensor (66 deg horizontal field of view; the "
      "paper does not name the lens, Point Grey sold 2.5, 3.8 and 6 mm). ps3_eye (basin paper, "
      "Kucic and Valcic 2020, Sec. 2.2): 640x480 px at 20 Hz; fx = fy = 521 px, the PlayStation "
      "Eye's wide 75 deg (diagonal) zoom setting; baseline 0.06 m (the paper gives none); its "
      "OV7720 sensor has a rolling shutter: line_delay_us 65.33, one VGA line of 784 pixel "
      "clocks (the OV77xx VGA timing) at the 12 MHz pixel clock of the sensor's 30 fps mode (the "
      "lowest rate of the PlayStation Eye's VGA modes that gives 20 Hz; an assumption, the paper "
      "names no mode); the two free-running cameras paired in software: right_offset_spread_ms "
      "16.67, half the sensor's 30 fps frame period. bumblebee2's CCDs have a global shutter "
      "and are synchronised in hardware (offsets 0)");
    a.when_reading([this] {
      if (preset != applied_preset_) apply_preset(preset);
    });
    a("width_px", width_px, "Image width [px]", yaml::in_range(1, 16384));
    a("height_px", height_px, "Image height [px]", yaml::in_range(1, 16384));
    a("fx_px", fx_px, "Focal length along x [px]",
      yaml::positive() & yaml::up_to(1e5, "a telephoto beyond any survey camera"));
    a("fy_px", fy_px, "Focal length along y [px]",
      yaml::positive() & yaml::up_to(1e5, "a telephoto beyond any survey camera"));
    a("cx_px", cx_px, "Principal point x, OpenCV pixel-centre convention [px]");
    a("cy_px", cy_px, "Principal point y [px]");
    a.require(cx_px >= 0 && cx_px < width_px, "cx_px", "a principal point inside [0, width_px)");
    a.require(cy_px >= 0 && cy_px < height_px, "cy_px", "a principal point inside [0, height_px)");
    a("baseline_m", baseline_m, "Stereo baseline B [m]",
      yaml::positive() & yaml::up_to(100, "a stereo rig wider than any vessel"));
    a("rate_hz", rate_hz, "Frame rate [Hz]", yaml::in_range(0.1, 1000) & yaml::positive());
    a("exposure_ms", exposure_ms,
      "Exposure time: scales the collected electrons (noise.reference_exposure_ms) and, in the "
      "renderer, motion blur [ms]",
      yaml::non_negative() & yaml::up_to(10000, "10 s per frame"));
    a.require(exposure_ms * 1e-3 * rate_hz <= 1.0, "exposure_ms",
              "an exposure no longer than the frame period");
    a("shutter", shutter,
      "global: every row exposed at once; rolling: row r exposed line_delay_us after row r - 1, "
      "each drawn with the pose of its own time (in bands of rows, render.rolling_shutter_*). "
      "A frame's time, its stamp and its truth are the middle row's mid-exposure (row "
      "(height_px - 1) / 2), so the first row is exposed (height_px - 1) / 2 line delays "
      "earlier");
    a("line_delay_us", line_delay_us,
      "Rolling shutter: time from one row's exposure to the next row's [us]",
      yaml::in_range(0, 1e5));
    a.require(shutter != Shutter::kRolling || line_delay_us > 0, "line_delay_us",
              "a line_delay_us > 0 with shutter: rolling");
    a.require(shutter != Shutter::kRolling || line_delay_us * 1e-6 * height_px * rate_hz <= 1.0,
              "line_delay_us",
              "a readout (height_px x line_delay_us) no longer than the frame period");
    a("right_offset_ms", right_offset_ms,
      "Unsynchronised stereo: the right image's exposure minus the left's, the same for every "
      "frame (the VO is told nothing, and the right image carries the left one's stamp) [ms]",
      yaml::in_range(-1000, 1000));
    a("right_offset_spread_ms", right_offset_spread_ms,
      "Free-running pair: an offset drawn once per run, uniform in +-this, added to "
      "right_offset_ms (two cameras paired in software meet at an arbitrary phase) [ms]",
      yaml::in_range(0, 1000));
    a("right_offset_jitter_ms", right_offset_jitter_ms,
      "Standard deviation of a per-frame Gaussian change of the right image's offset, truncated "
      "at 3 sigma [ms]",
      yaml::in_range(0, 1000));
    a.require(std::abs(right_offset_ms) + right_offset_spread_ms + 3 * right_offset_jitter_ms <=
                  500.0 / rate_hz,
              "right_offset_ms",
              "a right image within half a frame period of its left one (|right_offset_ms| + "
              "right_offset_spread_ms + 3 right_offset_jitter_ms <= 500 / rate_hz)");
    a("mount", mount, "Left camera mount on the body");
    a("noise", noise, "Photon shot noise and read noise");
    a("vignetting_strength", vignetting_strength,
      "Blend of cos^4 vignetting: 0 = none, 1 = the full cos^4 law of the pinhole's field angle",
      yaml::unit_interval());
    a("auto_exposure", auto_exposure, "Exposure control loop (exposure_ms is its start)");
    a.require(!auto_exposure.enabled || auto_exposure.max_exposure_ms * 1e-3 * rate_hz <= 1.0,
              "auto_exposure", "a max_exposure_ms no longer than the frame period");
    a("calibration_error", calibration_error, "Stereo miscalibration (true rig vs nominal)");
    a("lens_distortion", lens_distortion, "Lens distortion and rectification of both images");
    // (A baseline_m <= 0 has its own message.)
    a.require(baseline_m <= 0 || baseline_m + calibration_error.baseline_error_m > 0,
              "calibration_error", "a true baseline (baseline_m + baseline_error_m) > 0");
    a("clock", clock, "Frame time stamps: offset, jitter, dropped frames");
    ClockOptions::require_ordered(a, clock, rate_hz);
  }

 private:
  CameraPreset applied_preset_ = CameraPreset::kCustom;
};

inline void CameraOptions::apply_preset(CameraPreset p) {
  switch (p) {
    case CameraPreset::kCustom:
      break;
    case CameraPreset::kBumblebee2:
      width_px = 1024;
      height_px = 768;
      fx_px = fy_px = 817.0;  // 3.8 mm / 4.65 um
      baseline_m = 0.12;
      rate_hz = 8.2;
      shutter = Shutter::kGlobal;  // CCDs, synchronised in hardware
      line_delay_us = 0.0;
      right_offset_ms = right_offset_spread_ms = right_offset_jitter_ms = 0.0;
      break;
    case CameraPreset::kPs3Eye:
      width_px = 640;
      height_px = 480;
      fx_px = fy_px = 521.0;  // 400 px half diagonal / tan(75 deg / 2)
      baseline_m = 0.06;
      rate_hz = 20.0;
      shutter = Shutter::kRolling;  // OmniVision OV7720
      line_delay_us = 784 / 12.0;   // a VGA line of 784 pixel clocks at 12 MHz (30 fps mode)
      right_offset_ms = right_offset_jitter_ms = 0.0;
      right_offset_spread_ms = 1000.0 / 30 / 2;  // free-running, paired in software
      break;
  }
  if (p != CameraPreset::kCustom) {
    cx_px = (width_px - 1) / 2.0;
    cy_px = (height_px - 1) / 2.0;
  }
  preset = p;
  applied_preset_ = p;
}

/// Units of datasheet figures: degrees and standard gravity (g, ug). The same
/// value as sim::kGravity_m_s2 (checked in imu.cpp), repeated here so that the
/// options header stays free of the wave-field code.
inline constexpr double kImuDegToRad = std::numbers::pi / 180.0;
inline constexpr double kImuStandardGravity_m_s2 = 9.80665;

/// How GPS satellites are placed: on GPS-like circular orbits (a Walker
/// 24/6/1 constellation at 55 deg inclination seen from the datum), or spread
/// evenly over the whole sky sphere (no orbital holes; for tests).
enum class ConstellationModel { kOrbits, kSphere };
constexpr auto enum_table(ConstellationModel) {
  return std::array{std::pair{ConstellationModel::kOrbits, "orbits"},
                    std::pair{ConstellationModel::kSphere, "sphere"}};
}

enum class ImuPreset { kIdeal, kMpu9250, kAdis16448 };
constexpr auto enum_table(ImuPreset) {
  return std::array{std::pair{ImuPreset::kIdeal, "ideal"},
                    std::pair{ImuPreset::kMpu9250, "mpu9250"},
                    std::pair{ImuPreset::kAdis16448, "adis16448"}};
}

/// Error model of one triad (gyroscope or accelerometer), in the triad's units
/// U (rad/s or m/s^2): measured = (I + scale + misalignment) * true + bias + white noise,
/// then clipped to +-range. Kalibr's continuous-time parameters.
struct ImuTriadOptions {
  double noise_density = 0.0;      // U / sqrt(Hz)
  double random_walk = 0.0;        // U / s / sqrt(Hz)
  double turn_on_bias = 0.0;       // U, 1 sigma per axis
  double scale_factor_ppm = 0.0;   // 1 sigma per axis
  double misalignment_mrad = 0.0;  // 1 sigma per off-diagonal entry
  double range = 0.0;              // U; 0 = no saturation
};

struct ImuOptions {
  bool enabled = true;
  ImuPreset preset = ImuPreset::kMpu9250;
  double rate_hz = 200.0;
  MountOptions mount;
  // Noise fields: in-class defaults are mpu9250's, the same expressions as apply_preset().
  double gyro_noise_density_rad_s_sqrt_hz = 0.01 * kImuDegToRad;
  double gyro_random_walk_rad_s2_sqrt_hz = 2.0e-5;
  double gyro_turn_on_bias_rad_s = 0.0;
  double gyro_scale_factor_ppm = 0.0;
  double gyro_misalignment_mrad = 0.0;
  double gyro_range_rad_s = 2000 * kImuDegToRad;
  double accel_noise_density_m_s2_sqrt_hz = 300e-6 * kImuStandardGravity_m_s2;
  double accel_random_walk_m_s3_sqrt_hz = 1.5e-4;
  double accel_turn_on_bias_m_s2 = 0.0;
  double accel_scale_factor_ppm = 0.0;
  double accel_misalignment_mrad = 0.0;
  double accel_range_m_s2 = 16 * kImuStandardGravity_m_s2;
  ClockOptions clock;

  /// The noise fields of a preset (enabled, rate, mount and clock keep their defaults):
  ///  - ideal: no error of any kind.
  ///  - mpu9250 (the basin paper's IMU): noise densities from the InvenSense
  ///    PS-MPU-9250A-01 datasheet (0.01 deg/s/sqrt(Hz), 300 ug/sqrt(Hz)); largest
  ///    full-scale ranges (2000 deg/s, 16 g). The datasheet gives no bias random
  ///    walk: 2e-5 rad/s^2/sqrt(Hz) and 1.5e-4 m/s^3/sqrt(Hz) are assumed, which put
  ///    the Allan-deviation minima near 13 deg/h and 0.07 mg, the order of
  ///    consumer MEMS bias instability; replace them with your unit's Allan variance.
  ///  - adis16448 (EuRoC's IMU): the Kalibr parameters published with the EuRoC
  ///    MAV dataset (sensor.yaml of imu0); ranges 1000 deg/s and 18 g.
  /// Turn-on bias, scale factor and misalignment are 0 in every preset (a unit
  /// calibrated at start-up); set them to study an uncalibrated one (the
  /// MPU-9250 datasheet allows +-5 deg/s, +-60 mg, +-3 % and +-2 % cross-axis).
  static ImuOptions preset_defaults(ImuPreset preset);

  /// Sets the noise fields to `p`'s (see preset_defaults()).
  void apply_preset(ImuPreset p);

  ImuTriadOptions gyro() const {
    return {gyro_noise_density_rad_s_sqrt_hz, gyro_random_walk_rad_s2_sqrt_hz,
            gyro_turn_on_bias_rad_s,          gyro_scale_factor_ppm,
            gyro_misalignment_mrad,           gyro_range_rad_s};
  }
  ImuTriadOptions accel() const {
    return {accel_noise_density_m_s2_sqrt_hz, accel_random_walk_m_s3_sqrt_hz,
            accel_turn_on_bias_m_s2,          accel_scale_factor_ppm,
            accel_misalignment_mrad,          accel_range_m_s2};
  }

  template <class A>
  void visit(A& a) {
    a("enabled", enabled, "Simulate the IMU");
    a("preset", preset,
      "Noise model preset; setting it resets the gyro_* and accel_* fields below to the "
      "preset's values (the defaults shown are mpu9250's)");
    a.when_reading([this] {
      if (preset != applied_preset_) apply_preset(preset);
    });
    a("rate_hz", rate_hz, "Sample rate [Hz]", yaml::in_range(1, 10000) & yaml::positive());
    a("mount", mount, "IMU mount on the body (sensor axes = body FRD at rpy 0)");
    a("gyro_noise_density_rad_s_sqrt_hz", gyro_noise_density_rad_s_sqrt_hz,
      "Gyroscope white-noise density (Kalibr gyroscope_noise_density) [rad/s/sqrt(Hz)]",
      yaml::non_negative() & yaml::up_to(1, "1000 x a consumer MEMS gyro"));
    a("gyro_random_walk_rad_s2_sqrt_hz", gyro_random_walk_rad_s2_sqrt_hz,
      "Gyroscope bias random walk (Kalibr gyroscope_random_walk) [rad/s^2/sqrt(Hz)]",
      yaml::non_negative() & yaml::up_to(1, "1000 x a consumer MEMS gyro"));
    a("gyro_turn_on_bias_rad_s", gyro_turn_on_bias_rad_s,
      "Standard deviation of the gyroscope bias drawn at switch-on, per axis [rad/s]",
      yaml::non_negative() & yaml::up_to(1, "57 deg/s: a broken gyro"));
    a("gyro_scale_factor_ppm", gyro_scale_factor_ppm,
      "Standard deviation of the gyroscope scale-factor error drawn at switch-on [ppm]",
      yaml::in_range(0, 1e5));
    a("gyro_misalignment_mrad", gyro_misalignment_mrad,
      "Standard deviation of each off-diagonal gyroscope axis misalignment drawn at switch-on "
      "[mrad]",
      yaml::in_range(0, 100));
    a("gyro_range_rad_s", gyro_range_rad_s,
      "Gyroscope saturation: outputs are clipped to +-this (0 = no saturation) [rad/s]",
      yaml::non_negative());
    a("accel_noise_density_m_s2_sqrt_hz", accel_noise_density_m_s2_sqrt_hz,
      "Accelerometer white-noise density (Kalibr accelerometer_noise_density) [m/s^2/sqrt(Hz)]",
      yaml::non_negative() & yaml::up_to(10, "1000 x a consumer MEMS accelerometer"));
    a("accel_random_walk_m_s3_sqrt_hz", accel_random_walk_m_s3_sqrt_hz,
      "Accelerometer bias random walk (Kalibr accelerometer_random_walk) [m/s^3/sqrt(Hz)]",
      yaml::non_negative() & yaml::up_to(10, "1000 x a consumer MEMS accelerometer"));
    a("accel_turn_on_bias_m_s2", accel_turn_on_bias_m_s2,
      "Standard deviation of the accelerometer bias drawn at switch-on, per axis [m/s^2]",
      yaml::non_negative() & yaml::up_to(10, "1 g: a broken accelerometer"));
    a("accel_scale_factor_ppm", accel_scale_factor_ppm,
      "Standard deviation of the accelerometer scale-factor error drawn at switch-on [ppm]",
      yaml::in_range(0, 1e5));
    a("accel_misalignment_mrad", accel_misalignment_mrad,
      "Standard deviation of each off-diagonal accelerometer axis misalignment drawn at "
      "switch-on [mrad]",
      yaml::in_range(0, 100));
    a("accel_range_m_s2", accel_range_m_s2,
      "Accelerometer saturation: outputs are clipped to +-this (0 = no saturation) [m/s^2]",
      yaml::non_negative());
    a("clock", clock, "Sample time stamps: offset, jitter, dropped samples");
    ClockOptions::require_ordered(a, clock, rate_hz);
  }

 private:
  ImuPreset applied_preset_ = ImuPreset::kMpu9250;
};

inline void ImuOptions::apply_preset(ImuPreset p) {
  constexpr double kDeg = kImuDegToRad;
  constexpr double kG = kImuStandardGravity_m_s2;
  switch (p) {
    case ImuPreset::kIdeal:
      gyro_noise_density_rad_s_sqrt_hz = 0.0;
      gyro_random_walk_rad_s2_sqrt_hz = 0.0;
      gyro_range_rad_s = 0.0;
      accel_noise_density_m_s2_sqrt_hz = 0.0;
      accel_random_walk_m_s3_sqrt_hz = 0.0;
      accel_range_m_s2 = 0.0;
      break;
    case ImuPreset::kMpu9250:
      gyro_noise_density_rad_s_sqrt_hz = 0.01 * kDeg;
      gyro_random_walk_rad_s2_sqrt_hz = 2.0e-5;
      gyro_range_rad_s = 2000 * kDeg;
      accel_noise_density_m_s2_sqrt_hz = 300e-6 * kG;
      accel_random_walk_m_s3_sqrt_hz = 1.5e-4;
      accel_range_m_s2 = 16 * kG;
      break;
    case ImuPreset::kAdis16448:
      gyro_noise_density_rad_s_sqrt_hz = 1.6968e-4;
      gyro_random_walk_rad_s2_sqrt_hz = 1.9393e-5;
      gyro_range_rad_s = 1000 * kDeg;
      accel_noise_density_m_s2_sqrt_hz = 2.0e-3;
      accel_random_walk_m_s3_sqrt_hz = 3.0e-3;
      accel_range_m_s2 = 18 * kG;
      break;
  }
  gyro_turn_on_bias_rad_s = 0.0;
  gyro_scale_factor_ppm = 0.0;
  gyro_misalignment_mrad = 0.0;
  accel_turn_on_bias_m_s2 = 0.0;
  accel_scale_factor_ppm = 0.0;
  accel_misalignment_mrad = 0.0;
  preset = p;
  applied_preset_ = p;
}

inline ImuOptions ImuOptions::preset_defaults(ImuPreset p) {
  ImuOptions o;
  o.apply_preset(p);
  return o;
}

struct GpsOptions {
  bool enabled = true;
  double rate_hz = 1.0;
  double latency_s = 0.0;
  double sigma_horizontal_m = 1.5;
  std::array<double, 3> datum_lat_lon_h{52.1357, -0.4665, 20.0};
  int min_satellites = 4;
  std::array<double, 3> antenna_frd_m{0.0, 0.0, -1.0};
  ConstellationModel constellation = ConstellationModel::kOrbits;
  int constellation_size = 31;
  double elevation_mask_deg = 10.0;
  double max_hdop = 20.0;
  double constellation_period_s = 43082.0;
  double error_correlation_time_s = 0.0;
  ClockOptions clock;

  template <class A>
  void visit(A& a) {
    a("enabled", enabled, "Simulate the GPS receiver");
    a("rate_hz", rate_hz, "Fix rate [Hz]", yaml::in_range(0.01, 100) & yaml::positive());
    a("latency_s", latency_s,
      "Delay from the position's validity to the fix's time stamp: a fix stamped t holds the "
      "position at t - latency_s [s]",
      yaml::in_range(0, 10));
    a("sigma_horizontal_m", sigma_horizontal_m,
      "Horizontal noise at HDOP 1 [m]: the user-equivalent range error; the position error has "
      "covariance sigma^2 (H^T H)^-1, i.e. horizontal RMS sigma * HDOP, vertical sigma * VDOP",
      yaml::non_negative() & yaml::up_to(1000, "1 km: no GPS"));
    a("datum_lat_lon_h", datum_lat_lon_h,
      "Local tangent-plane origin (the world NED origin): WGS84 latitude [deg], longitude "
      "[deg], ellipsoidal height [m]");
    a.require(std::abs(datum_lat_lon_h[0]) <= 90, "datum_lat_lon_h",
              "a latitude in [-90, 90] deg as the first entry");
    a.require(std::abs(datum_lat_lon_h[1]) <= 360, "datum_lat_lon_h",
              "a longitude in [-360, 360] deg as the second entry");
    a.require(std::abs(datum_lat_lon_h[2]) <= 1e5, "datum_lat_lon_h",
              "a height in [-1e5, 1e5] m as the third entry");
    a("min_satellites", min_satellites,
      "No fix with fewer visible satellites (a 3D fix needs 4: position and clock)",
      yaml::in_range(4, 64));
    a("antenna_frd_m", antenna_frd_m,
      "Antenna phase centre from the centre of gravity, body FRD [m]",
      yaml::plausible(-500, 500, "inside the largest vessel"));
    a("constellation", constellation,
      "orbits: GPS-like circular orbits (6 planes at 55 deg inclination, 26 560 km, half a "
      "sidereal day) seen from datum_lat_lon_h, with the sky's real holes (none near the "
      "celestial pole at high latitudes); sphere: spread evenly over the sky sphere");
    a("constellation_size", constellation_size,
      "Satellites of the synthetic constellation (orbits: spread over 6 planes; 31 = GPS's "
      "operational count, 24 its nominal slots)",
      yaml::in_range(4, 200));
    a.require(constellation_size >= min_satellites, "constellation_size",
              "at least min_satellites satellites");
    a("elevation_mask_deg", elevation_mask_deg,
      "Satellites below this elevation are not used [deg]", yaml::in_range(0, 89));
    a("max_hdop", max_hdop, "No fix when the HDOP exceeds this (0 = no limit)",
      yaml::non_negative());
    a.require(max_hdop == 0 || max_hdop >= 1, "max_hdop", "0 (no limit) or a value >= 1");
    a("constellation_period_s", constellation_period_s,
      "orbits: orbital period (GPS: half a sidereal day), the Earth turning under them; "
      "sphere: period of the sky's rotation about the Earth's axis; 0 = a fixed sky [s]",
      yaml::non_negative());
    a("error_correlation_time_s", error_correlation_time_s,
      "Correlation time of the position error, first-order Gauss-Markov (0 = white, "
      "independent per fix) [s]",
      yaml::non_negative());
    a("clock", clock, "Fix time stamps: offset, jitter, dropped fixes");
    ClockOptions::require_ordered(a, clock, rate_hz);
  }
};

/// A magnetic disturbance attached to a steel structure (sheet piling of a
/// quay wall, a bridge), modelled as a segment from which a fixed field
/// perturbation decays with distance d as 1 / (1 + (d / decay_length_m)^decay_exponent).
struct MagneticAnomalyOptions {
  std::string name = "steel";
  std::array<double, 3> from_ned_m{0.0, 0.0, 0.0};
  std::array<double, 3> to_ned_m{0.0, 0.0, 0.0};
  std::array<double, 3> field_ned_nt{5000.0, 0.0, 0.0};
  double decay_length_m = 3.0;
  double decay_exponent = 2.0;

  template <class A>
  void visit(A& a) {
    a("name", name, "Label (e.g. quay_wall, bridge)", yaml::non_empty());
    a("from_ned_m", from_ned_m, "One end of the structure, world NED [m]");
    a("to_ned_m", to_ned_m, "Other end (equal to from_ned_m: a point source) [m]");
    a("field_ned_nt", field_ned_nt, "Field perturbation at the structure, world NED [nT]",
      yaml::in_range(-1e6, 1e6));
    a("decay_length_m", decay_length_m, "Distance at which the perturbation has halved [m]",
      yaml::positive() & yaml::up_to(1e4, "10 km: no local anomaly"));
    a("decay_exponent", decay_exponent,
      "Far-field fall-off exponent: 2 for a line of dipoles (sheet piling), 3 for a point dipole",
      yaml::in_range(0.5, 6));
  }
};

/// Where a compass takes the roll and pitch that level its field before the heading: the true
/// attitude (a perfectly levelled compass), its own accelerometer's specific force (a
/// strapdown compass: apparent gravity, tilted by every acceleration of the hull), or none
/// (a plain two-axis heading of the sensor-frame field).
enum class CompassLevelling { kTrueAttitude, kAccelerometer, kNone };
constexpr auto enum_table(CompassLevelling) {
  return std::array{std::pair{CompassLevelling::kTrueAttitude, "true_attitude"},
                    std::pair{CompassLevelling::kAccelerometer, "accelerometer"},
                    std::pair{CompassLevelling::kNone, "none"}};
}

struct CompassOptions {
  bool enabled = true;
  CompassLevelling levelling = CompassLevelling::kTrueAttitude;
  double rate_hz = 10.0;
  double sigma_deg = 1.0;
  MountOptions mount;
  double field_intensity_nt = 49000.0;
  double inclination_deg = 66.5;
  double declination_deg = -0.5;
  double field_noise_nt = 50.0;
  std::array<double, 3> hard_iron_nt{0.0, 0.0, 0.0};
  std::array<double, 9> soft_iron{1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  std::vector<MagneticAnomalyOptions> anomalies;
  // Ours: 2000 nT across the structure is ~6 deg of heading bias alongside it (horizontal field
  // ~19500 nT at 66.5 deg dip), ~1.5 deg at 5 m: the order of the bias the river paper blames
  // on steel sheet piling.
  bool steel_structures = true;
  std::array<double, 3> steel_field_ned_nt{2000.0, 2000.0, 0.0};
  double steel_decay_length_m = 3.0;
  double steel_decay_exponent = 2.0;
  ClockOptions clock;

  template <class A>
  void visit(A& a) {
    a("enabled", enabled, "Simulate the compass / magnetometer");
    a("rate_hz", rate_hz, "Sample rate [Hz]", yaml::in_range(0.01, 1000) & yaml::positive());
    a("levelling", levelling,
      "Roll and pitch that level the field before the heading: true_attitude (exact), "
      "accelerometer (from the specific force at the compass: a strapdown compass, tilted by "
      "the hull's accelerations) or none (the heading of the sensor-frame field)");
    a("sigma_deg", sigma_deg,
      "Heading noise standard deviation, added to the heading computed from the (distorted) "
      "field [deg]",
      yaml::non_negative() & yaml::up_to(180, "noise beyond half a turn"));
    a("mount", mount, "Magnetometer mount on the body (sensor axes = body FRD at rpy 0)");
    a("field_intensity_nt", field_intensity_nt,
      "Total intensity F of the Earth's field at the site (about 49000 in southern England) "
      "[nT]",
      yaml::in_range(1000, 100000));
    a("inclination_deg", inclination_deg, "Inclination (dip), positive downwards [deg]",
      yaml::in_range(-90, 90));
    a("declination_deg", declination_deg,
      "Declination, east of true north positive; the compass applies it, so headings are "
      "true [deg]",
      yaml::in_range(-180, 180));
    a("field_noise_nt", field_noise_nt,
      "Standard deviation of the white noise on each field axis, per sample [nT]",
      yaml::non_negative() & yaml::up_to(1e5, "twice the Earth field"));
    a("hard_iron_nt", hard_iron_nt, "Hard-iron offset in the sensor frame [nT]",
      yaml::in_range(-1e6, 1e6));
    a("soft_iron", soft_iron,
      "Soft-iron matrix (row-major 3x3) applied to the field in the sensor frame; identity = "
      "none",
      yaml::in_range(-10, 10));
    a("anomalies", anomalies,
      "Local disturbances of steel structures (quay wall sheet piling, bridge)");
    a("steel_structures", steel_structures,
      "In a run, also attach an anomaly to each steel structure of the scene (quay wall sheet "
      "piling, bridge), along the structure's length");
    a("steel_field_ned_nt", steel_field_ned_nt,
      "Field perturbation of those scene anomalies at the structure, world NED [nT]",
      yaml::in_range(-1e6, 1e6));
    a("steel_decay_length_m", steel_decay_length_m,
      "Distance at which the scene anomalies have halved [m]",
      yaml::positive() & yaml::up_to(1e4, "10 km: no local anomaly"));
    a("steel_decay_exponent", steel_decay_exponent, "Far-field fall-off of the scene anomalies",
      yaml::in_range(0.5, 6));
    a("clock", clock, "Sample time stamps: offset, jitter, dropped samples");
    ClockOptions::require_ordered(a, clock, rate_hz);
  }
};

/// The river paper's attitude reference (Section 2.2): an x-IMU on the hull, whose firmware
/// fuses its own gyroscope, accelerometer and magnetometer into ZYX Euler angles with
/// Madgwick's gradient-descent filter (Madgwick, Harrison & Vaidyanathan, ICORR 2011, the
/// paper's [43]; < 0.8 deg static and < 1.7 deg dynamic RMS against an optical reference).
/// The filter runs at update_rate_hz on the unit's own sensors and reports at rate_hz.
struct AhrsOptions {
  bool enabled = false;
  double rate_hz = 128.0;         // river paper Section 2.2: 128 Hz, constant
  double update_rate_hz = 512.0;  // x-IMU User Manual 4.0: internal state update at 512 Hz
  // Madgwick's gain: the default of x-io's reference implementation, which updates at 512 Hz.
  double beta_rad_s = 0.1;
  // The x-IMU's IMU-3000 gyroscope and LSM303DLH accelerometer: their noise is taken from the
  // mpu9250 preset (InvenSense's later part); the datasheets' figures were not confirmed.
  ImuPreset imu_preset = ImuPreset::kMpu9250;
  // The LSM303DLH's magnetometer at +-1.3 gauss: about two counts. A count is 91 nT on its
  // successor, the LSM303DLHC (1100 LSB/gauss, datasheet Table 75); the DLH's own gain was not
  // confirmed.
  double magnetometer_noise_nt = 190.0;
  MountOptions mount;

  /// The unit's gyroscope and accelerometer, sampled at update_rate_hz on its mount.
  ImuOptions imu() const {
    ImuOptions o = ImuOptions::preset_defaults(imu_preset);
    o.rate_hz = update_rate_hz;
    o.mount = mount;
    return o;
  }
  /// Filter updates per reported sample.
  int updates_per_sample() const { return static_cast<int>(std::lround(update_rate_hz / rate_hz)); }

  template <class A>
  void visit(A& a) {
    a("enabled", enabled,
      "Simulate the attitude and heading reference system (the river paper's x-IMU)");
    a("rate_hz", rate_hz, "Rate of the reported Euler angles [Hz]",
      yaml::in_range(1, 10000) & yaml::positive());
    a("update_rate_hz", update_rate_hz,
      "Rate of the filter's updates, each on one sample of the unit's own gyroscope, "
      "accelerometer and magnetometer [Hz]",
      yaml::in_range(1, 10000) & yaml::positive());
    a("beta_rad_s", beta_rad_s,
      "Madgwick's filter gain beta: the rate at which accelerometer and magnetometer pull the "
      "orientation [rad/s]",
      yaml::in_range(0, 10));
    a("imu_preset", imu_preset, "Noise model of the unit's gyroscope and accelerometer");
    a("magnetometer_noise_nt", magnetometer_noise_nt,
      "Standard deviation of the white noise on each magnetometer axis, per update [nT]",
      yaml::non_negative() & yaml::up_to(1e5, "twice the Earth field"));
    a("mount", mount, "AHRS mount on the body (sensor axes = body FRD at rpy 0)");
    a.require(update_rate_hz >= rate_hz &&
                  std::abs(update_rate_hz / rate_hz - updates_per_sample()) < 1e-9,
              "update_rate_hz", "a whole multiple of rate_hz");
  }
};

struct SensorOptions {
  CameraOptions camera;
  ImuOptions imu;
  GpsOptions gps;
  CompassOptions compass;
  OverheadOptions overhead;
  AhrsOptions ahrs;

  template <class A>
  void visit(A& a) {
    a("camera", camera, "Stereo camera");
    a("imu", imu, "Inertial measurement unit");
    a("gps", gps, "GPS receiver");
    a("compass", compass, "Compass / magnetometer");
    a("ahrs", ahrs,
      "Attitude and heading reference (the river paper's x-IMU): the attitude truth of its "
      "Table 1, as the paper measured it");
    a("overhead", overhead,
      "The basin's overhead camera and the model's colour markers: the basin paper's "
      "reference (Section 3.2)");
  }
};

}  // namespace driftlab::sim
