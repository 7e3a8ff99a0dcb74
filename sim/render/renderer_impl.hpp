// The renderer's inside (sim/render/renderer.hpp's StereoRenderer::Impl), shared by its three
// files: renderer.cpp (the public calls and the frame), renderer_upload.cpp (meshes, textures,
// waves, ripples and render targets onto the GPU) and renderer_passes.cpp (the passes that draw
// an eye: scene, water, sky, reflection, read-back). Not for use outside sim/render.
#pragma once

#include <glad/gl.h>

#include <fmt/format.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include "core/error.hpp"
#include "core/stopwatch.hpp"
#include "sim/render/alpha_mips.hpp"
#include "sim/render/gl_context.hpp"
#include "sim/render/gl_program.hpp"
#include "sim/render/mip_chain.hpp"
#include "sim/render/mip_chain_gl.hpp"
#include "sim/render/renderer.hpp"
#include "sim/render/shaders.hpp"

namespace driftlab::sim {
namespace render {

// A mesh uploaded to the GPU, with its bounding sphere for culling.
struct GpuMesh {
  GLuint vao = 0, vbo = 0, ebo = 0;
  Material material;
  bool on_body = false;  // Mesh::on_body
  int mover = -1;        // Mesh::mover
  GLuint sway_vbo = 0;   // Mesh::sway (0: rigid)
  float sway_most = 0;   // its largest sway or flutter weight
  bool cutout = false;   // its texture has alpha: drawn alpha-tested, after the opaque meshes
  Eigen::Vector3f centre = Eigen::Vector3f::Zero();  // bounding sphere, mesh frame
  float radius = 0;
  // Runs of consecutive triangles with their bounding spheres (mesh frame): those outside the
  // view are not drawn. A batch holds many small things (stones, roots, cards) spread along
  // its cell; the vertices of those out of view would cost this thread vertex work for nothing.
  struct Run {
    Eigen::Vector3f centre;
    float radius;
    GLsizei first, count;  // in indices
  };
  std::vector<Run> runs;
};

inline constexpr float kNear = 0.05f;
inline constexpr float kFar = 5000.f;

inline GLint loc(GLuint p, const char* name) { return glGetUniformLocation(p, name); }

inline void set_mat4(GLuint p, const char* name, const Eigen::Matrix4f& m) {
  glUniformMatrix4fv(loc(p, name), 1, GL_FALSE, m.data());  // Eigen is column-major
}

inline Eigen::Matrix4f to_view(const SE3& T_W_C) { return T_W_C.inverse().matrix().cast<float>(); }

// Frustum planes (a x + b y + c z + d >= 0 inside) of a view-projection
// matrix (Gribb and Hartmann's extraction).
inline std::array<Eigen::Vector4f, 6> frustum_planes(const Eigen::Matrix4f& vp) {
  std::array<Eigen::Vector4f, 6> p;
  for (int i = 0; i < 3; ++i) {
    p[2 * i] = vp.row(3).transpose() + vp.row(i).transpose();
    p[2 * i + 1] = vp.row(3).transpose() - vp.row(i).transpose();
  }
  for (auto& q : p) q /= q.head<3>().norm();
  return p;
}

inline bool sphere_visible(const std::array<Eigen::Vector4f, 6>& planes, const Eigen::Vector3f& c,
                           float r) {
  for (const auto& q : planes)
    if (q.head<3>().dot(c) + q.w() < -r) return false;
  return true;
}

}  // namespace render

using render::GpuMesh;

struct StereoRenderer::Impl {
  StereoRig rig;
  SE3 T_left_right;  // the true right camera (defaults to the rig's baseline)
  RenderOptions options;
  bool colour = false;                                  // ImageKind::kColour
  Eigen::Matrix4f T_W_B = Eigen::Matrix4f::Identity();  // where body meshes are drawn
  std::vector<MoverMotion> movers;                      // SceneGeometry::movers
  std::vector<Eigen::Matrix4f> T_W_M;                   // the movers' poses at the pass's time
  VegetationSway sway;                                  // set_sway (empty: still)
  float sway_reach_m = 0;  // the most a unit-weight vertex moves (sway and flutter)
  // The sway's uniforms at time t (phases reduced modulo 2 pi in double precision).
  void set_sway_uniforms(GLuint prog, double t) const;
  // Profiling (set_profiling): lap_start marks the time after glFinish; lap(slot) finishes the
  // pass drawn since, adds its time to times.*slot and marks again. Both do nothing otherwise.
  bool profiling = false;
  RenderPassTimes times;
  SteadyClock::time_point lap_mark;
  void lap_start();
  void lap(double RenderPassTimes::*slot);
  std::unique_ptr<GlContext> context;
  std::unique_ptr<MipChain> mip_chain;  // the mirror image's blur levels under wind ripples
  // Programs by variant, mode 0 gray, 1 linear depth.
  GLuint scene_progs[2][2][2][2] = {};  // [mode][sun][cutout][sway]
  GLuint water_progs[2][2][2] = {};     // [mode][sun][ripples]
  GLuint sky_progs[2][2] = {};          // [sun][clouds]
  GLuint empty_vao = 0;
  std::vector<GpuMesh> meshes;
  std::vector<GLuint> textures;
  GLuint cloud_tex = 0;  // scene.sky_clouds (0: none)
  SceneGeometry scene;   // lighting and water parameters (meshes released after upload)
  std::size_t triangle_count = 0;
  GLuint water_vao = 0, water_vbo = 0, water_ebo = 0;
  GLsizei water_count = 0;
  int water_segments = 0;
  float water_radius_m = 0;
  // The grid's spacing over its radius, radial (ring to ring) and tangential (u_grid_step).
  Eigen::Vector2f water_grid_step = Eigen::Vector2f::Zero();
  float wave_amplitude_sum_m = 0;
  float wave_slope_sum = 0;   // sum of amplitude x wavenumber: a bound on the waves' slope
  std::vector<float> wave_a;  // 4 per component
  std::vector<float> wave_phase;
  std::shared_ptr<RippleMaps> ripples;  // the wind ripples' slope maps (null: none)
  std::array<GLuint, RippleMaps::kTiles> ripple_tex = {};
  double ripple_t = std::numeric_limits<double>::quiet_NaN();  // the time the textures show
  int refl_levels = 1;
  int refl_width = 0, refl_height = 0;  // the reflection pass's size
  // Framebuffers.
  // Framebuffers, one set per eye: both eyes are drawn before either is read
  // back, so llvmpipe rasterises one eye's pass while the next pass's vertices
  // are processed on this thread.
  struct EyeTargets {
    GLuint msaa_fbo = 0, msaa_color = 0, msaa_depth = 0;
    GLuint resolve_fbo = 0, resolve_tex = 0;
    GLuint refl_fbo = 0, refl_tex = 0, refl_depth = 0;
    // The reflection pass with render.reflection_msaa_samples > 1: drawn here, resolved into
    // refl_tex.
    GLuint refl_msaa_fbo = 0, refl_msaa_color = 0, refl_msaa_depth = 0;
  };
  std::array<EyeTargets, 2> eyes;
  GLuint depth_fbo = 0, depth_tex = 0, depth_rb = 0;
  Eigen::Matrix4f proj;
  std::vector<std::pair<float, std::size_t>> draw_order;  // scratch for draw_scene
  WaterOrder water_order = WaterOrder::kByCost;           // draw_eye_rows

  void build_water_grid();
  void build_framebuffers();
  void build_eye_targets(EyeTargets* e);
  void color_target_(GLuint* fbo, GLuint* tex, unsigned format, GLuint* depth_rb, int W, int H,
                     int levels = 1);
  // A colour (`format`) and depth renderbuffer pair with `samples` samples (1: single-sampled).
  void multisample_target_(GLuint* fbo, GLuint* color, GLuint* depth, unsigned format, int samples,
                           int W, int H);
  // The eyes' colour format: R8 gray, RGBA8 colour.
  unsigned eye_format() const { return colour ? GL_RGBA8 : GL_R8; }
  // The meshes at time t (the movers where they are then).
  void draw_scene(const Eigen::Matrix4f& view, const Eigen::Vector3f& eye, float mirror, int mode,
                  double t);
  // Where mesh g is drawn: the identity, the body's pose or its mover's (T_W_M at the pass's t).
  const Eigen::Matrix4f& model_of(const GpuMesh& g) const;
  // One mesh with the program in use: its runs of triangles that can be in the view (planes,
  // in the pass's mirrored world).
  void draw_mesh(GLuint prog, const GpuMesh& g, const std::array<Eigen::Vector4f, 6>& planes,
                 float mirror);
  bool run_culling = true;               // set_run_culling
  std::size_t triangles_submitted = 0;   // by draw_mesh
  std::vector<GLsizei> run_counts;       // scratch for draw_mesh
  std::vector<const void*> run_offsets;  // scratch for draw_mesh
  void draw_water(const Eigen::Matrix4f& view, const Eigen::Vector3f& eye, double t, int mode,
                  GLuint reflection);  // 0: none
  // The sky where nothing was drawn; mirror -1: the mirrored sky below the horizon.
  void draw_sky(const Eigen::Matrix4f& view, float mirror);
  // A sky that is the same in every direction is the reflection pass's clear colour.
  bool uniform_sky() const { return scene.lighting.sky_zenith_ratio == 1.f && cloud_tex == 0; }
  // The ripples' slope maps at time t into ripple_tex (once per t).
  void upload_ripples(double t);
  bool reflects() const { return scene.water.enabled && options.reflections; }
  // The scene mirrored in the water plane for one eye, into its reflection texture: the rows
  // of it that the eye's rows [row_begin, row_end) read (reflection_rows), or all of them.
  void draw_reflection(const SE3& T_W_C, double t, int eye, int row_begin = 0, int row_end = -1);
  // The rows [first, last) of the reflection texture that the water shader samples for the
  // eye's rows [row_begin, row_end).
  std::pair<int, int> reflection_rows(int row_begin, int row_end) const;
  // The most the waves' normal moves the water shader's reflection lookup [uv] (u_shift_max).
  float reflection_shift_max() const {
    return 0.15f * std::min(1.f, wave_slope_sum) * 1.001f + 1e-5f;
  }
  // The eye's image: the water (with its reflection texture), the scene, the sky.
  void draw_eye(const SE3& T_W_C, double t, int eye);
  // draw_eye in steps: clear, draw rows [row_begin, row_end) (any number of times), resolve.
  void clear_eye(int eye);
  void draw_eye_rows(const SE3& T_W_C, double t, int eye, int row_begin, int row_end);
  // Resolves the multisampled rows [row_begin, row_end) (all rows by default) into resolve_tex.
  void resolve_eye(int eye, int row_begin = 0, int row_end = -1);
  // `channel` GL_RED: the image; GL_GREEN: the left eye's moving mask (left_mask_target).
  GrayImage read_eye(int eye, unsigned channel = GL_RED);
  TruthImages render_truth(const SE3& T_W_C, double t);
  // The left eye's single-sampled target becomes RG8 (gray in red, the scene shader's moving
  // flag in green), once: 4 % slower than R8 on llvmpipe, so only when a mask is asked for.
  void use_left_mask_target();
  bool left_mask_target = false;
  // render(), and with `moving_mask` the left eye's mask (render_bands).
  StereoImages render_pair(const SE3& T_W_C_left, double t_s, bool with_depth, bool moving_mask);
};

}  // namespace driftlab::sim
