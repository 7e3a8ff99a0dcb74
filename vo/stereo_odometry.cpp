#include "vo/stereo_odometry.hpp"

#include "core/error.hpp"

#include <cstdio>

namespace driftlab::vo {

StereoOdometry::~StereoOdometry() = default;

std::string VoResult::brief() const {
  char buf[160];
  if (valid) {
    std::snprintf(buf, sizeof(buf), "valid, %d/%d inliers, depth %.2f m, %.2f ms", inliers, matches,
                  mean_inlier_depth_m, times.total_ms);
  } else {
    std::snprintf(buf, sizeof(buf), "invalid (%s), %d/%d inliers, %.2f ms", reason.c_str(), inliers,
                  matches, times.total_ms);
  }
  return buf;
}

SE3 accumulate_pose(const SE3& T_world_prev, const VoResult& result) {
  // Eq. (3), Kriechbaumer 2015: H_hat <- H_hat H, with H = T_prev_curr.
  return result.valid ? T_world_prev * result.T_prev_curr : T_world_prev;
}

namespace {

void check_image(const cv::Mat& image, const PinholeCamera& camera, const char* who,
                 const char* which) {
  if (image.empty() || image.type() != CV_8UC1 || image.cols != camera.width ||
      image.rows != camera.height) {
    throw UserError(std::string(who) + ": " + which + " image: got " + std::to_string(image.cols) +
                    "x" + std::to_string(image.rows) + " of type " + std::to_string(image.type()) +
                    ", expected " + std::to_string(camera.width) + "x" +
                    std::to_string(camera.height) + " CV_8UC1");
  }
}

}  // namespace

namespace detail {

SteadyClock::time_point begin_frame(const StereoFrame& frame, const PinholeCamera& camera,
                                    const char* who) {
  check_image(frame.left, camera, who, "left");
  check_image(frame.right, camera, who, "right");
  return SteadyClock::now();
}

bool is_finite(const SE3& T) {
  return T.translation().allFinite() && T.quaternion().coeffs().allFinite();
}

void end_without_motion(VoResult* result, std::string reason, SteadyClock::time_point t_start) {
  result->valid = false;
  result->reason = std::move(reason);
  result->T_prev_curr = SE3();
  result->mean_inlier_depth_m = 0.0;
  result->times.total_ms = ms_since(t_start);
}

const char* end_with_motion(VoResult* result, const SE3& T_prev_curr, double mean_inlier_depth_m,
                            SteadyClock::time_point t_start) {
  if (!is_finite(T_prev_curr)) return "motion estimate not finite";
  if (!std::isfinite(mean_inlier_depth_m)) return "mean depth not finite";
  result->valid = true;
  result->T_prev_curr = T_prev_curr;
  result->mean_inlier_depth_m = mean_inlier_depth_m;
  result->times.total_ms = ms_since(t_start);
  return nullptr;
}

}  // namespace detail

}  // namespace driftlab::vo
