#include "vo/pnp/pnp_vo.hpp"

#include <chrono>
#include <cmath>
#include <utility>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/core.hpp>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "vo/pnp/pnp_features.hpp"
#include "vo/pnp/pnp_subpixel.hpp"

namespace driftlab::vo {

using pnp::FeatureSet;
using pnp::IndexMatch;

namespace pnp {

// A previous-frame 3D point and the current left pixel it was matched to.
struct Correspondences {
  std::vector<cv::Point3d> object;  // previous left optical frame [m]
  std::vector<cv::Point2d> image;   // current left image [px]
  void clear() {
    object.clear();
    image.clear();
  }
};

}  // namespace pnp

struct PnpStereoOdometry::Impl {
  Impl(const StereoRig& rig_in, const PnpVoOptions& options_in, Rng rng_in)
      : rig(rig_in),
        options(options_in),
        initial_rng(rng_in),
        rng(rng_in),
        extractor(options_in, rig_in.camera.width, rig_in.camera.height),
        aligner(options_in.alignment_window_px / 2, /*max_iterations=*/30,
                options_in.alignment_max_shift_px) {
    K = (cv::Mat_<double>(3, 3) << rig.camera.fx, 0.0, rig.camera.cx, 0.0, rig.camera.fy,
         rig.camera.cy, 0.0, 0.0, 1.0);
  }

  StereoRig rig;
  PnpVoOptions options;
  Rng initial_rng;
  Rng rng;
  pnp::FeatureExtractor extractor;
  pnp::PatchAligner aligner;
  cv::Mat K;
  // The searched (cropped) part of the left and right images as CV_32F, for the alignment;
  // current (1) and previous (0) left.
  cv::Mat left_f1, left_f0, right_f;

  FeatureSet left, right;
  std::vector<IndexMatch> stereo, temporal;
  // The stereo points of a pair: left pixel, left descriptor, 3D point by Eq. (1). Current (1)
  // and previous (0); swapped, never copied, after each frame.
  FeatureSet points1, points0;
  std::vector<cv::Point3d> xyz1, xyz0;
  bool has_previous = false;
  pnp::Correspondences corr;
  std::vector<int> inliers;
  PnpFrameStats stats;

  int max_hamming(int bits) const {
    return static_cast<int>(std::floor(options.max_hamming_fraction * bits));
  }

  // Step 3: cross-checked Hamming matching along the epipolar row within the disparity range,
  // and a 3D point per match.
  void build_stereo_points() {
    points1.px.clear();
    xyz1.clear();
    points1.descriptors.release();
    if (left.size() == 0 || right.size() == 0) return;
    pnp::MatchWindow w;
    w.row_band_px = options.stereo_row_tolerance_px;
    // Right = left - disparity.
    w.du_min_px = -options.max_disparity_px;
    w.du_max_px = -options.min_disparity_px;
    pnp::match_features(left.px, left.descriptors, right.px, right.descriptors, w,
                        max_hamming(left.bits()), options.cross_check, &stereo);
    points1.descriptors.create(static_cast<int>(stereo.size()), left.descriptors.cols, CV_8UC1);
    int kept = 0;
    for (std::size_t k = 0; k < stereo.size(); ++k) {
      const cv::Point2f& pl = left.px[static_cast<std::size_t>(stereo[k].a)];
      cv::Point2f pr = right.px[static_cast<std::size_t>(stereo[k].b)];
      if (options.subpixel_alignment) {
        // The left window's position in the right image, along the row: the disparity of the
        // left corner itself, not of the right image's own (differently quantised) corner.
        pr.y = pl.y;
        if (!aligner.align(left_f1, pl, right_f, /*horizontal_only=*/true, &pr)) continue;
        const double d = static_cast<double>(pl.x) - pr.x;
        if (d < options.min_disparity_px || d > options.max_disparity_px) continue;
      }
      // Basin paper Eq. (1) is OpenCV's reprojection through Q; for a rectified pair with a
      // common principal point (c_xl = c_xr) it is river paper Eq. (1): Z = f B / (x_l - x_r),
      // X = Z (x_l - c_x) / f, Y = Z (y_l - c_y) / f.
      const Vec3 p = rig.triangulate(Eigen::Vector2d(pl.x, pl.y), static_cast<double>(pl.x) - pr.x);
      points1.px.push_back(pl);
      xyz1.emplace_back(p.x(), p.y(), p.z());
      left.descriptors.row(stereo[k].a).copyTo(points1.descriptors.row(kept++));
    }
    points1.descriptors.resize(static_cast<std::size_t>(kept));
  }

  // Inliers of a pose (rvec, tvec: previous -> current) by reprojection into the current left
  // image; points that end up behind the camera are outliers.
  void select_inliers(const cv::Vec3d& rvec, const cv::Vec3d& tvec, std::vector<int>* out) const {
    out->clear();
    const Mat3 R = so3_exp(Vec3(rvec[0], rvec[1], rvec[2])).toRotationMatrix();
    const Vec3 t(tvec[0], tvec[1], tvec[2]);
    const double thr2 = options.ransac_reprojection_px * options.ransac_reprojection_px;
    for (std::size_t i = 0; i < corr.object.size(); ++i) {
      const cv::Point3d& o = corr.object[i];
      const Vec3 pc = R * Vec3(o.x, o.y, o.z) + t;
      if (!(pc.z() > 1e-6)) continue;
      const double du = rig.camera.fx * pc.x() / pc.z() + rig.camera.cx - corr.image[i].x;
      const double dv = rig.camera.fy * pc.y() / pc.z() + rig.camera.cy - corr.image[i].y;
      if (du * du + dv * dv <= thr2) out->push_back(static_cast<int>(i));
    }
  }

  // Levenberg-Marquardt on the reprojection error of the inliers of the current pose, twice:
  // the first pass can admit points RANSAC's pose just missed (or drop ones it just kept).
  bool refine(cv::Vec3d* rvec, cv::Vec3d* tvec) {
    std::vector<cv::Point3d> obj;
    std::vector<cv::Point2d> img;
    for (int pass = 0; pass < 2; ++pass) {
      select_inliers(*rvec, *tvec, &inliers);
      if (static_cast<int>(inliers.size()) < options.min_inliers) return false;
      obj.clear();
      img.clear();
      for (const int i : inliers) {
        obj.push_back(corr.object[static_cast<std::size_t>(i)]);
        img.push_back(corr.image[static_cast<std::size_t>(i)]);
      }
      cv::solvePnPRefineLM(
          obj, img, K, cv::noArray(), *rvec, *tvec,
          cv::TermCriteria(cv::TermCriteria::COUNT | cv::TermCriteria::EPS, 50, 1e-12));
    }
    select_inliers(*rvec, *tvec, &inliers);
    return static_cast<int>(inliers.size()) >= options.min_inliers;
  }

  // Steps 1-2: crop, GFTT, descriptors (basin paper: "done on the left and right frames in
  // parallel"; sequential here, so the thread count never changes a result).
  void extract_features(const StereoFrame& frame) {
    extractor.extract(frame.left, &left);
    extractor.extract(frame.right, &right);
    if (options.subpixel_alignment) {
      const cv::Rect crop(0, 0, frame.left.cols, extractor.crop_rows());
      frame.left(crop).convertTo(left_f1, CV_32F);
      frame.right(crop).convertTo(right_f, CV_32F);
    }
  }

  // Step 4a: current left features against the previous pair's points, within a window. Returns
  // the number of correspondences (corr).
  int match_temporal() {
    pnp::MatchWindow w;
    w.row_band_px = options.max_image_motion_px;
    w.du_min_px = -options.max_image_motion_px;
    w.du_max_px = options.max_image_motion_px;
    pnp::match_features(points0.px, points0.descriptors, left.px, left.descriptors, w,
                        max_hamming(left.bits()), options.cross_check, &temporal);
    corr.clear();
    for (const IndexMatch& m : temporal) {
      cv::Point2f p = left.px[static_cast<std::size_t>(m.b)];
      // Where the previous corner's window is now: the pixel of the very point whose 3D position
      // Eq. (1) gave, rather than an independently detected (and quantised) corner near it.
      if (options.subpixel_alignment &&
          !aligner.align(left_f0, points0.px[static_cast<std::size_t>(m.a)], left_f1,
                         /*horizontal_only=*/false, &p))
        continue;
      corr.object.push_back(xyz0[static_cast<std::size_t>(m.a)]);
      corr.image.emplace_back(p.x, p.y);
    }
    return static_cast<int>(corr.object.size());
  }

  // A pose (rvec, tvec: previous -> current) and its inlier count; the count is what failed
  // the check when !ok.
  struct PoseEstimate {
    bool ok = false;
    cv::Vec3d rvec, tvec;
    int inliers = 0;
  };

  // Step 4b: PnP inside RANSAC, then (refine_on_inliers) Levenberg-Marquardt on the inliers;
  // `inliers` holds the final inliers.
  PoseEstimate estimate_pose() {
    // OpenCV draws samples from its thread-local RNG; seeding it from our stream makes the draw
    // a function of (scenario seed, frame index) only.
    cv::theRNG().state = rng.next_u64() | 1u;  // a zero state would make OpenCV's RNG constant
    cv::Vec3d rvec(0.0, 0.0, 0.0), tvec(0.0, 0.0, 0.0);
    std::vector<int> ransac_inliers;
    inliers.clear();
    bool ok = false;
    try {
      ok = cv::solvePnPRansac(corr.object, corr.image, K, cv::noArray(), rvec, tvec,
                              /*useExtrinsicGuess=*/false, options.ransac_iterations,
                              static_cast<float>(options.ransac_reprojection_px),
                              options.ransac_confidence, ransac_inliers, cv::SOLVEPNP_ITERATIVE);
    } catch (const cv::Exception&) {
      // Degenerate samples (e.g. all points on a line) make some OpenCV solvers throw; to the VO
      // that is one more failed frame.
      ok = false;
    }
    if (ok && options.refine_on_inliers) {
      ok = refine(&rvec, &tvec);
    } else if (ok) {
      inliers = ransac_inliers;
      ok = static_cast<int>(inliers.size()) >= options.min_inliers;
    }
    if (!ok)
      return {false, rvec, tvec,
              static_cast<int>(options.refine_on_inliers ? inliers.size() : ransac_inliers.size())};
    return {true, rvec, tvec, static_cast<int>(inliers.size())};
  }

  // Mean depth of the inliers in the current camera.
  double mean_inlier_depth(const SE3& T_curr_prev) const {
    double depth_sum = 0.0;
    for (const int i : inliers) {
      const cv::Point3d& o = corr.object[static_cast<std::size_t>(i)];
      depth_sum += (T_curr_prev * Vec3(o.x, o.y, o.z)).z();
    }
    return depth_sum / static_cast<int>(inliers.size());
  }
};

PnpStereoOdometry::PnpStereoOdometry(const StereoRig& rig, const PnpVoOptions& options, Rng rng) {
  const std::string rig_problems = validate(rig);
  if (!rig_problems.empty()) throw UserError("PnpStereoOdometry: invalid rig: " + rig_problems);
  yaml::validate_or_throw(options, "PnpStereoOdometry");
  const int min_side = options.orb_patch_size_px + 16;
  const int crop_rows =
      static_cast<int>(std::lround(options.crop_upper_fraction * rig.camera.height));
  if (rig.camera.width < min_side || crop_rows < min_side) {
    throw UserError("PnpStereoOdometry: searched image area of " +
                    std::to_string(rig.camera.width) + "x" + std::to_string(crop_rows) +
                    " px (width x crop_upper_fraction * height) is too small, expected at least " +
                    std::to_string(min_side) + " px a side");
  }
  impl_ = std::make_unique<Impl>(rig, options, rng);
}

PnpStereoOdometry::~PnpStereoOdometry() = default;

const PnpVoOptions& PnpStereoOdometry::options() const { return impl_->options; }
const PnpFrameStats& PnpStereoOdometry::last_stats() const { return impl_->stats; }
int PnpStereoOdometry::crop_rows() const { return impl_->extractor.crop_rows(); }

void PnpStereoOdometry::reset() {
  impl_->has_previous = false;
  impl_->rng = impl_->initial_rng;
  impl_->stats = {};
  impl_->points0.px.clear();
  impl_->points0.descriptors.release();
  impl_->xyz0.clear();
}

VoResult PnpStereoOdometry::process(const StereoFrame& frame) {
  Impl& s = *impl_;
  const auto t_start = detail::begin_frame(frame, s.rig.camera, "PnpStereoOdometry");
  VoResult result;
  s.stats = {};

  s.extract_features(frame);
  result.times.detect_ms = ms_since(t_start);
  s.stats.left_features = static_cast<int>(s.left.size());
  s.stats.right_features = static_cast<int>(s.right.size());

  auto t = SteadyClock::now();
  s.build_stereo_points();
  s.stats.stereo_points = static_cast<int>(s.points1.size());
  double match_ms = ms_since(t);

  // Whatever happens below, this pair's points are the next call's previous points.
  struct Advance {
    Impl& s;
    ~Advance() {
      std::swap(s.points0, s.points1);
      std::swap(s.xyz0, s.xyz1);
      std::swap(s.left_f0, s.left_f1);
      s.has_previous = true;
    }
  } advance{s};

  auto finish = [&](const char* reason) {
    result.times.match_ms = match_ms;
    detail::end_without_motion(&result, reason, t_start);
    return result;
  };

  if (!s.has_previous) return finish("first frame");
  if (s.stats.left_features < s.options.min_inliers)
    return finish("too few features in the current left image (black, flat or textureless?)");
  if (static_cast<int>(s.points0.size()) < s.options.min_inliers)
    return finish("too few stereo points in the previous frame");

  t = SteadyClock::now();
  result.matches = s.match_temporal();
  match_ms += ms_since(t);
  s.stats.temporal_matches = result.matches;
  if (result.matches < s.options.min_inliers) return finish("too few temporal matches");

  t = SteadyClock::now();
  const Impl::PoseEstimate pose = s.estimate_pose();
  result.times.estimate_ms = ms_since(t);
  result.times.match_ms = match_ms;
  if (!pose.ok) {
    result.inliers = pose.inliers;
    s.stats.inliers = result.inliers;
    return finish("too few PnP inliers");
  }

  // solvePnP's pose maps previous-frame points into the current camera: T_curr_prev.
  const cv::Vec3d& rvec = pose.rvec;
  const cv::Vec3d& tvec = pose.tvec;
  const SE3 T_curr_prev(so3_exp(Vec3(rvec[0], rvec[1], rvec[2])), Vec3(tvec[0], tvec[1], tvec[2]));
  result.inliers = pose.inliers;
  s.stats.inliers = result.inliers;
  if (const char* why = detail::end_with_motion(&result, T_curr_prev.inverse(),
                                                s.mean_inlier_depth(T_curr_prev), t_start))
    return finish(why);
  return result;
}

}  // namespace driftlab::vo
