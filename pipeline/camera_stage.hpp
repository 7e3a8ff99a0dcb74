// The camera stage: from the renderer's ideal pinhole images to what the
// stereo camera delivers (issue "sensors": camera effects and timing).
//
// Per frame, in the order light meets the camera:
//  1. motion blur: render.motion_blur_samples renders at instants spread
//     evenly over the exposure (sensors.camera.exposure_ms, centred on the
//     frame time) along the true motion, averaged; the body moves with its
//     twist at the frame time, T_W_B(t + d) = T_W_B(t) exp(d [v_B; w_B]).
//     With render.motion_blur_step_px, as few samples as keep the image's
//     motion between two of them within that step (blur_samples());
//     With a rolling shutter (sensors.camera.shutter), each render draws the
//     image in bands of rows, each band from the pose of its own time
//     (shutter_bands(), rolling_bands()); the blur's instants are spread about
//     each band's time. With an unsynchronised pair (right_offset_*), the right
//     image's times are shifted by the frame's offset (right_offset_s());
//  2. the true stereo rig: the right camera is rendered where the
//     miscalibrated rig puts it (sensors.camera.calibration_error), the VO is
//     told the nominal one;
//  3. lens distortion (sensors.camera.lens_distortion): the raw image;
//  4. vignetting, gain, exposure, shot and read noise on the raw image
//     (sim::PhotometricModel), left and right from separate streams;
//  5. rectification with the calibrated lens coefficients;
//  6. with auto exposure, the next frame's exposure from this left image's
//     mean (sim::next_auto_exposure_ms); it also sets the blur's duration.
// Frame timing (clock offset, jitter, dropped frames) is applied by the
// caller with sim::camera_frame_times.
#pragma once

#include <memory>
#include <optional>
#include <vector>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "core/se3.hpp"
#include "pipeline/scenario.hpp"
#include "sim/render/renderer.hpp"
#include "sim/sensors/camera_effects.hpp"
#include "sim/sensors/lens.hpp"

namespace driftlab::pipeline {

/// A band of image rows exposed together, centred dt_s after the frame time.
struct ShutterBand {
  int row_begin = 0;
  int row_end = 0;  // one past the last row
  double dt_s = 0;
};

/// The rows of an image `height` rows high in `bands` bands of equal height (the first ones a
/// row taller where they do not divide), each exposed at its centre row's time: row r's
/// exposure is centred (r - (height - 1) / 2) line_delay_s after the frame time (the frame
/// time is the middle row's mid-exposure).
std::vector<ShutterBand> shutter_bands(int height, double line_delay_s, int bands);

/// The right image's exposure minus the left's in a run of this seed, before each frame's
/// jitter: right_offset_ms plus the run's draw within +-right_offset_spread_ms [s].
double run_right_offset_s(const sim::CameraOptions& camera, const RngStreams& rng);

/// The true state of the camera's platform at a frame.
struct FrameTruth {
  double t_s = 0;               // true time of the frame (centre of the exposure)
  SE3 T_W_B;                    // body pose
  Vec6 twist_B = Vec6::Zero();  // [v_B; w_B]: body-frame velocity and angular rate
};

/// The share of a mask's pixels that are set (non-zero); 0 for an empty mask.
double moving_share(const sim::GrayImage& mask);

class CameraStage {
 public:
  /// `renderer` must outlive the stage; its right camera is set to the true rig.
  CameraStage(const Scenario& sc, sim::StereoRenderer* renderer, const RngStreams& rng);
  /// Renders and processes one stereo pair (8-bit grayscale, rectified). With `moving_mask`,
  /// also the left image's moving things (moving_left) from its own pass where that pass is the
  /// ideal camera at the centre of the exposure (one render: no motion blur, one band, no
  /// multisampling); moving_left stays empty where it is not.
  sim::StereoImages capture(const FrameTruth& truth, bool moving_mask = false);
  /// capture(), and the left camera's ground truth at the centre of the exposure: with `depth`
  /// its depth in depth_left; with `depth` or `mask` its moving mask in moving_left; always
  /// the share of its pixels that show moving things in *moving_px (0 when nothing moves). The
  /// mask comes from the left image's own pass where capture() can give it (the same pixels as
  /// render_truth's: tests/sim/render_test.cpp), from render_truth's pass otherwise.
  sim::StereoImages capture_with_truth(const FrameTruth& truth, bool depth, bool mask,
                                       double* moving_px);
  /// The exposure of the next frame [ms] (changes frame to frame with auto exposure).
  double exposure_ms() const { return exposure_ms_; }
  /// How many renders the blur of a frame with this truth takes: motion_blur_samples, or with
  /// motion_blur_step_px > 0 the fewest (>= 1) whose spacing keeps the image motion from the
  /// camera's rotation over the exposure within the step; that motion is the largest shift of
  /// the four image corners, each ray turned by the exposure's rotation and projected again
  /// (a rotation moves the corners the most). The translation's share is left out (at the
  /// river's speeds below a pixel: 0.5 m/s over 5 ms moves a point 5 m away by 0.4 px at
  /// f = 817 px).
  int blur_samples(const FrameTruth& truth) const;
  /// How many bands of rows a rolling-shutter frame with this truth is drawn in (1 with a global
  /// shutter): the fewest that keep the image motion over one band's share of the readout
  /// within render.rolling_shutter_step_px, at most render.rolling_shutter_max_bands. The motion
  /// is the largest shift of the four image corners over the readout, each ray moved by the
  /// camera's rotation and by its translation seen at render.rolling_shutter_near_m.
  int rolling_bands(const FrameTruth& truth) const;
  /// The bands the last capture() took.
  int last_rolling_bands() const { return last_rolling_bands_; }
  /// The right image's exposure minus the left's for the last capture() [s].
  double last_right_offset_s() const { return last_right_offset_s_; }
  /// The samples the last capture() took.
  int last_blur_samples() const { return last_blur_samples_; }
  /// Left-camera pose at the centre of the exposure.
  SE3 T_W_C(const FrameTruth& truth) const { return truth.T_W_B * T_B_C_; }
  /// Left-camera pose dt_s after the frame time, the body moving with its twist at the frame
  /// time: T_W_B(t + d) = T_W_B(t) exp(d [v_B; w_B]).
  SE3 T_W_C(const FrameTruth& truth, double dt_s) const;

 private:
  sim::StereoImages render_blurred(const FrameTruth& truth, bool moving_mask);
  // One render of the pair, every row exposed d_s after its own time.
  sim::StereoImages render_at(const FrameTruth& truth, const std::vector<ShutterBand>& bands,
                              double d_s, bool moving_mask = false);
  // The image motion [px] of the left camera's four corners from pose a to pose b (C(a) <- C(b)
  // relative motion), points at depth `depth_m`.
  double corner_motion_px(const SE3& T_a_b, double depth_m) const;

  sim::StereoRenderer* renderer_;
  SE3 T_B_C_;
  int blur_samples_;
  double blur_step_px_;
  bool single_sampled_;   // render.msaa_samples 1: the left eye's pass can give the moving mask
  PinholeCamera camera_;  // the left camera's intrinsics, for blur_samples()
  int last_blur_samples_ = 1;
  sim::Shutter shutter_;
  double line_delay_s_;
  double band_step_px_;
  int max_bands_;
  double near_m_;
  int last_rolling_bands_ = 1;
  double right_offset_s_;  // the run's constant part (right_offset_ms + the run's draw)
  double right_jitter_s_;
  Rng right_jitter_;
  double last_right_offset_s_ = 0;
  double exposure_ms_;
  sim::AutoExposureOptions auto_exposure_;
  sim::CameraImageNoise left_noise_, right_noise_;
  std::optional<sim::LensRoundTrip> lens_;
};

}  // namespace driftlab::pipeline
