#include "vo/sparse/sparse_vo.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>
#include <vector>

#include <opencv2/video/tracking.hpp>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "vo/sparse/circle_matcher.hpp"
#include "vo/sparse/features.hpp"
#include "vo/sparse/shared_detection.hpp"
#include "vo/sparse/stereo_motion.hpp"
#include "vo/sparse/window_ba.hpp"

namespace driftlab::vo {

using sparse::CircleMatch;
using sparse::StereoPointMatch;

struct SparseStereoOdometry::Impl {
  Impl(const StereoRig& rig_in, const SparseVoOptions& options_in, Rng rng_in,
       std::shared_ptr<sparse::SharedDetection> shared_in)
      : rig(rig_in),
        options(options_in),
        initial_rng(rng_in),
        rng(rng_in),
        detector(rig_in.camera.width, rig_in.camera.height, options_in),
        shared(shared_in ? std::move(shared_in)
                         : std::make_shared<sparse::SharedDetection>(
                               sparse::detection_settings(options_in))),
        matcher(rig_in, options_in),
        estimator(rig_in, options_in) {
    if (options_in.refine == SparseRefine::kWindowBa)
      window_ba = std::make_unique<sparse::WindowBundleAdjuster>(rig_in, options_in);
  }

  StereoRig rig;
  SparseVoOptions options;
  Rng initial_rng;
  Rng rng;
  sparse::PairDetector detector;
  // Where the pairs' features come from: shared with the run's other sparse VOs that detect
  // alike, or this VO's own.
  std::shared_ptr<sparse::SharedDetection> shared;
  SparseStereoOdometry::DetectionCounts counts;
  sparse::CircleMatcher matcher;
  sparse::StereoMotionEstimator estimator;
  std::unique_ptr<sparse::WindowBundleAdjuster> window_ba;  // refine: window_ba only
  // The current pair and the reference pair (the previous one, or the keyframe), each with
  // its features and, for lk_refinement, its images' LK pyramids.
  std::shared_ptr<const sparse::PairFeatures> cur, ref;
  bool has_previous = false;
  // keyframes: the motion from the reference (keyframe) to the previous frame, and how many
  // frames back the reference is from the current one.
  SE3 T_key_prev;
  int key_frames_back = 1;
  std::vector<CircleMatch> circles;
  std::vector<StereoPointMatch> points;
  std::vector<SparseMatchInfo> infos;
  // lk_refinement: reused point buffers. The pairs' pyramids (built once per pair, the left
  // one with its Scharr derivatives, which calcOpticalFlowPyrLK would otherwise compute again
  // for every track) serve the three tracks of this frame and, as the reference pair, those of
  // the frames that follow.
  std::vector<cv::Point2f> lk_from, lk_to;
  std::vector<unsigned char> lk_status;
  std::vector<float> lk_error;
  std::vector<unsigned char> lk_keep;

  // Tracks the current left patch of every circle into `target`, starting at (u, v) of each
  // circle as `get` gives it; `set` stores the result. A circle whose track fails or moves
  // farther than lk_max_shift_px is marked for removal.
  template <class Get, class Set>
  void lk_track(const std::vector<cv::Mat>& target, Get get, Set set) {
    lk_to.clear();
    for (const CircleMatch& c : circles) lk_to.push_back(get(c));
    const cv::TermCriteria stop(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 20, 0.005);
    cv::calcOpticalFlowPyrLK(cur->pyr_left, target, lk_from, lk_to, lk_status, lk_error,
                             cv::Size(options.lk_window_px, options.lk_window_px), 0, stop,
                             cv::OPTFLOW_USE_INITIAL_FLOW);
    for (std::size_t i = 0; i < circles.size(); ++i) {
      const cv::Point2f start = get(circles[i]);
      const cv::Point2f& end = lk_to[i];
      if (lk_status[i] == 0 || !std::isfinite(end.x) || !std::isfinite(end.y) ||
          std::hypot(end.x - start.x, end.y - start.y) > options.lk_max_shift_px) {
        lk_keep[i] = 0;
      } else {
        set(circles[i], end);
      }
    }
  }

  // The final circles' positions by Lucas-Kanade (SparseVoOptions::lk_refinement). The right
  // images are rectified, so only their columns are taken.
  void lk_refine() {
    lk_from.clear();
    for (const CircleMatch& c : circles)
      lk_from.emplace_back(static_cast<float>(c.u_lc), static_cast<float>(c.v_lc));
    lk_keep.assign(circles.size(), 1);
    lk_track(
        cur->pyr_right,
        [](const CircleMatch& c) { return cv::Point2f(float(c.u_rc), float(c.v_lc)); },
        [](CircleMatch& c, const cv::Point2f& p) { c.u_rc = p.x; });
    lk_track(
        ref->pyr_left,
        [](const CircleMatch& c) { return cv::Point2f(float(c.u_lp), float(c.v_lp)); },
        [](CircleMatch& c, const cv::Point2f& p) {
          c.u_lp = p.x;
          c.v_lp = p.y;
        });
    lk_track(
        ref->pyr_right,
        [](const CircleMatch& c) { return cv::Point2f(float(c.u_rp), float(c.v_lp)); },
        [](CircleMatch& c, const cv::Point2f& p) { c.u_rp = p.x; });
    const double dmin = options.min_disparity_px;
    std::size_t kept = 0;
    for (std::size_t i = 0; i < circles.size(); ++i) {
      const CircleMatch& c = circles[i];
      if (lk_keep[i] == 0 || !(c.u_lc - c.u_rc >= dmin) || !(c.u_lp - c.u_rp >= dmin)) continue;
      circles[kept++] = c;
    }
    circles.resize(kept);
  }

  // keyframes: whether the reference stays for the next frame, given this frame's inliers
  // against it and the motion from it (SparseVoOptions::keyframe_*).
  bool keeps_keyframe(const std::vector<int>& inliers, const SE3& T_ref_curr) {
    if (key_frames_back >= options.keyframe_max_frames) return false;
    if (static_cast<int>(inliers.size()) < options.keyframe_min_inliers) return false;
    std::vector<double> flow, depth;
    flow.reserve(inliers.size());
    depth.reserve(inliers.size());
    for (const int i : inliers) {
      const CircleMatch& c = circles[static_cast<std::size_t>(i)];
      flow.push_back(std::hypot(c.u_lc - c.u_lp, c.v_lc - c.v_lp));
      depth.push_back(rig.depth_from_disparity(c.u_lc - c.u_rc));  // Eq. (1)
    }
    auto quantile = [](std::vector<double>& v, double q) {
      const auto at =
          v.begin() + static_cast<std::ptrdiff_t>(q * static_cast<double>(v.size() - 1));
      std::nth_element(v.begin(), at, v.end());
      return *at;
    };
    if (quantile(flow, 0.5) >= options.keyframe_min_flow_px) return false;
    // Moving along the optical axis scales the near points' patches by about t_z / depth,
    // which the fixed-size descriptors and LK windows do not follow.
    const double near_depth_m = quantile(depth, 0.1);
    return std::abs(T_ref_curr.translation().z()) <
           options.keyframe_max_scale_change * near_depth_m;
  }

  // The matches as Eq. (2) sees them: previous-frame points by Eq. (1), current observations.
  void to_points() {
    points.clear();
    for (const CircleMatch& c : circles) {
      StereoPointMatch p;
      p.p_prev = rig.triangulate(Eigen::Vector2d(c.u_lp, c.v_lp), c.u_lp - c.u_rp);
      p.u_l = c.u_lc;
      p.v_l = c.v_lc;
      p.u_r = c.u_rc;
      p.v_r = c.v_lc;
      points.push_back(p);
    }
  }

  // Features of the current pair (and its LK pyramids, for lk_refinement).
  void detect(const StereoFrame& frame) {
    sparse::SharedDetection::Got got = shared->get(frame.left, frame.right, &detector);
    cur = std::move(got.features);
    ++(got.detected_here ? counts.detected : counts.shared);
  }

  // Why the current or the reference pair has too few features to match; nullptr if neither.
  const char* feature_shortage() const {
    const auto min_features = static_cast<std::size_t>(options.min_inliers);
    if (cur->left.all.features.size() < min_features ||
        cur->right.all.features.size() < min_features)
      return "too few features in the current images (no texture?)";
    if (ref->left.all.features.size() < min_features ||
        ref->right.all.features.size() < min_features)
      return "too few features in the previous images (no texture?)";
    return nullptr;
  }

  // One matching stage's motion estimate and how long its steps took.
  struct Stage {
    sparse::StereoMotionEstimator::Result est;
    double match_ms = 0.0, estimate_ms = 0.0;
  };

  // Circular matching (the coarse sets alone, or every feature, Lucas-Kanade refined when
  // lk_refinement, around the prior's predictions when there is one) and RANSAC on Eq. (2).
  Stage match_and_estimate(bool coarse_only, const SE3* prior) {
    Stage out;
    auto t = SteadyClock::now();
    matcher.match(cur->left, cur->right, ref->left, ref->right, coarse_only, prior, &circles);
    if (!coarse_only && options.lk_refinement && !circles.empty()) lk_refine();
    out.match_ms = ms_since(t);
    t = SteadyClock::now();
    to_points();
    // RANSAC hypotheses start from the prior when there is one: fewer Gauss-Newton iterations.
    out.est = estimator.estimate(points, &rng, prior != nullptr ? prior->inverse() : SE3());
    out.estimate_ms = ms_since(t);
    return out;
  }

  // The matches as last_matches() reports them, none an inlier yet.
  void record_matches() {
    for (const CircleMatch& c : circles)
      infos.push_back({c.u_lc, c.v_lc, c.u_rc, c.u_lp, c.v_lp, c.u_rp, false});
  }

  // Flags the inliers in last_matches() and returns their mean depth in the current pair.
  double flag_inliers(const std::vector<int>& inliers) {
    double depth_sum = 0.0;
    for (const int i : inliers) {
      const CircleMatch& c = circles[static_cast<std::size_t>(i)];
      infos[static_cast<std::size_t>(i)].inlier = true;
      depth_sum += rig.depth_from_disparity(c.u_lc - c.u_rc);  // Eq. (1), current pair
    }
    return depth_sum / static_cast<int>(inliers.size());
  }

  // On leaving process(): unless a keyframe stays the reference (keep_reference), the current
  // pair becomes the reference pair.
  struct Advance {
    Impl& s;
    bool keep_reference = false;
    ~Advance() {
      if (keep_reference) {
        ++s.key_frames_back;
        s.cur.reset();  // free for the next pair
        return;
      }
      s.ref = std::move(s.cur);
      s.has_previous = true;
      s.T_key_prev = SE3();
      s.key_frames_back = 1;
    }
  };
};

SparseStereoOdometry::SparseStereoOdometry(const StereoRig& rig, const SparseVoOptions& options,
                                           Rng rng,
                                           std::shared_ptr<sparse::SharedDetection> shared) {
  const std::string rig_problems = validate(rig);
  if (!rig_problems.empty()) throw UserError("SparseStereoOdometry: invalid rig: " + rig_problems);
  yaml::validate_or_throw(options, "SparseStereoOdometry");
  const int half = options.descriptor_window_px / 2;
  const int min_side = 2 * (half + 4) + 16;
  if (rig.camera.width < min_side || rig.camera.height < min_side) {
    throw UserError("SparseStereoOdometry: image of " + std::to_string(rig.camera.width) + "x" +
                    std::to_string(rig.camera.height) + " px is too small, expected at least " +
                    std::to_string(min_side) + " px a side");
  }
  if (shared && !(shared->settings() == sparse::detection_settings(options)))
    throw InternalError("SparseStereoOdometry: shared detection with other detection options");
  impl_ = std::make_unique<Impl>(rig, options, rng, std::move(shared));
}

SparseStereoOdometry::~SparseStereoOdometry() = default;

const SparseVoOptions& SparseStereoOdometry::options() const { return impl_->options; }

std::span<const MatchInfo> SparseStereoOdometry::last_matches() const { return impl_->infos; }

SparseStereoOdometry::DetectionCounts SparseStereoOdometry::detection_counts() const {
  return impl_->counts;
}

int SparseStereoOdometry::last_feature_count() const {
  return impl_->ref ? static_cast<int>(impl_->ref->left.all.features.size()) : 0;
}

void SparseStereoOdometry::reset() {
  impl_->has_previous = false;
  impl_->cur.reset();
  impl_->ref.reset();
  impl_->T_key_prev = SE3();
  impl_->key_frames_back = 1;
  impl_->rng = impl_->initial_rng;
  impl_->circles.clear();
  impl_->infos.clear();
  if (impl_->window_ba) impl_->window_ba->reset();
}

VoResult SparseStereoOdometry::process(const StereoFrame& frame) {
  Impl& s = *impl_;
  const auto t_start = detail::begin_frame(frame, s.rig.camera, "SparseStereoOdometry");
  VoResult result;
  s.circles.clear();
  s.infos.clear();

  s.detect(frame);
  result.times.detect_ms = ms_since(t_start);

  // Unless a keyframe stays the reference (keep_reference), this pair is the next call's
  // reference pair, whatever happens below.
  Impl::Advance advance{s};
  result.reference_frames_back = s.key_frames_back;

  auto finish = [&](std::string reason) {
    if (s.window_ba) s.window_ba->reset();  // the tracks break here
    detail::end_without_motion(&result, std::move(reason), t_start);
    return result;
  };

  if (!s.has_previous) return finish("first frame");
  if (const char* shortage = s.feature_shortage()) return finish(shortage);

  // Stage 1 (two_stage_matching): the coarse sets alone, wide windows, and a motion prior
  // from them; stage 2: every feature, narrow windows around the prior's predictions.
  double match_ms = 0.0, estimate_ms = 0.0;
  SE3 prior_T_prev_curr;
  const SE3* prior = nullptr;
  if (s.options.two_stage_matching) {
    const Impl::Stage coarse = s.match_and_estimate(/*coarse_only=*/true, nullptr);
    match_ms += coarse.match_ms;
    estimate_ms += coarse.estimate_ms;
    if (!coarse.est.ok) {
      result.matches = static_cast<int>(s.circles.size());
      result.times.match_ms = match_ms;
      result.times.estimate_ms = estimate_ms;
      return finish("coarse matching failed: " + coarse.est.failure);
    }
    prior_T_prev_curr = coarse.est.T_curr_prev.inverse();
    prior = &prior_T_prev_curr;
  }
  const Impl::Stage fine = s.match_and_estimate(/*coarse_only=*/false, prior);
  const auto& est = fine.est;
  result.times.match_ms = match_ms + fine.match_ms;
  result.times.estimate_ms = estimate_ms + fine.estimate_ms;
  result.matches = static_cast<int>(s.circles.size());

  s.record_matches();
  if (!est.ok) return finish(est.failure);
  const SE3 T_ref_curr = est.T_curr_prev.inverse();
  if (!detail::is_finite(T_ref_curr)) return finish("motion estimate not finite");
  // With a keyframe as the reference, the increment since the previous frame; the chain of
  // Eq. (3) then telescopes to keyframe pose * T_ref_curr.
  SE3 T_prev_curr = s.T_key_prev.inverse() * T_ref_curr;
  if (s.window_ba) {  // falls back to the frame-to-frame estimate when the window solve fails
    const auto t = SteadyClock::now();
    T_prev_curr = s.window_ba->add_frame(s.circles, *est.inliers, T_prev_curr).T_prev_curr;
    result.times.estimate_ms += ms_since(t);
  }

  result.inliers = static_cast<int>(est.inliers->size());
  if (const char* why =
          detail::end_with_motion(&result, T_prev_curr, s.flag_inliers(*est.inliers), t_start))
    return finish(why);
  if (s.options.keyframes && s.keeps_keyframe(*est.inliers, T_ref_curr)) {
    advance.keep_reference = true;
    s.T_key_prev = T_ref_curr;
  }
  return result;
}

}  // namespace driftlab::vo
