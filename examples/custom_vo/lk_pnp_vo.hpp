// A small stereo VO of "a user's own", to show the plug-in interface: corners in the previous
// left image, their depth from Lucas-Kanade flow into the previous right image (the pair is
// rectified: a disparity along the row), their position in the current left image by
// Lucas-Kanade flow, and the motion by PnP with RANSAC (OpenCV).
#pragma once

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "vo/stereo_odometry.hpp"

class LkPnpVo final : public driftlab::vo::StereoOdometry {
 public:
  LkPnpVo(const driftlab::StereoRig& rig, driftlab::Rng rng);
  driftlab::vo::VoResult process(const driftlab::vo::StereoFrame& frame) override;
  void reset() override;
  std::string name() const override { return "lk_pnp"; }

 private:
  driftlab::StereoRig rig_;
  driftlab::Rng initial_rng_, rng_;
  cv::Mat prev_left_, prev_right_;
};
