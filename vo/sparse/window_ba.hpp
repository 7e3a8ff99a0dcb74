// Sparse VO internals, optional refinement (`refine: window_ba`): a sliding-window bundle
// adjustment over the last window_frames frames, run after the frame-to-frame estimate of
// river paper Section 2.3.1 (iv). Not part of the river paper; it goes beyond frame-to-frame.
//
// Window state, all relative to the window anchor (the oldest frame, whose pose is the
// identity and stays fixed, which fixes the gauge; stereo fixes the scale):
//  - per frame: T_frame_anchor as angle-axis + translation (the Ceres parameter block), and,
//    for the newest frame, the left-image feature slot -> track map used to extend tracks;
//  - tracks: one 3D point per inlier circle match, triangulated by Eq. (1) from the stereo pair
//    of the frame it was first seen in, and its stereo observations (u_l, v_l, u_r) per frame.
//    A match of frame k continues the track that the match of frame k-1 with
//    slot_lc == slot_lp ended in.
// The problem is Eq. (2) summed over the window: for every observation the left and right
// reprojection errors (u_l, v_l, u_r, v_r = v_l), under a Huber loss, minimised over every pose
// but the anchor's and every point by Ceres (Levenberg-Marquardt, dense Schur, one thread, a
// fixed iteration cap: deterministic).
//
// Output: the refined newest pose relative to the refined previous one,
// T_prev_curr = T_{k-1}_anchor * T_anchor_k (initialised from the frame-to-frame estimate).
// Corrections the window makes to older poses are not fed back into poses already output
// (feeding them back, T_prev_curr = E_{k-1}^-1 T_anchor_k with E the output chain, was tried
// and gave larger accumulated errors on the test sequences). Internal to vo/sparse.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <vector>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "vo/sparse/circle_matcher.hpp"
#include "vo/sparse/sparse_options.hpp"

namespace driftlab::vo::sparse {

class WindowBundleAdjuster {
 public:
  WindowBundleAdjuster(const StereoRig& rig, const SparseVoOptions& options);
  ~WindowBundleAdjuster();
  WindowBundleAdjuster(const WindowBundleAdjuster&) = delete;
  WindowBundleAdjuster& operator=(const WindowBundleAdjuster&) = delete;

  /// Forgets the window (first frame, lost tracking): the next add_frame() starts a new window
  /// anchored at its previous frame.
  void reset();

  struct Result {
    bool ok = false;    ///< false: the refinement failed; the window was reset
    SE3 T_prev_curr;    ///< refined motion (the input one when !ok)
    int frames = 0;     ///< frames in the window after this call
    int tracks = 0;     ///< tracks (points) in the problem
    int residuals = 0;  ///< stereo observations in the problem
  };

  /// Adds the frame of a successful frame-to-frame estimate: `circles` are its matches with the
  /// previous frame, `inliers` the indices of those the estimate kept, `T_prev_curr` the
  /// estimate. Returns the refined motion.
  Result add_frame(std::span<const CircleMatch> circles, std::span<const int> inliers,
                   const SE3& T_prev_curr);

  /// Frames in the window (diagnostics, tests).
  int frames() const { return static_cast<int>(frames_.size()); }

 private:
  struct Observation {
    std::int32_t frame = 0;  ///< frame id (monotonic since reset)
    double u_l = 0, v_l = 0, u_r = 0;
  };
  struct Track {
    std::array<double, 3> p{};  ///< anchor frame [m]
    std::vector<Observation> obs;
  };
  struct Frame {
    std::int32_t id = 0;
    std::array<double, 6> pose{};  ///< T_frame_anchor: angle-axis [rad], translation [m]
  };

  void drop_oldest();
  bool solve(Result* result);
  std::size_t frame_index(std::int32_t id) const;

  StereoRig rig_;
  int window_frames_;
  std::vector<Frame> frames_;
  std::vector<Track> tracks_;
  std::vector<std::int32_t> slot_track_prev_;  ///< newest frame's left slot -> track, -1: none
  std::vector<std::int32_t> slot_track_next_;
  std::int32_t next_id_ = 0;
  struct Ceres;
  std::unique_ptr<Ceres> ceres_;
};

}  // namespace driftlab::vo::sparse
