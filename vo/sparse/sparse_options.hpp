// Options of the sparse stereo VO (river paper Section 2.3.1, after Geiger et al. 2011,
// "StereoScan"). Where the river paper states a value, that is the default ("paper"); values
// it does not state are marked with their origin: StereoScan's published implementation
// defaults ("StereoScan"), or ours, chosen on the exactly rendered sequences of tests/vo and
// explained here.
#pragma once

#include <array>
#include <utility>

#include "core/yaml_io.hpp"

namespace driftlab::vo {

/// What follows the frame-to-frame estimate of step (iv).
enum class SparseRefine {
  kNone,      ///< nothing: the river paper's frame-to-frame method
  kWindowBa,  ///< sliding-window bundle adjustment (Ceres) over the last window_frames frames
};
constexpr auto enum_table(SparseRefine) {
  return std::array{std::pair{SparseRefine::kNone, "none"},
                    std::pair{SparseRefine::kWindowBa, "window_ba"}};
}

/// How step (iv)'s RANSAC ranks its hypotheses.
enum class RansacScore {
  kInliers,  ///< the most inliers (river paper, StereoScan)
  /// MSAC (Torr and Zisserman 2000): the least sum over the matches of the squared
  /// reprojection error truncated at the inlier threshold, so of two hypotheses with as many
  /// inliers the one that fits them better wins.
  kMsac,
};
constexpr auto enum_table(RansacScore) {
  return std::array{std::pair{RansacScore::kInliers, "inliers"},
                    std::pair{RansacScore::kMsac, "msac"}};
}

struct SparseVoOptions {
  // --- (i) detection: 5x5 blob and corner masks, non-maximum/-minimum suppression -------------
  // The masks themselves are fixed (StereoScan Fig. 3); they are not options.
  int nms_radius_px = 3;   // StereoScan: windows of 7x7
  int nms_threshold = 50;  // StereoScan

  // --- (ii) description and matching ------------------------------------------------------------
  int descriptor_window_px = 11;  // paper: 11x11 windows of horizontal and vertical Sobel
  // Ours: rectified images put a point on the same row; 1 px absorbs the integer rounding of
  // two independently detected features.
  int stereo_row_tolerance_px = 1;
  // Ours: the nearest depth searched is fx B / 200 (0.3 m for B = 0.12 m, fx = 500; 1.9 m for
  // the KITTI rig); wider costs time in every stereo search.
  int max_disparity_px = 200;
  // Ours: 1 px of disparity is 60 m for the river paper's rig; farther points only add noise.
  double min_disparity_px = 1.0;
  // Ours: the largest image motion tracked (a 7 deg turn at fx = 500 is 61 px); the coarse
  // stage's cost grows with its square.
  int match_radius_px = 120;
  // StereoScan matches a sparse subset first to narrow the search for the rest; we do the same
  // with a motion prior from the subset (see the visit() documentation).
  bool two_stage_matching = true;
  int coarse_features_per_class = 4;  // ours: 4 per class, i.e. up to 16 candidates per bucket
  int prior_radius_px = 6;            // ours: the prior's prediction error stays below ~2 px
  // Ours: without it the motion errors on the 640x480 test rig (B = 0.12 m) grow 4-5x; on the
  // KITTI-like rig (B = 0.54 m) integer disparities are already good enough.
  bool subpixel_refinement = true;
  // Ours: the SAD fits lock to integer pixels (measured on a rendered river run: vertical flow
  // came out at 0.69 of the truth and far points looked still, so a slow straight run was
  // estimated 3x too short). Lucas-Kanade on the image intensities, started at the SAD
  // positions, removes the locking.
  bool lk_refinement = true;
  int lk_window_px = 11;         // ours: the descriptor's window
  double lk_max_shift_px = 1.0;  // ours: farther than this from the SAD match is another point

  // --- bucketing ------------------------------------------------------------------------------
  int bucket_width_px = 50;         // paper: 50x50 pixel windows
  int bucket_height_px = 50;        // paper
  int max_features_per_bucket = 2;  // paper: "reduced to two"

  // --- (iv) estimation: RANSAC around Gauss-Newton on Eq. (2) ----------------------------------
  int ransac_iterations = 50;                        // paper: "50 times"
  int ransac_sample_size = 3;                        // paper: "three randomly-selected matches"
  RansacScore ransac_score = RansacScore::kInliers;  // paper: the most inliers
  // Ours (the paper states none; libviso2's default is 2 px, for integer matches with a parabola
  // fit): the Lucas-Kanade refined matches are good to about 0.05 px on rendered frames, and at
  // the river paper's 0.2 m/s and 8.2 Hz a feature 25 m away moves about 0.6 px a frame. Within
  // 2 px every match fits almost any small motion, so RANSAC cannot tell the true motion from one
  // that a few wrong stereo matches pull (a horizontal edge matched at the wrong disparity looks
  // 3.5 m away and barely moves): on the crossing's 1,970 rendered frames, 132 of the 270 frames of
  // one straight leg came out 4x short. At 1 px: track length -8.4 % -> +0.1 %, e'_p 0.092 ->
  // 0.023 m/m (docs/vo-and-filters.md).
  double inlier_threshold_px = 1.0;
  // Ours: Gauss-Newton on Eq. (2) converges quadratically, in ~6 iterations from no motion;
  // the tolerance is far below any pixel-level effect.
  int gauss_newton_max_iterations = 20;
  double gauss_newton_step_tolerance = 1e-10;
  bool final_refinement = true;  // paper: final optimisation on the best iteration's inliers
  // Ours: fewer inliers than this is not a trustworthy 6-DOF motion.
  int min_inliers = 10;

  // --- refinement beyond the paper (vo/sparse/window_ba.hpp) ------------------------------------
  SparseRefine refine = SparseRefine::kNone;  // paper: frame-to-frame only
  int window_frames = 5;                      // ours: poses in the window, the oldest fixed

  // --- keyframes beyond the paper (the algorithm sparse_kf) -------------------------------------
  // Ours: at 0.17 m/s and 13 Hz a feature 20 m away moves 0.3 px per frame, below what
  // frame-to-frame matching resolves; matching against a keyframe until the image has moved
  // enough makes the motion per estimate several pixels (see the river figures in
  // docs/vo-and-filters.md).
  bool keyframes = false;              // paper: frame-to-frame
  double keyframe_min_flow_px = 12.0;  // ours: chosen on river_crossing (docs/vo-and-filters.md)
  int keyframe_min_inliers = 40;       // ours: below this the keyframe's overlap is thinning
  int keyframe_max_frames = 60;        // ours: about 4.6 s at the river paper's 13 Hz
  // Ours: beyond ~10 % the near points' patches no longer match (forward runs, shared VO suite).
  double keyframe_max_scale_change = 0.1;

  template <class A>
  void visit(A& a) {
    a("nms_radius_px", nms_radius_px,
      "Non-maximum/-minimum suppression radius n: a feature is the extremum of its (2n+1)^2 "
      "window [px] (StereoScan default)",
      yaml::in_range(1, 8));
    a("nms_threshold", nms_threshold,
      "Smallest |blob or corner filter response| of a feature [grey levels x mask weight] "
      "(StereoScan default)",
      yaml::in_range(1, 6000));
    a("descriptor_window_px", descriptor_window_px,
      "Side of the square window of Sobel responses compared by SAD [px] (river paper: 11)",
      yaml::in_range(3, 15));
    a.require(descriptor_window_px % 2 == 1, "descriptor_window_px", "an odd window side");
    a("stereo_row_tolerance_px", stereo_row_tolerance_px,
      "Largest row difference of a left/right match in the rectified images [px]",
      yaml::in_range(0, 4));
    a("max_disparity_px", max_disparity_px,
      "Largest disparity searched, i.e. nearest depth fx B / max_disparity_px [px]",
      yaml::in_range(1, 1000));
    a("min_disparity_px", min_disparity_px,
      "Smallest disparity of a match used for motion; farther points are dropped, since "
      "Eq. (1) makes their depth meaningless [px]",
      yaml::in_range(0.05, 100.0));
    a.require(min_disparity_px < max_disparity_px, "min_disparity_px",
              "min_disparity_px < max_disparity_px");
    a("match_radius_px", match_radius_px,
      "Half-width of the square window searched between previous and current images, i.e. the "
      "largest image motion tracked [px]",
      yaml::in_range(4, 1000));
    a("two_stage_matching", two_stage_matching,
      "Stage 1 circles the coarse features alone within match_radius_px and estimates a motion "
      "prior from them (RANSAC + Eq. (2)); stage 2 searches all features within prior_radius_px "
      "of where the prior puts them (StereoScan's speed-up). false: one stage, all features, "
      "match_radius_px windows (slower)");
    a("coarse_features_per_class", coarse_features_per_class,
      "Strongest features per class and bucket that take part in matching (all four classes "
      "together give the candidates of a bucket)",
      yaml::in_range(1, 16));
    a("prior_radius_px", prior_radius_px,
      "Half-width of the windows around the positions predicted by the motion prior [px]",
      yaml::in_range(1, 64));
    a("subpixel_refinement", subpixel_refinement,
      "Refine matched positions to sub-pixel precision by equiangular fits of the SAD costs");
    a("lk_refinement", lk_refinement,
      "Then refine the final matches by Lucas-Kanade tracking of the current left patch into "
      "the other three images (OpenCV calcOpticalFlowPyrLK, one level), which does not lock "
      "to integer pixels (ours, not in the paper)");
    a("lk_window_px", lk_window_px, "Lucas-Kanade window side [px], odd", yaml::in_range(5, 31));
    a.require(lk_window_px % 2 == 1, "lk_window_px", "an odd number");
    a("lk_max_shift_px", lk_max_shift_px,
      "A match whose Lucas-Kanade position is farther than this from its SAD position is "
      "dropped [px]",
      yaml::positive());
    a("bucket_width_px", bucket_width_px, "Bucket width [px] (river paper: 50)",
      yaml::in_range(8, 4096));
    a("bucket_height_px", bucket_height_px, "Bucket height [px] (river paper: 50)",
      yaml::in_range(8, 4096));
    a("max_features_per_bucket", max_features_per_bucket,
      "Matches kept per bucket (river paper: 2)", yaml::in_range(1, 64));
    a("ransac_iterations", ransac_iterations, "RANSAC iterations (river paper: 50)",
      yaml::in_range(1, 100000));
    a("ransac_sample_size", ransac_sample_size,
      "Matches drawn per RANSAC iteration (river paper: 3, the minimum for 6 DOF)",
      yaml::in_range(3, 64));
    a("ransac_score", ransac_score,
      "How RANSAC ranks its hypotheses: inliers, the most inliers (river paper); msac, the "
      "least sum of squared reprojection errors truncated at inlier_threshold_px (Torr and "
      "Zisserman 2000; a match's error is the larger of its left and right image's)");
    a("inlier_threshold_px", inlier_threshold_px,
      "Largest reprojection error, in the left and in the right image, of an inlier [px] (ours: "
      "the Lucas-Kanade refined matches are good to ~0.05 px; libviso2's default, 2 px, lets "
      "wrong stereo matches carry sub-pixel motions, see docs/twin-vs-paper.md)",
      yaml::positive());
    a("gauss_newton_max_iterations", gauss_newton_max_iterations,
      "Iteration limit of each Gauss-Newton minimisation of Eq. (2)", yaml::in_range(1, 1000));
    a("gauss_newton_step_tolerance", gauss_newton_step_tolerance,
      "Gauss-Newton stops when the update's norm (m and rad mixed) falls below this",
      yaml::positive());
    a("final_refinement", final_refinement,
      "Re-minimise Eq. (2) over all inliers of the best RANSAC iteration (river paper)");
    a("min_inliers", min_inliers, "Fewest inliers for a valid motion; fewer gives valid = false",
      yaml::in_range(3, 100000));
    a.require(min_inliers >= ransac_sample_size, "min_inliers",
              "min_inliers >= ransac_sample_size");
    a("refine", refine,
      "After the frame-to-frame estimate: none (river paper) or window_ba, a bundle adjustment "
      "of Eq. (2) over the last window_frames poses and their tracked points (Ceres)");
    a("window_frames", window_frames,
      "Frames in the window_ba window, the oldest of them fixed (used with refine: window_ba)",
      yaml::in_range(2, 20));
    a("keyframes", keyframes,
      "Match each frame against a keyframe instead of the previous frame, and move the keyframe "
      "to the current frame once the median inlier flow reaches keyframe_min_flow_px, the "
      "inliers fall below keyframe_min_inliers, the near points' scale changes by "
      "keyframe_max_scale_change, keyframe_max_frames have passed or the estimate fails (ours, "
      "beyond the paper; the algorithm sparse_kf turns it on)");
    a.require(!keyframes || refine == SparseRefine::kNone, "keyframes",
              "refine: none with keyframes (the window adjustment assumes consecutive frames)");
    a("keyframe_min_flow_px", keyframe_min_flow_px,
      "Median image motion of the inliers between keyframe and current left image that moves "
      "the keyframe [px]",
      yaml::in_range(0.0, 1000.0));
    a("keyframe_min_inliers", keyframe_min_inliers,
      "Fewer inliers against the keyframe than this moves the keyframe", yaml::in_range(0, 100000));
    a("keyframe_max_scale_change", keyframe_max_scale_change,
      "The keyframe also moves once the motion along the optical axis since it reaches this "
      "fraction of the near inliers' depth (their 10th percentile): the scale change of their "
      "patches",
      yaml::in_range(0.0, 1.0));
    a("keyframe_max_frames", keyframe_max_frames,
      "Most frames matched against one keyframe; 1 is frame-to-frame", yaml::in_range(1, 1000));
  }
};

}  // namespace driftlab::vo
