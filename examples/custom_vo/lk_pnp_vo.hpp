// A small stereo VO of "a user's own", to show the plug-in interface: corners in the previous
// left image, their depth from Lucas-Kanade flow into the previous right image (the pair is
// rectified: a disparity along the row), their position in the current left image by
// Lucas-Kanade flow, and the motion by PnP with RANSAC (OpenCV).
#pragma once

#include <opencv2/core.hpp>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "core/yaml_io.hpp"
#include "vo/stereo_odometry.hpp"

/// Its options: set in a scenario as pipeline.plugins.lk_pnp.KEY, read, checked, written to
/// scenario.resolved.yaml and documented by driftlab's own options machinery (core/yaml_io.hpp).
struct LkPnpOptions {
  int max_corners = 600;
  double min_corner_distance_px = 8;
  double ransac_threshold_px = 1.0;
  int min_inliers = 10;

  template <class A>
  void visit(A& a) {
    a("max_corners", max_corners, "Corners detected in the previous left image",
      driftlab::yaml::in_range(10, 10000));
    a("min_corner_distance_px", min_corner_distance_px, "Least distance between two corners [px]",
      driftlab::yaml::positive());
    a("ransac_threshold_px", ransac_threshold_px, "PnP RANSAC reprojection threshold [px]",
      driftlab::yaml::positive());
    a("min_inliers", min_inliers, "Fewest PnP inliers for a motion", driftlab::yaml::at_least(4));
    a.require(min_inliers <= max_corners, "min_inliers", "no more than max_corners");
  }
};

class LkPnpVo final : public driftlab::vo::StereoOdometry {
 public:
  LkPnpVo(const driftlab::StereoRig& rig, driftlab::Rng rng, const LkPnpOptions& options = {});
  driftlab::vo::VoResult process(const driftlab::vo::StereoFrame& frame) override;
  void reset() override;
  std::string name() const override { return "lk_pnp"; }

 private:
  driftlab::StereoRig rig_;
  LkPnpOptions options_;
  driftlab::Rng initial_rng_, rng_;
  cv::Mat prev_left_, prev_right_;
};
