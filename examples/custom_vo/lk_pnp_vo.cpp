#include "lk_pnp_vo.hpp"

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/video/tracking.hpp>

using driftlab::vo::StereoFrame;
using driftlab::vo::VoResult;

LkPnpVo::LkPnpVo(const driftlab::StereoRig& rig, driftlab::Rng rng, const LkPnpOptions& options)
    : rig_(rig), options_(options), initial_rng_(rng), rng_(rng) {}

void LkPnpVo::reset() {
  prev_left_.release();
  prev_right_.release();
  rng_ = initial_rng_;
}

VoResult LkPnpVo::process(const StereoFrame& frame) {
  VoResult r;
  const cv::Mat prev_left = prev_left_, prev_right = prev_right_;
  prev_left_ = frame.left.clone();
  prev_right_ = frame.right.clone();
  if (prev_left.empty()) {
    r.reason = "first frame";
    return r;
  }
  // Corners of the previous left image, followed into the previous right and the current left.
  std::vector<cv::Point2f> corners, in_right, in_current;
  // Corners bucketed over a 4 x 4 grid (as libviso2 buckets its features): without it the
  // strongest corners of the image, the glints of rippled water, crowd out the bank's.
  const int cells = 4;
  for (int row = 0; row < cells; ++row)
    for (int col = 0; col < cells; ++col) {
      const cv::Rect cell(col * prev_left.cols / cells, row * prev_left.rows / cells,
                          prev_left.cols / cells, prev_left.rows / cells);
      std::vector<cv::Point2f> found;
      cv::goodFeaturesToTrack(prev_left(cell), found, options_.max_corners / (cells * cells), 0.01,
                              options_.min_corner_distance_px);
      for (const cv::Point2f& p : found) corners.emplace_back(p.x + cell.x, p.y + cell.y);
    }
  if (corners.size() < 10) {
    r.reason = "too few corners";
    return r;
  }
  std::vector<unsigned char> ok_right, ok_current, ok_back, ok_since;
  std::vector<float> error;
  std::vector<cv::Point2f> back_in_left, back_in_prev;
  cv::calcOpticalFlowPyrLK(prev_left, prev_right, corners, in_right, ok_right, error);
  cv::calcOpticalFlowPyrLK(prev_left, frame.left, corners, in_current, ok_current, error);
  // Each match followed back must land where it started (the forward-backward check of Kalal
  // et al. 2010): water, sky and repeated texture give stereo matches that do not, and glints
  // on rippled water, which move with the wind and not with the scene, give tracks that do not.
  cv::calcOpticalFlowPyrLK(prev_right, prev_left, in_right, back_in_left, ok_back, error);
  cv::calcOpticalFlowPyrLK(frame.left, prev_left, in_current, back_in_prev, ok_since, error);
  // Points of the previous left camera (Z = fx B / disparity) and where they are now.
  const auto& c = rig_.camera;
  std::vector<cv::Point3f> points;
  std::vector<cv::Point2f> pixels;
  for (std::size_t i = 0; i < corners.size(); ++i) {
    const double disparity = corners[i].x - in_right[i].x;
    if (!ok_right[i] || !ok_current[i] || !ok_back[i] || !ok_since[i] ||
        std::abs(corners[i].y - in_right[i].y) > 1.0 ||
        cv::norm(back_in_left[i] - corners[i]) > 0.5 ||
        cv::norm(back_in_prev[i] - corners[i]) > 0.5 || disparity < 2.0)
      continue;
    const double z = c.fx * rig_.baseline_m / disparity;
    points.emplace_back((corners[i].x - c.cx) * z / c.fx, (corners[i].y - c.cy) * z / c.fy, z);
    pixels.push_back(in_current[i]);
  }
  r.matches = static_cast<int>(points.size());
  if (static_cast<int>(points.size()) < options_.min_inliers) {
    r.reason = "too few stereo matches";
    return r;
  }
  // PnP with RANSAC; OpenCV draws its samples from cv::theRNG(), seeded from our stream so
  // that the same frames give the same result.
  cv::theRNG().state = rng_.next_u64() | 1;
  const cv::Matx33d K(c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1);
  // From no motion (a frame period moves the camera little): far points constrain the
  // translation weakly, and the refinement then stays near the motion they allow.
  cv::Vec3d rvec(0, 0, 0), tvec(0, 0, 0);
  std::vector<int> inliers;
  if (!cv::solvePnPRansac(points, pixels, K, cv::noArray(), rvec, tvec, true, 200,
                          static_cast<float>(options_.ransac_threshold_px), 0.999, inliers) ||
      static_cast<int>(inliers.size()) < options_.min_inliers) {
    r.reason = "PnP failed";
    return r;
  }
  cv::Matx33d R;
  cv::Rodrigues(rvec, R);
  driftlab::Mat3 R_curr_prev;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) R_curr_prev(i, j) = R(i, j);
  // solvePnP maps previous-camera points into the current camera: T_curr_prev.
  const driftlab::SE3 T_curr_prev(driftlab::Quat(R_curr_prev),
                                  driftlab::Vec3(tvec[0], tvec[1], tvec[2]));
  r.T_prev_curr = T_curr_prev.inverse();
  r.valid = true;
  r.inliers = static_cast<int>(inliers.size());
  double depth = 0;
  for (int i : inliers) depth += points[i].z;
  r.mean_inlier_depth_m = depth / static_cast<double>(inliers.size());
  return r;
}
