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

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "core/se3.hpp"
#include "pipeline/scenario.hpp"
#include "sim/render/renderer.hpp"
#include "sim/sensors/camera_effects.hpp"
#include "sim/sensors/lens.hpp"

namespace driftlab::pipeline {

/// The true state of the camera's platform at a frame.
struct FrameTruth {
  double t_s = 0;               // true time of the frame (centre of the exposure)
  SE3 T_W_B;                    // body pose
  Vec6 twist_B = Vec6::Zero();  // [v_B; w_B]: body-frame velocity and angular rate
};

class CameraStage {
 public:
  /// `renderer` must outlive the stage; its right camera is set to the true rig.
  CameraStage(const Scenario& sc, sim::StereoRenderer* renderer, const RngStreams& rng);
  /// Renders and processes one stereo pair (8-bit grayscale, rectified).
  sim::StereoImages capture(const FrameTruth& truth);
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
  /// The samples the last capture() took.
  int last_blur_samples() const { return last_blur_samples_; }
  /// Left-camera pose at the centre of the exposure.
  SE3 T_W_C(const FrameTruth& truth) const { return truth.T_W_B * T_B_C_; }

 private:
  sim::StereoImages render_blurred(const FrameTruth& truth);

  sim::StereoRenderer* renderer_;
  SE3 T_B_C_;
  int blur_samples_;
  double blur_step_px_;
  PinholeCamera camera_;  // the left camera's intrinsics, for blur_samples()
  int last_blur_samples_ = 1;
  double exposure_ms_;
  sim::AutoExposureOptions auto_exposure_;
  sim::CameraImageNoise left_noise_, right_noise_;
  std::optional<sim::LensRoundTrip> lens_;
};

}  // namespace driftlab::pipeline
