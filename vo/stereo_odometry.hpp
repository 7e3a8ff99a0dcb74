// The stereo visual odometry interface every VO implementation (sparse/, dense/, pnp/) follows.
// A VO sees rectified stereo pairs and the rig only, never ground truth (docs/design.md,
// "Layers").
#pragma once

#include <span>
#include <string>

#include <opencv2/core/mat.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "core/stopwatch.hpp"
#include "core/time.hpp"

namespace driftlab::vo {

/// One rectified stereo pair: left and right images, CV_8UC1, both of the rig's width x height.
struct StereoFrame {
  TimeNs t_ns = 0;  ///< capture time [ns]; carried through, not used by the estimators
  cv::Mat left;     ///< rectified left image, CV_8UC1
  cv::Mat right;    ///< rectified right image, CV_8UC1
};

/// Wall-clock time of the stages of one process() call [ms]. Detection comes first; matching
/// and estimation may run side by side (the dense VO computes the new pair's disparity while it
/// aligns to the previous pair), so total_ms >= detect_ms + max(match_ms, estimate_ms).
struct VoStageTimes {
  double detect_ms = 0.0;    ///< feature detection / image preparation of the new pair
  double match_ms = 0.0;     ///< correspondence search (dense: disparity and reference points)
  double estimate_ms = 0.0;  ///< motion estimation (RANSAC, Gauss-Newton; dense: alignment)
  double total_ms = 0.0;     ///< the whole call
};

/// Outcome of one process() call.
///
/// Policy shared by every implementation:
/// - The first frame after construction or reset() returns valid = false with reason
///   "first frame" and identity motion: there is nothing to move from yet, and the river paper
///   updates the global pose "after each frame (apart from the very first)" (Eq. (3)).
/// - When tracking fails, valid = false, `reason` says why, and T_prev_curr is the identity.
///   The VO still advances: the next result is relative to the frame that failed.
/// - No field is ever NaN or infinite.
struct VoResult {
  bool valid = false;
  std::string reason;  ///< empty when valid; why not, otherwise
  SE3 T_prev_curr;     ///< motion since the previous frame: p_prev = T_prev_curr * p_curr,
                       ///< left camera, OpenCV optical frame (x right, y down, z forward)
  int matches = 0;     ///< correspondences handed to the estimator
  int inliers = 0;     ///< of those, consistent with the estimated motion
  double mean_inlier_depth_m =
      0.0;                     ///< mean optical-axis depth of the inliers, current frame [m]
                               ///< (dense: of the pixels used; covariate d of the river paper)
  int valid_depth_pixels = 0;  ///< dense VO: pixels with a valid depth in the depth map the motion
                               ///< was estimated from; others: 0
  int features = -1;           ///< covariate f of the river paper (Table 4) as this VO counts its
                      ///< features: the dense VO sets its valid-depth pixels; -1 (not set):
                      ///< the inliers, as for the feature VOs. Read it with feature_count().
  int reference_frames_back = 1;  ///< how many frames before this one the frame was that the
                                  ///< motion was measured from (1: the previous frame; more
                                  ///< with keyframes); T_prev_curr is still relative to the
                                  ///< previous frame
  VoStageTimes times;

  /// Covariate f: `features` when the VO set it, the inliers otherwise.
  int feature_count() const { return features >= 0 ? features : inliers; }
  /// One line for logs: "valid, 212/240 inliers, depth 7.3 m, 3.1 ms" or the reason.
  std::string brief() const;
};

/// A match as the last process() call used it (diagnostics, the river paper's Fig. 3, tests):
/// pixels [px].
struct MatchInfo {
  double u_lc = 0, v_lc = 0;  ///< current left
  double u_rc = 0;            ///< current right (row v_lc)
  double u_lp = 0, v_lp = 0;  ///< previous left
  double u_rp = 0;            ///< previous right (row v_lp)
  bool inlier = false;
};

/// A stereo visual odometry. Implementations are stateful (they keep the previous frame) and
/// deterministic: the same frames in the same order give the same results, byte for byte
/// (stage times aside).
class StereoOdometry {
 public:
  virtual ~StereoOdometry();

  /// Motion from the previous frame to this one. Throws UserError when the images are not
  /// CV_8UC1 of the rig's size.
  virtual VoResult process(const StereoFrame& frame) = 0;
  /// Forget the previous frame (the next process() is a first frame again) and restore the
  /// initial random state, so a reset VO repeats its results.
  virtual void reset() = 0;
  /// Short identifier, as in scenario files and estimate file names ("sparse").
  virtual std::string name() const = 0;
  /// The feature matches of the last process() call, for drawing; empty for a VO without
  /// discrete matches (dense) or that does not report them.
  virtual std::span<const MatchInfo> last_matches() const { return {}; }
};

/// Global pose update of river paper Eq. (3), H_hat <- H_hat * H: the pose of the current
/// camera in the world from the previous one and a result. Invalid results leave it unchanged.
SE3 accumulate_pose(const SE3& T_world_prev, const VoResult& result);

/// Helpers every implementation shares.
namespace detail {
/// The start of a process() call: throws UserError unless both images of `frame` are CV_8UC1
/// images of the camera's size (`who`, the VO, and the image named in the message), and returns
/// the time the call's total is counted from.
SteadyClock::time_point begin_frame(const StereoFrame& frame, const PinholeCamera& camera,
                                    const char* who);
/// True when every number of T is finite.
bool is_finite(const SE3& T);
/// The end of a process() call without a motion: `result` invalid for `reason`, with the
/// identity motion, no depth, and the call's total time since `t_start`.
void end_without_motion(VoResult* result, std::string reason, SteadyClock::time_point t_start);
/// The end of a process() call with a motion: `result` valid with T_prev_curr and the mean
/// inlier depth, and the call's total time since `t_start`. Returns what makes that impossible
/// ("motion estimate not finite", "mean depth not finite"; `result` untouched), nullptr when
/// nothing does.
const char* end_with_motion(VoResult* result, const SE3& T_prev_curr, double mean_inlier_depth_m,
                            SteadyClock::time_point t_start);
}  // namespace detail

}  // namespace driftlab::vo
