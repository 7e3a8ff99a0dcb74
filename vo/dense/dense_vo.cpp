#include "vo/dense/dense_vo.hpp"

#include <chrono>
#include <cmath>
#include <future>
#include <memory>
#include <utility>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "vo/dense/disparity.hpp"
#include "vo/dense/photometric.hpp"

namespace driftlab::vo {

namespace {

// Coarsest level side below which the alignment has too little to work with.
constexpr int kMinLevelSidePx = 8;

// What aligning the current image to the previous pair's reference gave, kept aside until the
// current pair's reference is done too.
struct AlignOutcome {
  bool ran = false;
  dense::AlignSummary summary;
  SE3 T_curr_prev;
  double ms = 0.0;
};

}  // namespace

namespace dense {

int sgbm_mode(DenseSgbmMode mode) {
  switch (mode) {
    case DenseSgbmMode::kSgbm:
      return cv::StereoSGBM::MODE_SGBM;
    case DenseSgbmMode::kHh:
      return cv::StereoSGBM::MODE_HH;
    case DenseSgbmMode::kThreeWay:
      return cv::StereoSGBM::MODE_SGBM_3WAY;
    case DenseSgbmMode::kHh4:
      return cv::StereoSGBM::MODE_HH4;
  }
  throw InternalError("sgbm_mode: unknown DenseSgbmMode");
}

DisparityOptions disparity_options(const DenseVoOptions& o) {
  DisparityOptions d;
  d.num_disparities = o.sgbm_num_disparities_px;
  d.block_size = o.sgbm_block_size_px;
  d.p1 = o.sgbm_p1;
  d.p2 = o.sgbm_p2;
  d.disp12_max_diff = o.sgbm_disp12_max_diff_px;
  d.pre_filter_cap = o.sgbm_pre_filter_cap;
  d.uniqueness_ratio = o.sgbm_uniqueness_ratio_pct;
  d.speckle_window = o.sgbm_speckle_window_px;
  d.speckle_range = o.sgbm_speckle_range_px;
  d.mode = sgbm_mode(o.sgbm_mode);
  d.downsample = o.effective_sgbm_downsample();
  d.refine_iterations = o.use_refine_disparity() ? o.refine_iterations : 0;
  d.refine_window = o.refine_window_px;
  d.refine_max_change = o.refine_max_change_px;
  d.refine_max_residual = o.refine_max_residual_grey;
  return d;
}

RefSelection ref_selection(const DenseVoOptions& o) {
  RefSelection s;
  s.min_disparity_px = o.min_disparity_px;
  s.gradient_mask = o.use_gradient_mask();
  s.min_gradient = o.min_gradient_grey_per_px;
  s.lower_mask_fraction = o.effective_lower_mask();
  return s;
}

AlignOptions align_options(const DenseVoOptions& o) {
  AlignOptions a;
  a.max_iterations = o.pyramid_max_iterations;
  a.initial_lambda = o.lm_initial_lambda;
  a.step_tolerance = o.lm_step_tolerance;
  a.robust = o.use_robust_weights();
  a.t_dof = o.t_dof;
  a.inlier_residual = o.inlier_residual_grey;
  return a;
}

}  // namespace dense

struct DenseStereoOdometry::Impl {
  // What one pair leaves behind: the current pair's, then (swapped) the previous pair's.
  struct FrameData {
    dense::Pyramid pyramid;
    cv::Mat disparity;  // CV_32FC1 [px]
    dense::Reference ref;
  };

  Impl(const StereoRig& rig_in, const DenseVoOptions& options_in)
      : rig(rig_in),
        options(options_in),
        stereo(std::make_unique<dense::DisparityEstimator>(dense::disparity_options(options_in))),
        selection(dense::ref_selection(options_in)),
        align(dense::align_options(options_in)) {
    for (FrameData* f : {&a, &b}) f->pyramid.configure(rig.camera, options.pyramid_scales);
  }

  // Stereo correspondence (SGBM disparity of the pair, refined) and Eq. (1)'s points and
  // Jacobians of `f`, the reference of the next call.
  void prepare_reference(const StereoFrame& frame, FrameData* f) {
    auto t = SteadyClock::now();
    stereo->compute(frame.left, frame.right, f->pyramid.images.back(), &f->disparity);
    stats.sgbm_ms = ms_since(t);
    t = SteadyClock::now();
    dense::build_reference(f->pyramid, f->disparity, rig.camera.fx * rig.baseline_m, selection,
                           &f->ref);
    stats.reference_ms = ms_since(t);
  }

  // Step 2: the current image `f` aligned to the previous pair's reference, from the
  // constant-velocity prior where there is one.
  AlignOutcome align_to_previous(const FrameData& f) {
    const auto t = SteadyClock::now();
    AlignOutcome out;
    out.ran = true;
    out.T_curr_prev = options.use_constant_velocity() && has_velocity ? last_T_curr_prev : SE3();
    out.summary = aligner.align(prev->ref, f.pyramid, align, &out.T_curr_prev);
    out.ms = ms_since(t);
    return out;
  }

  StereoRig rig;
  DenseVoOptions options;
  std::unique_ptr<dense::DisparityEstimator> stereo;
  dense::RefSelection selection;
  dense::AlignOptions align;
  dense::Aligner aligner;
  FrameData a, b;
  FrameData* cur = &a;
  FrameData* prev = &b;
  bool has_previous = false;
  // Constant-velocity prior: the last valid motion (T_curr_prev), if the last frame was valid.
  bool has_velocity = false;
  SE3 last_T_curr_prev;
  DenseFrameStats stats;
};

DenseStereoOdometry::DenseStereoOdometry(const StereoRig& rig, const DenseVoOptions& options,
                                         Rng /*rng*/) {
  const std::string rig_problems = validate(rig);
  if (!rig_problems.empty()) throw UserError("DenseStereoOdometry: invalid rig: " + rig_problems);
  yaml::validate_or_throw(options, "DenseStereoOdometry");
  const dense::LevelCamera coarsest = dense::level_camera(rig.camera, options.pyramid_scales[0]);
  if (coarsest.width < kMinLevelSidePx || coarsest.height < kMinLevelSidePx) {
    throw UserError("DenseStereoOdometry: pyramid_scales[0] = " +
                    yaml::format_double(options.pyramid_scales[0]) + " makes the coarsest level " +
                    std::to_string(coarsest.width) + "x" + std::to_string(coarsest.height) +
                    " px, expected at least " + std::to_string(kMinLevelSidePx) + " px a side");
  }
  if (options.sgbm_num_disparities_px >= rig.camera.width) {
    throw UserError("DenseStereoOdometry: sgbm_num_disparities_px: got " +
                    std::to_string(options.sgbm_num_disparities_px) +
                    ", expected less than the image width " + std::to_string(rig.camera.width));
  }
  const dense::DisparityOptions d = dense::disparity_options(options);
  const int shrunk_width = rig.camera.width / d.downsample;
  if (dense::searched_disparities(d) >= shrunk_width) {
    throw UserError("DenseStereoOdometry: sgbm_downsample: got " + std::to_string(d.downsample) +
                    ", which leaves SGBM a pair " + std::to_string(shrunk_width) +
                    " px wide to search " + std::to_string(dense::searched_disparities(d)) +
                    " disparities in; expected a smaller sgbm_downsample or "
                    "sgbm_num_disparities_px");
  }
  impl_ = std::make_unique<Impl>(rig, options);
}

DenseStereoOdometry::~DenseStereoOdometry() = default;

const DenseVoOptions& DenseStereoOdometry::options() const { return impl_->options; }
const DenseFrameStats& DenseStereoOdometry::last_stats() const { return impl_->stats; }
const cv::Mat& DenseStereoOdometry::last_disparity() const { return impl_->prev->disparity; }

void DenseStereoOdometry::reset() {
  impl_->has_previous = false;
  impl_->has_velocity = false;
  impl_->last_T_curr_prev = SE3();
  impl_->stats = {};
}

VoResult DenseStereoOdometry::process(const StereoFrame& frame) {
  Impl& s = *impl_;
  const auto t_start = detail::begin_frame(frame, s.rig.camera, "DenseStereoOdometry");
  VoResult result;
  s.stats = {};
  Impl::FrameData& cur = *s.cur;

  // Image preparation: the pyramid of the current left image (target now, reference next).
  auto t = SteadyClock::now();
  cur.pyramid.build(frame.left, s.options.pyramid_blur_sigma_px,
                    s.options.pyramid_area_downscaling);
  s.stats.pyramid_ms = ms_since(t);
  result.times.detect_ms = s.stats.pyramid_ms;

  // The current pair's disparity and reference (for the next call) on a second thread, while
  // this one aligns the current image to the previous reference: both only read the current
  // pyramid and write apart, so the bytes are those of doing the two in turn. The alignment
  // runs whenever the previous pair allows it; the checks below, in the serial order, decide
  // whether its result is used.
  std::future<void> reference =
      std::async(std::launch::async, [&s, &cur, &frame] { s.prepare_reference(frame, &cur); });
  AlignOutcome aligned;
  try {
    if (s.has_previous && s.prev->ref.textured_depth_pixels >= s.options.min_textured_pixels)
      aligned = s.align_to_previous(cur);
  } catch (...) {
    reference.wait();
    throw;
  }
  reference.get();
  s.stats.valid_depth_pixels = cur.ref.valid_depth_pixels;
  s.stats.textured_pixels = cur.ref.textured_pixels;
  s.stats.textured_depth_pixels = cur.ref.textured_depth_pixels;
  result.times.match_ms = s.stats.sgbm_ms + s.stats.reference_ms;

  // Whatever happens below, this pair is the next call's reference.
  struct Advance {
    Impl& s;
    ~Advance() {
      std::swap(s.cur, s.prev);
      s.has_previous = true;
    }
  } advance{s};

  auto finish = [&](const char* reason) {
    s.has_velocity = false;
    result.times.estimate_ms = s.stats.align_ms;
    detail::end_without_motion(&result, reason, t_start);
    return result;
  };

  if (!s.has_previous) return finish("first frame");
  const Impl::FrameData& prev = *s.prev;
  result.valid_depth_pixels = prev.ref.valid_depth_pixels;
  result.features = result.valid_depth_pixels;  // covariate f: pixels with depth (Table 4)
  s.stats.reference_points = static_cast<int>(prev.ref.levels.back().size());
  if (cur.ref.textured_pixels < s.options.min_textured_pixels)
    return finish("too little texture in the current left image (black, flat or water?)");
  if (!aligned.ran) return finish("too few textured pixels with valid depth in the previous frame");

  // Step 2 (Levenberg-Marquardt on Eq. (9), coarse to fine) ran beside the reference.
  const dense::AlignSummary& a = aligned.summary;
  s.stats.align_ms = aligned.ms;
  s.stats.iterations = a.iterations;
  s.stats.rms_residual_grey = a.rms_residual;
  s.stats.sigma_grey = a.sigma;
  result.matches = a.used;
  result.inliers = a.inliers;
  if (!a.ok) return finish(a.failure);
  if (a.textured_inliers < s.options.min_textured_pixels ||
      a.textured_inliers < s.options.min_inlier_fraction * a.textured_used)
    return finish("photometric residuals too large: the images do not align");

  result.times.estimate_ms = s.stats.align_ms;
  if (const char* why = detail::end_with_motion(&result, aligned.T_curr_prev.inverse(),
                                                a.mean_inlier_depth_m, t_start))
    return finish(why);
  s.has_velocity = true;
  s.last_T_curr_prev = aligned.T_curr_prev;
  return result;
}

}  // namespace driftlab::vo
