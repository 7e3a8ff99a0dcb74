#include "vo/sparse/window_ba.hpp"

#include <algorithm>
#include <cmath>

#include <ceres/ceres.h>
#include <ceres/rotation.h>

#include "vo/sparse/stereo_motion.hpp"

namespace driftlab::vo::sparse {

namespace {

// Huber threshold on the norm of an observation's four residuals [px]: sub-pixel matches stay
// quadratic, the odd wrong track (inlier of frame-to-frame RANSAC, 2 px) is down-weighted.
// 0.5 px beat 0.3, 1 and 3 px on the straight and yaw sequences of tests/vo/window_ba_test.cpp.
constexpr double kHuberDeltaPx = 0.5;
// The fixed iteration cap of each window solve (Levenberg-Marquardt from a warm start).
constexpr int kMaxIterations = 10;

// Eq. (2) for one observation: the left and right reprojection errors of an anchor-frame point
// in a frame at pose T_frame_anchor = (angle-axis, translation).
struct StereoReprojection {
  double fx, fy, cx, cy, baseline;
  double u_l, v_l, u_r;

  template <class T>
  bool operator()(const T* pose, const T* point, T* residual) const {
    T p[3];
    ceres::AngleAxisRotatePoint(pose, point, p);
    p[0] += pose[3];
    p[1] += pose[4];
    p[2] += pose[5];
    if (!(p[2] > T(kMinProjectionDepthM))) return false;
    const T inv_z = T(1.0) / p[2];
    const T v = fy * p[1] * inv_z + cy;
    residual[0] = u_l - (fx * p[0] * inv_z + cx);
    residual[1] = v_l - v;
    residual[2] = u_r - (fx * (p[0] - baseline) * inv_z + cx);
    residual[3] = v_l - v;  // the right observation shares the left row (rectified)
    return true;
  }
};

SE3 to_se3(const std::array<double, 6>& pose) {
  return SE3(so3_exp(Vec3(pose[0], pose[1], pose[2])), Vec3(pose[3], pose[4], pose[5]));
}

void from_se3(const SE3& T, std::array<double, 6>* pose) {
  const Vec3 w = so3_log(T.quaternion());
  const Vec3 t = T.translation();
  *pose = {w.x(), w.y(), w.z(), t.x(), t.y(), t.z()};
}

bool finite(const SE3& T) {
  return T.translation().allFinite() && T.quaternion().coeffs().allFinite();
}

}  // namespace

struct WindowBundleAdjuster::Ceres {
  ceres::HuberLoss loss{kHuberDeltaPx};
  ceres::Problem::Options problem_options;
  ceres::Solver::Options solver_options;
  Ceres() {
    problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
    solver_options.linear_solver_type = ceres::DENSE_SCHUR;
    solver_options.num_threads = 1;
    solver_options.max_num_iterations = kMaxIterations;
    solver_options.logging_type = ceres::SILENT;
    solver_options.minimizer_progress_to_stdout = false;
  }
};

WindowBundleAdjuster::WindowBundleAdjuster(const StereoRig& rig, const SparseVoOptions& options)
    : rig_(rig), window_frames_(options.window_frames), ceres_(std::make_unique<Ceres>()) {
  frames_.reserve(static_cast<std::size_t>(window_frames_) + 1);
}

WindowBundleAdjuster::~WindowBundleAdjuster() = default;

void WindowBundleAdjuster::reset() {
  frames_.clear();
  tracks_.clear();
  slot_track_prev_.clear();
  slot_track_next_.clear();
  next_id_ = 0;
}

std::size_t WindowBundleAdjuster::frame_index(std::int32_t id) const {
  return static_cast<std::size_t>(id - frames_.front().id);  // ids are consecutive
}

WindowBundleAdjuster::Result WindowBundleAdjuster::add_frame(std::span<const CircleMatch> circles,
                                                             std::span<const int> inliers,
                                                             const SE3& T_prev_curr) {
  Result result;
  result.T_prev_curr = T_prev_curr;
  if (frames_.empty()) {  // a new window, anchored at the previous frame
    Frame anchor;
    anchor.id = next_id_++;
    frames_.push_back(anchor);
    slot_track_prev_.clear();
  }
  const Frame& prev = frames_.back();
  const SE3 T_prev_anchor = to_se3(prev.pose);
  const SE3 T_anchor_prev = T_prev_anchor.inverse();
  Frame curr;
  curr.id = next_id_++;
  from_se3(T_prev_curr.inverse() * T_prev_anchor, &curr.pose);

  // Extend the tracks that ended in the previous frame; start new ones from the previous pair.
  std::int32_t max_slot = -1;
  for (const int i : inliers)
    max_slot = std::max(max_slot, circles[static_cast<std::size_t>(i)].slot_lc);
  slot_track_next_.assign(static_cast<std::size_t>(max_slot + 1), -1);
  for (const int i : inliers) {
    const CircleMatch& c = circles[static_cast<std::size_t>(i)];
    if (!(c.u_lp - c.u_rp > 0.0) || !(c.u_lc - c.u_rc > 0.0)) continue;
    const auto lp = static_cast<std::size_t>(c.slot_lp);
    std::int32_t t = lp < slot_track_prev_.size() ? slot_track_prev_[lp] : -1;
    if (t >= 0 && tracks_[static_cast<std::size_t>(t)].obs.back().frame == curr.id) continue;
    if (t < 0) {
      const Vec3 p = T_anchor_prev *
                     rig_.triangulate(Eigen::Vector2d(c.u_lp, c.v_lp), c.u_lp - c.u_rp);  // Eq. (1)
      if (!p.allFinite()) continue;
      t = static_cast<std::int32_t>(tracks_.size());
      Track& track = tracks_.emplace_back();
      track.p = {p.x(), p.y(), p.z()};
      track.obs.push_back({prev.id, c.u_lp, c.v_lp, c.u_rp});
    }
    // The new match follows the current left feature's own pixel, which lies a sub-pixel
    // offset away from the track's point in the previous frame (its u_lp, v_lp, refined to
    // sub-pixel, say where). Shift the new observation by that offset, the image motion being
    // locally a translation, so that the track observes one scene point throughout.
    Observation o{curr.id, c.u_lc, c.v_lc, c.u_rc};
    const Observation& last = tracks_[static_cast<std::size_t>(t)].obs.back();
    if (last.frame == prev.id) {
      o.u_l += last.u_l - c.u_lp;
      o.v_l += last.v_l - c.v_lp;
      o.u_r += last.u_r - c.u_rp;
    }
    tracks_[static_cast<std::size_t>(t)].obs.push_back(o);
    slot_track_next_[static_cast<std::size_t>(c.slot_lc)] = t;
  }
  slot_track_prev_.swap(slot_track_next_);
  frames_.push_back(curr);
  while (static_cast<int>(frames_.size()) > window_frames_) drop_oldest();

  if (!solve(&result)) {
    reset();
    result.ok = false;
    result.T_prev_curr = T_prev_curr;
    return result;
  }
  // T_prev_curr = T_{k-1}_anchor * T_anchor_k: the refined motion between the refined poses.
  Frame& newest = frames_.back();
  const SE3 T_anchor_curr = to_se3(newest.pose).inverse();
  const SE3 out = to_se3(frames_[frames_.size() - 2].pose) * T_anchor_curr;
  if (!finite(out)) {
    reset();
    result.ok = false;
    result.T_prev_curr = T_prev_curr;
    return result;
  }
  result.ok = true;
  result.T_prev_curr = out;
  result.frames = static_cast<int>(frames_.size());
  return result;
}

void WindowBundleAdjuster::drop_oldest() {
  // Re-anchor at the second-oldest frame j: T_i_j = T_i_anchor T_anchor_j, p_j = T_j_anchor p.
  const SE3 T_j_anchor = to_se3(frames_[1].pose);
  const SE3 T_anchor_j = T_j_anchor.inverse();
  for (std::size_t i = 1; i < frames_.size(); ++i)
    from_se3(to_se3(frames_[i].pose) * T_anchor_j, &frames_[i].pose);
  frames_[1].pose = {};  // exactly the identity
  const std::int32_t old_id = frames_.front().id;
  frames_.erase(frames_.begin());

  // Drop the old frame's observations, then the tracks left with fewer than two (a single
  // stereo observation hardly constrains a pose), compacting and remapping track indices.
  std::size_t kept = 0;
  std::vector<std::int32_t>& remap = slot_track_next_;  // scratch
  remap.assign(tracks_.size(), -1);
  for (std::size_t k = 0; k < tracks_.size(); ++k) {
    Track& track = tracks_[k];
    if (!track.obs.empty() && track.obs.front().frame == old_id) track.obs.erase(track.obs.begin());
    if (track.obs.size() < 2) continue;
    const Vec3 p = T_j_anchor * Vec3(track.p[0], track.p[1], track.p[2]);
    track.p = {p.x(), p.y(), p.z()};
    remap[k] = static_cast<std::int32_t>(kept);
    if (kept != k) std::swap(tracks_[kept], track);
    ++kept;
  }
  tracks_.resize(kept);
  for (std::int32_t& t : slot_track_prev_)
    if (t >= 0) t = remap[static_cast<std::size_t>(t)];
}

bool WindowBundleAdjuster::solve(Result* result) {
  ceres::Problem problem(ceres_->problem_options);
  const PinholeCamera& cam = rig_.camera;
  int residuals = 0;
  for (Track& track : tracks_) {
    for (const Observation& o : track.obs) {
      auto* cost =
          new ceres::AutoDiffCostFunction<StereoReprojection, 4, 6, 3>(new StereoReprojection{
              cam.fx, cam.fy, cam.cx, cam.cy, rig_.baseline_m, o.u_l, o.v_l, o.u_r});
      problem.AddResidualBlock(cost, &ceres_->loss, frames_[frame_index(o.frame)].pose.data(),
                               track.p.data());
      ++residuals;
    }
  }
  result->tracks = static_cast<int>(tracks_.size());
  result->residuals = residuals;
  double* anchor = frames_.front().pose.data();
  double* newest = frames_.back().pose.data();
  if (!problem.HasParameterBlock(anchor) || !problem.HasParameterBlock(newest)) return false;
  problem.SetParameterBlockConstant(anchor);
  ceres::Solver::Summary summary;
  ceres::Solve(ceres_->solver_options, &problem, &summary);
  if (!summary.IsSolutionUsable()) return false;
  for (const Frame& f : frames_)
    for (const double x : f.pose)
      if (!std::isfinite(x)) return false;
  return true;
}

}  // namespace driftlab::vo::sparse
