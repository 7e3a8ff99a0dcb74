// Sequences and ground truth that the dense VO's tests share (dense_vo_test.cpp,
// dense_components_test.cpp).
#pragma once

#include <opencv2/core.hpp>

#include "tests/vo/vo_test_sequences.hpp"

namespace driftlab::vo::test {

// The river bank at 640x480, five frames 0.5 m apart: straight ahead, and turning 2 deg a frame.
inline const Sequence& dense_straight_640() {
  static const Sequence s =
      make_sequence(river_bank_scene_640(), rig_640x480(), straight_poses(5, 0.5));
  return s;
}
inline const Sequence& dense_turn_640() {
  static const Sequence s =
      make_sequence(river_bank_scene_640(), rig_640x480(), turning_poses(5, 0.5, 2.0));
  return s;
}

// The disparity of the left image of a pose, from the ray-cast depths (0 where nothing is hit).
inline cv::Mat true_disparity(const Scene& scene, const StereoRig& rig, const SE3& T_scene_cam) {
  cv::Mat d(rig.camera.height, rig.camera.width, CV_32FC1, cv::Scalar(0));
  const SE3 T_cam_scene = T_scene_cam.inverse();
  for (int v = 0; v < d.rows; ++v)
    for (int u = 0; u < d.cols; ++u) {
      Vec3 p;
      if (scene_point(scene, rig.camera, T_scene_cam, u, v, &p))
        d.at<float>(v, u) = static_cast<float>(rig.disparity_from_depth((T_cam_scene * p).z()));
    }
  return d;
}

}  // namespace driftlab::vo::test
