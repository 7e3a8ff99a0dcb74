// Options of the dense appearance-based stereo VO (river paper Section 2.3.2, after Steinbruecker
// et al. 2011 and Kerl et al. 2013). Where the river paper states a value, that is the default
// ("paper"). SGBM parameters are not in the paper: those defaults are OpenCV's documented
// recommendations ("OpenCV"). Values marked "ours" were chosen on tests/vo's exactly rendered
// sequences and say why.
#pragma once

#include <array>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "core/yaml_io.hpp"

namespace driftlab::vo {

/// Which variant of the alignment runs.
enum class DenseMethod {
  /// The river paper's plain method: least squares on Eq. (9) over every pixel with a valid
  /// depth, from the identity. The "extended method" switches below are ignored.
  kPaper,
  /// The paper's method plus what it says it lacked: robust weights, a constant-velocity
  /// initial guess and the texture / lower-image mask, each as switched below.
  kExtended,
};
constexpr auto enum_table(DenseMethod) {
  return std::array{std::pair{DenseMethod::kPaper, "paper"},
                    std::pair{DenseMethod::kExtended, "extended"}};
}

/// cv::StereoSGBM's mode. Every mode here gives the same disparity whatever OpenCV's thread count:
/// MODE_SGBM_3WAY splits the image into 4 stripes of rows and MODE_HH4 into its own pieces, both
/// fixed by OpenCV (calib3d/src/stereosgbm.cpp, "to make the results fully reproducible").
enum class DenseSgbmMode {
  kSgbm,      ///< MODE_SGBM: 5 path directions, single pass, one thread
  kHh,        ///< MODE_HH: full 8 directions, two passes (Hirschmueller 2008); slower
  kThreeWay,  ///< MODE_SGBM_3WAY: 3 directions (along the row both ways, down), 4 stripes in
              ///< parallel; the fastest
  kHh4,       ///< MODE_HH4: 8 directions, in parallel
};
constexpr auto enum_table(DenseSgbmMode) {
  return std::array{std::pair{DenseSgbmMode::kSgbm, "sgbm"}, std::pair{DenseSgbmMode::kHh, "hh"},
                    std::pair{DenseSgbmMode::kThreeWay, "3way"},
                    std::pair{DenseSgbmMode::kHh4, "hh4"}};
}

struct DenseVoOptions {
  DenseMethod method = DenseMethod::kExtended;

  // --- disparity: semi-global block matching (paper: [49], no parameters given) ----------------
  int sgbm_num_disparities_px = 64;    // ours: depths from f B / 64 (0.94 m on the 640x480 rig)
  int sgbm_block_size_px = 5;          // OpenCV: 3..11; 5 keeps thin structures
  int sgbm_p1 = 200;                   // OpenCV: 8 * block^2
  int sgbm_p2 = 800;                   // OpenCV: 32 * block^2
  int sgbm_disp12_max_diff_px = 1;     // left-right check; OpenCV's usual value
  int sgbm_pre_filter_cap = 63;        // OpenCV
  int sgbm_uniqueness_ratio_pct = 10;  // OpenCV: 5..15
  int sgbm_speckle_window_px = 100;    // OpenCV: 50..200
  int sgbm_speckle_range_px = 2;       // OpenCV: 1 or 2
  // ours: 3way: faster on one core than sgbm, parallel, and as accurate (the paper names no SGBM
  // variant; docs/vo-and-filters.md has the modes compared).
  DenseSgbmMode sgbm_mode = DenseSgbmMode::kThreeWay;
  // ours (extended only): SGBM on the pair shrunk 2x finds the depths to within a pixel at an
  // eighth of the cost; refine_disparity then makes them sub-pixel at full resolution.
  int sgbm_downsample = 2;
  double min_disparity_px = 1.0;  // ours: Eq. (1) needs D > 0; 1 px is 60 m on the paper's rig

  // --- alignment: Levenberg-Marquardt on Eq. (9) over an image pyramid (paper) -----------------
  std::vector<double> pyramid_scales{0.125, 0.25, 0.5, 1.0};  // paper, coarsest first
  std::vector<int> pyramid_max_iterations{40, 20, 3, 1};      // paper, coarsest first
  double pyramid_blur_sigma_px = 3.0;                         // paper
  // paper: bilinear. A sigma of 3 px leaves the 1/8 level aliased (its pixels are 8 px wide);
  // averaging instead extends the yaw rate the 640x480 rig tracks from 4 to 4.5 deg/frame (to 5
  // with sgbm_downsample 1).
  bool pyramid_area_downscaling = false;
  double lm_initial_lambda = 1e-4;  // ours: Gauss-Newton steps are good from the start
  double lm_step_tolerance = 1e-6;  // ours: 1 um / 1 urad, far below the errors reached

  // --- beyond the paper (method: extended) ------------------------------------------------------
  // ours: SGBM's sub-pixel disparities are biased by up to 0.2-0.3 px on tests/vo's scenes, and
  // a disparity error moves a warped pixel by |t| / B times as much (4 px per px at 0.5 m/frame
  // on the paper's rig), whatever the depth; refinement brings the bias below ~0.02 px.
  bool refine_disparity = true;
  // ours: 2 after SGBM on the shrunk pair (worst errors on tests/vo's sequences 0.6-0.9x those
  // of 1 iteration after SGBM on the full pair); after SGBM on the full pair 1 is enough
  int refine_iterations = 2;
  int refine_window_px = 9;           // ours
  double refine_max_change_px = 1.0;  // ours: a larger change means SGBM's match was wrong
  // ours: matched windows of tests/vo's scenes stay within a few grey levels RMS; a right image
  // of noise (a faulty camera) leaves ~100, yet SGBM on a shrunk pair matches 10 % of it.
  double refine_max_residual_grey = 16.0;
  bool robust_weights = true;        // Kerl et al. 2013: t-distribution weights
  double t_dof = 5.0;                // Kerl et al. 2013: nu = 5
  bool constant_velocity = true;     // start from the last motion rather than the identity
  bool gradient_mask = true;         // keep only pixels whose gradient reaches min_gradient below
  double mask_lower_fraction = 0.0;  // ours: 0 (the test scenes' lower image is textured ground)

  // --- validity of a result (both methods) -------------------------------------------------------
  // ours: tests/vo's water renders peak at 0.71 grey/px (8-bit steps of smooth ripples); a
  // quarter of the textured banks' pixels reach 5 grey/px, and aligning those alone is as
  // accurate as aligning the 70% above 2 grey/px, in under half the time (bench/dense_bench.cpp).
  // Also above the gradients of 2-3 grey levels of sensor noise.
  double min_gradient_grey_per_px = 5.0;
  int min_textured_pixels = 2000;      // ours: ~1% of a 640x480 image
  double inlier_residual_grey = 16.0;  // ours: 3-5x the noise of real cameras
  // ours: on tests/vo's scenes aligned frames have >99% of their textured pixels within
  // inlier_residual_grey, frames that converged to a wrong motion 60-70%; an occluder that
  // covers 8% of the view still leaves >90%.
  double min_inlier_fraction = 0.8;

  /// The plain method of the river paper (method: paper), otherwise the defaults.
  static DenseVoOptions paper() {
    DenseVoOptions o;
    o.method = DenseMethod::kPaper;
    return o;
  }

  /// True when a beyond-the-paper switch is in effect (method extended and the switch on).
  bool use_refine_disparity() const { return method == DenseMethod::kExtended && refine_disparity; }
  /// SGBM's shrink factor: the paper runs SGBM on the full pair, and so does a VO that does
  /// not refine (a shrunk pair's disparities are only as fine as its pixels).
  int effective_sgbm_downsample() const { return use_refine_disparity() ? sgbm_downsample : 1; }
  bool use_robust_weights() const { return method == DenseMethod::kExtended && robust_weights; }
  bool use_constant_velocity() const {
    return method == DenseMethod::kExtended && constant_velocity;
  }
  bool use_gradient_mask() const { return method == DenseMethod::kExtended && gradient_mask; }
  double effective_lower_mask() const {
    return method == DenseMethod::kExtended ? mask_lower_fraction : 0.0;
  }

  template <class A>
  void visit(A& a) {
    a("method", method,
      "paper: the river paper's plain least squares on Eq. (9) over every pixel with a valid "
      "depth, from the identity (the extended switches below are ignored); extended: plus the "
      "switches refine_disparity, robust_weights, constant_velocity, gradient_mask and "
      "mask_lower_fraction");
    a("sgbm_num_disparities_px", sgbm_num_disparities_px,
      "Disparity search range of cv::StereoSGBM, a multiple of 16; the nearest depth is "
      "f B / this [px]",
      yaml::in_range(16, 1024));
    a.require(sgbm_num_disparities_px % 16 == 0, "sgbm_num_disparities_px", "a multiple of 16");
    a("sgbm_block_size_px", sgbm_block_size_px, "Side of SGBM's matched blocks, odd [px]",
      yaml::in_range(1, 11));
    a.require(sgbm_block_size_px % 2 == 1, "sgbm_block_size_px", "an odd block side");
    a("sgbm_p1", sgbm_p1, "SGBM penalty of a disparity change by 1 between neighbours",
      yaml::in_range(0, 100000));
    a("sgbm_p2", sgbm_p2, "SGBM penalty of a disparity change by more than 1; must exceed sgbm_p1",
      yaml::in_range(1, 100000));
    a.require(sgbm_p2 > sgbm_p1, "sgbm_p2", "sgbm_p2 > sgbm_p1");
    a("sgbm_disp12_max_diff_px", sgbm_disp12_max_diff_px,
      "Largest difference of the left-right consistency check; -1 disables [px]",
      yaml::in_range(-1, 1000));
    a("sgbm_pre_filter_cap", sgbm_pre_filter_cap, "Clip of SGBM's prefiltered x-derivative",
      yaml::in_range(1, 63));
    a("sgbm_uniqueness_ratio_pct", sgbm_uniqueness_ratio_pct,
      "Margin by which the best matching cost must beat the second best [%]",
      yaml::in_range(0, 100));
    a("sgbm_speckle_window_px", sgbm_speckle_window_px,
      "Largest connected disparity region treated as a speckle and invalidated; 0 disables "
      "[px^2]",
      yaml::in_range(0, 100000));
    a("sgbm_speckle_range_px", sgbm_speckle_range_px,
      "Largest disparity variation inside one connected region of the speckle filter [px]",
      yaml::in_range(0, 64));
    a("sgbm_mode", sgbm_mode,
      "cv::StereoSGBM mode: sgbm (5 directions), hh (8, two passes), 3way (3, in 4 stripes "
      "of rows on OpenCV's threads: the fastest), hh4 (8, on OpenCV's threads); each gives the "
      "same bytes at any thread count");
    a("sgbm_downsample", sgbm_downsample,
      "extended, with refine_disparity: run SGBM on the pair shrunk by this factor (pixel "
      "averaging) over sgbm_num_disparities_px / this disparities, and take its disparity back "
      "to full resolution for refine_disparity; 1 runs SGBM on the full pair (as the paper and "
      "a VO without refinement do)",
      yaml::in_range(1, 4));
    a("min_disparity_px", min_disparity_px,
      "Pixels with a smaller disparity have no valid depth by Eq. (1) [px]",
      yaml::in_range(1.0 / 16.0, 1024.0));
    a("pyramid_scales", pyramid_scales,
      "Image scale of each pyramid level, coarsest first, strictly increasing, the last 1 "
      "(paper: 0.125, 0.25, 0.5, 1)",
      yaml::size_between(1, 8) & yaml::greater_than(0.0) & yaml::at_most(1.0));
    bool increasing = !pyramid_scales.empty() && pyramid_scales.back() == 1.0;
    for (std::size_t k = 1; k < pyramid_scales.size(); ++k)
      increasing = increasing && pyramid_scales[k - 1] < pyramid_scales[k];
    a.require(increasing, "pyramid_scales", "strictly increasing scales ending at 1");
    a("pyramid_max_iterations", pyramid_max_iterations,
      "Most Levenberg-Marquardt iterations on each level, coarsest first (paper: 40, 20, 3, 1)",
      yaml::size_between(1, 8) & yaml::in_range(0, 10000));
    a.require(pyramid_max_iterations.size() == pyramid_scales.size(), "pyramid_max_iterations",
              "one entry per pyramid_scales entry");
    a("pyramid_blur_sigma_px", pyramid_blur_sigma_px,
      "Standard deviation of the Gaussian blur applied to the full image before it is "
      "downscaled (bilinear) to the coarser levels; 0 disables (paper: 3) [px]",
      yaml::in_range(0.0, 20.0));
    a("pyramid_area_downscaling", pyramid_area_downscaling,
      "Make the coarser levels by averaging the (blurred) pixels each level pixel covers "
      "(cv::INTER_AREA) instead of the paper's bilinear interpolation, which aliases at 1/8");
    a("lm_initial_lambda", lm_initial_lambda,
      "Initial Levenberg-Marquardt damping, relative to the diagonal of J^T W J; x10 after a "
      "rejected step, /10 after an accepted one",
      yaml::in_range(0.0, 1e6));
    a("lm_step_tolerance", lm_step_tolerance,
      "A level stops when the norm of the step [translation m; rotation rad] is below this",
      yaml::in_range(0.0, 1.0));
    a("refine_disparity", refine_disparity,
      "extended: refine SGBM's disparity by Lucas-Kanade along the rows (one correction per "
      "window, iterated): removes the bias of SGBM's sub-pixel interpolation");
    a("refine_iterations", refine_iterations, "Lucas-Kanade iterations of refine_disparity",
      yaml::in_range(1, 20));
    a("refine_window_px", refine_window_px, "Side of the windows of refine_disparity, odd [px]",
      yaml::in_range(3, 31));
    a.require(refine_window_px % 2 == 1, "refine_window_px", "an odd window side");
    a("refine_max_change_px", refine_max_change_px,
      "Pixels whose disparity refine_disparity moves farther than this lose their depth [px]",
      yaml::greater_than(0.0) & yaml::at_most(16.0));
    a("refine_max_residual_grey", refine_max_residual_grey,
      "Pixels whose refined match leaves an RMS residual |L(x) - R(x - d)| over their "
      "refine_window_px window above this lose their depth [grey levels]",
      yaml::greater_than(0.0) & yaml::at_most(255.0));
    a("robust_weights", robust_weights,
      "extended: weight residuals by the t-distribution (Kerl et al. 2013), its scale "
      "re-estimated after every accepted step");
    a("t_dof", t_dof, "Degrees of freedom nu of the t-distribution (Kerl et al. 2013: 5)",
      yaml::in_range(0.5, 1000.0));
    a("constant_velocity", constant_velocity,
      "extended: start each frame from the previous valid motion instead of the identity");
    a("gradient_mask", gradient_mask,
      "extended: use only pixels whose full-resolution gradient reaches "
      "min_gradient_grey_per_px (coarse levels: pixels that cover at least half such pixels): "
      "drops water, sky and other flat areas, which carry no motion information but noise, and "
      "speeds the alignment up");
    a("mask_lower_fraction", mask_lower_fraction,
      "extended: ignore this lower fraction of the image (where water fills the view of a "
      "level camera on a vessel); 0 keeps the whole image",
      yaml::in_range(0.0, 0.9));
    a("min_gradient_grey_per_px", min_gradient_grey_per_px,
      "Gradient magnitude (central differences, grey levels per full-resolution pixel) from "
      "which a pixel counts as textured",
      yaml::in_range(0.0, 255.0));
    a("min_textured_pixels", min_textured_pixels,
      "Fewest textured pixels the current left image, and textured pixels with a valid depth "
      "the previous one, need for a valid motion",
      yaml::in_range(16, 100000000));
    a("inlier_residual_grey", inlier_residual_grey,
      "A pixel is an inlier when its Eq. (9) residual at the estimated motion is within this "
      "[grey levels]",
      yaml::greater_than(0.0) & yaml::at_most(255.0));
    a("min_inlier_fraction", min_inlier_fraction,
      "Fewest inliers, as a fraction of the textured pixels compared at full resolution, of a "
      "valid motion (flat pixels are left out: their residuals stay small whatever the motion)",
      yaml::in_range(0.0, 1.0));
  }

  /// "" when valid, else one "field: got V, expected E" per problem, one per line.
  std::string validate() const { return yaml::validate(*this); }
};

}  // namespace driftlab::vo
