// Synthetic rectified stereo sequences for VO tests and benchmarks: textured planes rendered by
// exact per-pixel ray casting (no OpenGL), so every image is an exact function of the known
// camera pose and the expected motion between frames is known exactly.
//
// Scene frame: the first camera's optical frame (x right, y down, z forward). Planes:
//  - a ground plane `ground_below_m` below the camera,
//  - a bank wall rising at 60 deg from the ground `wall_side_m` to the right (its foot;
//    about 0.9 m farther at eye height),
//  - a frontal backdrop `backdrop_m` ahead.
// Each carries a multi-octave value-noise texture in plane coordinates, bilinear between
// lattice values. A pixel integrates its footprint on the plane, as a camera would: octaves
// finer than the footprint are faded out, so the images do not alias and the four views of a
// point stay consistent. At grazing incidence (the ground) the footprint is long and thin, so
// it is filtered anisotropically (up to 4 samples along its long side, each faded by the short
// side), as GPUs do; fading by the long side alone smeared the ground into horizontal streaks
// that no detector can localise across, and doubled the VO's motion errors.
//
// Plane distances: with B = 0.12 m and fx = 500 px, Eq. (1) gives a depth step of Z^2/60 m per
// pixel of disparity (0.27 m at 4 m, 1.7 m at 10 m); a 5 mm motion error per frame needs most
// features within ~10 m, hence the defaults: ground 1.5 m below (visible from 3.1 m), wall foot
// 3 m to the side, backdrop 40 m (KITTI-like rig: 1.65 m, 4 m, 60 m).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <thread>
#include <vector>

#include <opencv2/core/mat.hpp>

#include "core/camera.hpp"
#include "core/se3.hpp"
#include "core/time.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::vo::test {

/// A rectified rig with square pixels: width x height px, focal length f [px], principal point
/// (cx, cy) [px], baseline [m].
inline StereoRig make_rig(int width, int height, double f, double cx, double cy, double baseline) {
  StereoRig rig;
  rig.camera.fx = rig.camera.fy = f;
  rig.camera.cx = cx;
  rig.camera.cy = cy;
  rig.camera.width = width;
  rig.camera.height = height;
  rig.baseline_m = baseline;
  return rig;
}

/// The river paper's Bumblebee2 (the `bumblebee2` camera preset): 1024x768, fx = fy = 817,
/// B = 0.12 m.
inline StereoRig bumblebee2_rig() { return make_rig(1024, 768, 817.0, 511.5, 383.5, 0.12); }

/// KITTI-like rig: 1241x376, fx = fy = 718.856, principal point (607.19, 185.22), B = 0.537 m.
inline StereoRig kitti_rig() { return make_rig(1241, 376, 718.856, 607.1928, 185.2157, 0.537); }

/// Bumblebee2-like rig of the river paper: 640x480, fx = fy = 500, centred, B = 0.12 m.
inline StereoRig rig_640x480() { return make_rig(640, 480, 500.0, 319.5, 239.5, 0.12); }

enum class Surface { kTexture, kWater };

/// A plane p = origin + s axis_u + r axis_v (axis_u, axis_v orthonormal), s in [s_min, s_max].
struct TexturedPlane {
  Vec3 origin = Vec3::Zero();
  Vec3 axis_u = Vec3::UnitX();
  Vec3 axis_v = Vec3::UnitZ();
  double s_min = -std::numeric_limits<double>::infinity();
  double s_max = std::numeric_limits<double>::infinity();
  Surface surface = Surface::kTexture;
  double base_cells_per_m = 1.0;  ///< lattice density of the coarsest octave [1/m]
  int octaves = 7;
  double mean = 128.0;      ///< grey level
  double contrast = 130.0;  ///< grey levels for a unit noise sum
  std::uint64_t seed = 1;
  double water_phase = 0.0;  ///< kWater only: advances the ripples [rad]
};

struct Scene {
  std::vector<TexturedPlane> planes;
  double background = 128.0;  ///< grey of rays that hit nothing
};

namespace detail {

inline std::uint64_t mix64(std::uint64_t z) {
  z ^= z >> 30;
  z *= 0xbf58476d1ce4e5b9ULL;
  z ^= z >> 27;
  z *= 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// Lattice values in [-1, 1): one 256 x 256 table (256 KB, cache-resident), shared by every
// plane and octave through per-(seed, octave) offsets; a lookup is several times cheaper than
// hashing each lattice point. An octave repeats every 256 cells (4 m for the finest ground
// octave), but the sum of octaves with different periods and offsets does not repeat in view.
inline constexpr int kLatticeBits = 8;
inline constexpr std::int64_t kLatticeMask = (std::int64_t{1} << kLatticeBits) - 1;

inline const std::vector<float>& lattice_table() {
  static const std::vector<float> table = [] {
    std::vector<float> t(std::size_t{1} << (2 * kLatticeBits));
    for (std::size_t i = 0; i < t.size(); ++i)
      t[i] = static_cast<float>(
          static_cast<double>(mix64(i + 0x9e3779b97f4a7c15ULL) >> 11) * 0x1.0p-52 - 1.0);
    return t;
  }();
  return table;
}

inline double value_noise(double s, double r, std::uint64_t seed, int k) {
  const std::uint64_t h = mix64(seed * 0x9e3779b97f4a7c15ULL + static_cast<std::uint64_t>(k));
  const double fs = std::floor(s), fr = std::floor(r);
  const std::int64_t i = static_cast<std::int64_t>(fs) + static_cast<std::int64_t>(h & 0xffff);
  const std::int64_t j = static_cast<std::int64_t>(fr) + static_cast<std::int64_t>(h >> 48);
  const double a = s - fs, b = r - fr;
  const float* t = lattice_table().data();
  auto at = [t](std::int64_t x, std::int64_t y) {
    return static_cast<double>(
        t[static_cast<std::size_t>(((y & kLatticeMask) << kLatticeBits) | (x & kLatticeMask))]);
  };
  const double v00 = at(i, j), v10 = at(i + 1, j), v01 = at(i, j + 1), v11 = at(i + 1, j + 1);
  return (1 - b) * ((1 - a) * v00 + a * v10) + b * ((1 - a) * v01 + a * v11);
}

// Grey level of a plane at plane coordinates (s, r) for a pixel footprint of fp metres.
inline double shade(const TexturedPlane& p, double s, double r, double fp) {
  if (p.surface == Surface::kWater) {
    // A few long, low ripples that move from frame to frame: no texture for a 5x5 detector.
    const double w = 3.0 * std::sin(4.1 * s + 1.3 * r + p.water_phase) +
                     2.0 * std::sin(-2.3 * s + 5.7 * r + 1.7 * p.water_phase) +
                     1.5 * std::sin(7.9 * s - 3.1 * r + 0.6 * p.water_phase);
    return p.mean + w;
  }
  double sum = 0.0, norm = 0.0, amp = 1.0, cells = p.base_cells_per_m;
  for (int k = 0; k < p.octaves; ++k, amp *= 0.8, cells *= 2.0) {
    norm += amp;
    // Cells smaller than ~1.5 px alias: fade each octave out between 3 and 1.5 px per cell.
    const double cell_px = 1.0 / (cells * fp);
    const double weight = std::clamp((cell_px - 1.5) / 1.5, 0.0, 1.0);
    if (weight <= 0.0) continue;
    // Offsetting octaves keeps their lattice lines apart.
    sum += weight * amp * value_noise(s * cells + 0.37 * k, r * cells + 0.61 * k, p.seed, k);
  }
  return p.mean + p.contrast * sum / norm;
}

}  // namespace detail

/// The nearest plane a ray o + t d (t > 0) hits: its index (-1: none), t, and the plane
/// coordinates (s, r) of the hit.
struct RayHit {
  int plane = -1;
  double t = std::numeric_limits<double>::infinity();
  double s = 0.0;
  double r = 0.0;
};

inline RayHit cast_ray(const Scene& scene, const Vec3& o, const Vec3& d) {
  RayHit hit;
  for (std::size_t k = 0; k < scene.planes.size(); ++k) {
    const TexturedPlane& pl = scene.planes[k];
    const Vec3 n = pl.axis_u.cross(pl.axis_v);
    const double nd = n.dot(d);
    if (std::abs(nd) < 1e-12) continue;
    const double t = n.dot(pl.origin - o) / nd;
    if (!(t > 1e-6) || t >= hit.t) continue;
    const Vec3 rel = o + t * d - pl.origin;
    const double s = rel.dot(pl.axis_u);
    if (s < pl.s_min || s > pl.s_max) continue;
    hit = {static_cast<int>(k), t, s, rel.dot(pl.axis_v)};
  }
  return hit;
}

/// The scene point seen at pixel (u, v) of `camera` at pose T_scene_cam, in the scene frame;
/// false when the ray hits nothing. Tests use it for exact correspondences.
inline bool scene_point(const Scene& scene, const PinholeCamera& camera, const SE3& T_scene_cam,
                        double u, double v, Vec3* p_scene) {
  const Vec3 d =
      T_scene_cam.rotation() * Vec3((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
  const RayHit hit = cast_ray(scene, T_scene_cam.translation(), d);
  if (hit.plane < 0) return false;
  *p_scene = T_scene_cam.translation() + hit.t * d;
  return true;
}

/// Renders what `camera` at pose T_scene_cam sees (CV_8UC1). Rows are split over a few
/// threads; every pixel depends on nothing but its own ray, so the bytes do not depend on them.
inline cv::Mat render(const Scene& scene, const PinholeCamera& camera, const SE3& T_scene_cam) {
  cv::Mat img(camera.height, camera.width, CV_8UC1);
  const Mat3 R = T_scene_cam.rotation();
  const Vec3 o = T_scene_cam.translation();
  detail::lattice_table();  // built once, before the threads share it
  auto render_rows = [&](int v0, int v1) {
    for (int v = v0; v < v1; ++v) {
      auto* row = img.ptr<std::uint8_t>(v);
      for (int u = 0; u < camera.width; ++u) {
        // Ray through the pixel centre with unit optical-axis component: t is the depth.
        const Vec3 d = R * Vec3((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
        const RayHit hit = cast_ray(scene, o, d);
        double grey = scene.background;
        if (hit.plane >= 0) {
          const TexturedPlane& pl = scene.planes[static_cast<std::size_t>(hit.plane)];
          const Vec3 n = pl.axis_u.cross(pl.axis_v);
          // The pixel's footprint on the plane: the images of one pixel step along u and v,
          // dp/du = t (d_u - d (n.d_u) / (n.d)), in plane coordinates. It is long and thin at
          // grazing incidence, so filter anisotropically as a GPU does: up to kProbes samples
          // along the long side, each faded by the remaining footprint.
          const double nd = n.dot(d);
          const Vec3 du = R.col(0) / camera.fx, dv = R.col(1) / camera.fy;
          const Vec3 pu = hit.t * (du - d * (n.dot(du) / nd));
          const Vec3 pv = hit.t * (dv - d * (n.dot(dv) / nd));
          const Eigen::Vector2d ju(pu.dot(pl.axis_u), pu.dot(pl.axis_v));
          const Eigen::Vector2d jv(pv.dot(pl.axis_u), pv.dot(pl.axis_v));
          const Eigen::Vector2d major = ju.norm() >= jv.norm() ? ju : jv;
          const double minor = std::abs(ju.x() * jv.y() - ju.y() * jv.x()) / major.norm();
          constexpr int kProbes = 4;
          const int probes =
              std::clamp(static_cast<int>(std::ceil(major.norm() / minor)), 1, kProbes);
          const double fp = std::max(minor, major.norm() / probes);
          double sum = 0.0;
          for (int k = 0; k < probes; ++k) {
            const double off = (k + 0.5) / probes - 0.5;
            sum += detail::shade(pl, hit.s + off * major.x(), hit.r + off * major.y(), fp);
          }
          grey = sum / probes;
        }
        row[u] = static_cast<std::uint8_t>(std::clamp(std::lround(grey), 0L, 255L));
      }
    }
  };
  const int threads = static_cast<int>(std::clamp(std::thread::hardware_concurrency(), 1u, 4u));
  std::vector<std::thread> pool;
  for (int k = 1; k < threads; ++k)
    pool.emplace_back(render_rows, camera.height * k / threads, camera.height * (k + 1) / threads);
  render_rows(0, camera.height / threads);
  for (auto& t : pool) t.join();
  return img;
}

/// The stereo pair of a rig whose left camera is at T_scene_left.
inline StereoFrame render_stereo(const Scene& scene, const StereoRig& rig, const SE3& T_scene_left,
                                 TimeNs t_ns) {
  StereoFrame f;
  f.t_ns = t_ns;
  f.left = render(scene, rig.camera, T_scene_left);
  f.right = render(scene, rig.camera, T_scene_left * rig.T_left_right());
  return f;
}

/// The river-bank scene of the file comment.
inline Scene river_bank_scene(double ground_below_m, double wall_side_m, double backdrop_m) {
  Scene s;
  TexturedPlane ground;
  ground.origin = Vec3(0.0, ground_below_m, 0.0);
  ground.axis_u = Vec3::UnitX();
  ground.axis_v = Vec3::UnitZ();
  ground.base_cells_per_m = 0.5;
  ground.octaves = 8;
  ground.mean = 120.0;
  ground.seed = 11;
  s.planes.push_back(ground);

  TexturedPlane wall;
  const double slope = 60.0 * std::numbers::pi / 180.0;
  wall.origin = Vec3(wall_side_m, ground_below_m, 0.0);
  wall.axis_u = Vec3(std::cos(slope), -std::sin(slope), 0.0);  // up the bank, away from the river
  wall.axis_v = Vec3::UnitZ();
  wall.s_min = 0.0;
  wall.s_max = 8.0;
  wall.base_cells_per_m = 0.7;
  wall.octaves = 8;
  wall.mean = 135.0;
  wall.seed = 23;
  s.planes.push_back(wall);

  TexturedPlane backdrop;
  backdrop.origin = Vec3(0.0, 0.0, backdrop_m);
  backdrop.axis_u = Vec3::UnitX();
  backdrop.axis_v = Vec3::UnitY();
  backdrop.base_cells_per_m = 0.15;
  backdrop.octaves = 8;
  backdrop.mean = 140.0;
  backdrop.seed = 37;
  s.planes.push_back(backdrop);
  return s;
}

inline Scene river_bank_scene_640() { return river_bank_scene(1.5, 3.0, 40.0); }
inline Scene river_bank_scene_kitti() { return river_bank_scene(1.65, 4.0, 60.0); }

/// Nothing but water, filling the view 5 m ahead: smooth ripples that move between frames.
inline Scene water_scene(double phase) {
  Scene s;
  TexturedPlane water;
  water.origin = Vec3(0.0, 0.0, 5.0);
  water.axis_u = Vec3::UnitX();
  water.axis_v = Vec3::UnitY();
  water.surface = Surface::kWater;
  water.mean = 110.0;
  water.water_phase = phase;
  s.planes.push_back(water);
  return s;
}

/// Camera poses driving straight ahead (+z) by step_m per frame.
inline std::vector<SE3> straight_poses(int n, double step_m) {
  std::vector<SE3> poses;
  for (int k = 0; k < n; ++k) poses.push_back(SE3::from_translation(Vec3(0.0, 0.0, k * step_m)));
  return poses;
}

/// A turn: each frame yaws by yaw_deg (about the camera's y axis, i.e. the vertical; positive
/// turns right) and then moves step_m along the new heading.
inline std::vector<SE3> turning_poses(int n, double step_m, double yaw_deg) {
  std::vector<SE3> poses;
  SE3 T;
  const SE3 step(Quat(Eigen::AngleAxisd(yaw_deg * std::numbers::pi / 180.0, Vec3::UnitY())),
                 Vec3(0.0, 0.0, step_m));
  for (int k = 0; k < n; ++k) {
    poses.push_back(T);
    T = T * step;
  }
  return poses;
}

struct Sequence {
  StereoRig rig;
  std::vector<SE3> T_scene_cam;  ///< left camera poses
  std::vector<StereoFrame> frames;

  /// The exact motion between frame k-1 and frame k: p_prev = T * p_curr.
  SE3 T_prev_curr(std::size_t k) const { return T_scene_cam[k - 1].inverse() * T_scene_cam[k]; }
};

/// Renders poses into a sequence at 10 Hz.
inline Sequence make_sequence(const Scene& scene, const StereoRig& rig,
                              const std::vector<SE3>& poses) {
  Sequence seq;
  seq.rig = rig;
  seq.T_scene_cam = poses;
  for (std::size_t k = 0; k < poses.size(); ++k)
    seq.frames.push_back(render_stereo(scene, rig, poses[k], static_cast<TimeNs>(k) * 100'000'000));
  return seq;
}

/// Translation error [m] and rotation error [rad] of an estimated T_prev_curr.
struct MotionError {
  double translation_m;
  double rotation_rad;
};
inline MotionError motion_error(const SE3& estimate, const SE3& truth) {
  return {(estimate.translation() - truth.translation()).norm(),
          angle_between(estimate.quaternion(), truth.quaternion())};
}

}  // namespace driftlab::vo::test
