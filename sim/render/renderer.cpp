#include "sim/render/renderer.hpp"

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
#include "sim/render/gl_program.hpp"
#include "sim/render/mip_chain.hpp"
#include "sim/render/mip_chain_gl.hpp"
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

}  // namespace render

using render::GpuMesh;

namespace {

constexpr float kNear = 0.05f;
constexpr float kFar = 5000.f;

GLint loc(GLuint p, const char* name) { return glGetUniformLocation(p, name); }

void set_mat4(GLuint p, const char* name, const Eigen::Matrix4f& m) {
  glUniformMatrix4fv(loc(p, name), 1, GL_FALSE, m.data());  // Eigen is column-major
}

Eigen::Matrix4f to_view(const SE3& T_W_C) { return T_W_C.inverse().matrix().cast<float>(); }

// Frustum planes (a x + b y + c z + d >= 0 inside) of a view-projection
// matrix (Gribb and Hartmann's extraction).
std::array<Eigen::Vector4f, 6> frustum_planes(const Eigen::Matrix4f& vp) {
  std::array<Eigen::Vector4f, 6> p;
  for (int i = 0; i < 3; ++i) {
    p[2 * i] = vp.row(3).transpose() + vp.row(i).transpose();
    p[2 * i + 1] = vp.row(3).transpose() - vp.row(i).transpose();
  }
  for (auto& q : p) q /= q.head<3>().norm();
  return p;
}

bool sphere_visible(const std::array<Eigen::Vector4f, 6>& planes, const Eigen::Vector3f& c,
                    float r) {
  for (const auto& q : planes)
    if (q.head<3>().dot(c) + q.w() < -r) return false;
  return true;
}

// The axis-aligned box of the vertices added, and the sphere around it.
struct Box {
  Eigen::Vector3f lo = Eigen::Vector3f::Constant(1e30f), hi = -lo;
  void add(const Vertex& v) {
    lo = lo.cwiseMin(Eigen::Vector3f(v.x, v.y, v.z));
    hi = hi.cwiseMax(Eigen::Vector3f(v.x, v.y, v.z));
  }
  Eigen::Vector3f centre() const { return 0.5f * (lo + hi); }
  float radius() const { return 0.5f * (hi - lo).norm(); }
};

// A mesh's triangles in runs of kRunTriangles, each with a sphere holding its vertices (grown
// by a part in 10^4 and a millimetre against rounding).
std::vector<GpuMesh::Run> triangle_runs(const Mesh& mesh) {
  constexpr std::size_t kRunTriangles = 32;
  std::vector<GpuMesh::Run> runs;
  for (std::size_t first = 0; first < mesh.indices.size(); first += 3 * kRunTriangles) {
    const std::size_t end = std::min(mesh.indices.size(), first + 3 * kRunTriangles);
    Box box;
    for (std::size_t k = first; k < end; ++k) box.add(mesh.vertices[mesh.indices[k]]);
    runs.push_back({box.centre(), box.radius() * 1.0001f + 1e-3f, static_cast<GLsizei>(first),
                    static_cast<GLsizei>(end - first)});
  }
  return runs;
}

// An alpha-tested texture on the GPU: RG8 (grey, alpha), its levels keeping level 0's coverage
// (computed on the CPU: glGenerateMipmap's box filter thins leaves out with distance), the
// nearest level bilinearly filtered (no blend of two levels' edges), clamped at its edges.
GLuint upload_cutout_texture(const Texture& t) {
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  const std::vector<AlphaMipLevel> levels = coverage_preserving_mips(t);
  glTexStorage2D(GL_TEXTURE_2D, static_cast<GLsizei>(levels.size()), GL_RG8, t.width, t.height);
  for (std::size_t k = 0; k < levels.size(); ++k)
    glTexSubImage2D(GL_TEXTURE_2D, static_cast<GLint>(k), 0, 0, levels[k].width, levels[k].height,
                    GL_RG, GL_UNSIGNED_BYTE, levels[k].grey_alpha.data());
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  return tex;
}

// A scene texture on the GPU: R8, mip-mapped, trilinear, repeating; RG8 where it has alpha.
GLuint upload_texture(const Texture& t) {
  const auto n = static_cast<std::size_t>(std::max(t.width, 0)) * std::max(t.height, 0);
  if (t.width <= 0 || t.height <= 0 || t.pixels.size() != n ||
      (!t.alpha.empty() && t.alpha.size() != n))
    throw InternalError(fmt::format("renderer: texture '{}' has inconsistent size", t.name));
  if (!t.alpha.empty()) return upload_cutout_texture(t);
  GLuint tex = 0;
  glGenTextures(1, &tex);
  glBindTexture(GL_TEXTURE_2D, tex);
  const int levels = 1 + static_cast<int>(std::floor(std::log2(std::max(t.width, t.height))));
  glTexStorage2D(GL_TEXTURE_2D, levels, GL_R8, t.width, t.height);
  glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, t.width, t.height, GL_RED, GL_UNSIGNED_BYTE,
                  t.pixels.data());
  glGenerateMipmap(GL_TEXTURE_2D);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
  return tex;
}

}  // namespace

Eigen::Matrix4f projection_from_intrinsics(const PinholeCamera& c, float n, float f) {
  Eigen::Matrix4f P = Eigen::Matrix4f::Zero();
  const float W = static_cast<float>(c.width), H = static_cast<float>(c.height);
  P(0, 0) = static_cast<float>(2.0 * c.fx / W);
  P(0, 2) = static_cast<float>(2.0 * (c.cx + 0.5) / W - 1.0);
  P(1, 1) = static_cast<float>(2.0 * c.fy / H);
  P(1, 2) = static_cast<float>(2.0 * (c.cy + 0.5) / H - 1.0);
  P(2, 2) = (f + n) / (f - n);
  P(2, 3) = -2.f * f * n / (f - n);
  P(3, 2) = 1.f;
  return P;
}

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

StereoRenderer::StereoRenderer(const StereoRig& rig, const RenderOptions& options, ImageKind kind)
    : impl_(std::make_unique<Impl>()) {
  const std::string problems = validate(rig);
  if (!problems.empty()) throw UserError("renderer: invalid stereo rig: " + problems);
  yaml::validate_or_throw(options, "render");
  impl_->rig = rig;
  impl_->T_left_right = rig.T_left_right();
  impl_->options = options;
  impl_->colour = kind == ImageKind::kColour;
  impl_->context = create_gl_context(options.backend);
  const std::string colour = fmt::format("#define COLOUR {}\n", impl_->colour ? 1 : 0);
  for (int mode : {0, 1})
    for (int sun : {0, 1}) {
      const std::string defines =
          fmt::format("#define DEPTH {}\n#define SUN {}\n", mode, sun) + colour;
      for (int cutout : {0, 1})
        for (int sway : {0, 1})
          impl_->scene_progs[mode][sun][cutout][sway] = link_program(
              shaders::kSceneVs, shaders::kSceneFs, "scene",
              defines + fmt::format("#define CUTOUT {}\n#define SWAY {}\n", cutout, sway));
      for (int ripples : {0, 1})
        impl_->water_progs[mode][sun][ripples] = link_program(
            shaders::kWaterVs, shaders::kWaterFs, "water",
            defines + fmt::format("#define RIPPLES {}\n", ripples) + shaders::kWaterWaves);
    }
  for (int sun : {0, 1})
    for (int clouds : {0, 1})
      impl_->sky_progs[sun][clouds] =
          link_program(shaders::kSkyVs, shaders::kSkyFs, "sky",
                       fmt::format("#define SUN {}\n#define CLOUDS {}\n", sun, clouds) + colour);
  glGenVertexArrays(1, &impl_->empty_vao);
  impl_->mip_chain = std::make_unique<MipChain>();
  impl_->proj = projection_from_intrinsics(rig.camera, kNear, kFar);
  impl_->build_water_grid();
  impl_->build_framebuffers();
  glPixelStorei(GL_PACK_ALIGNMENT, 1);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
}

StereoRenderer::~StereoRenderer() = default;

const std::string& StereoRenderer::context_description() const {
  static thread_local std::string s;
  s = impl_->context->description();
  return s;
}

std::size_t StereoRenderer::triangles() const { return impl_->triangle_count; }

void StereoRenderer::Impl::build_water_grid() {
  // Rings growing geometrically from 5 cm to the water extent: fine where the
  // camera is close to the water, coarse far away.
  const int rings = 96, segments = 128;
  const float r0 = 0.05f, r1 = 300.f;
  std::vector<float> v;
  v.push_back(0);
  v.push_back(0);
  for (int i = 0; i < rings; ++i) {
    const float r = r0 * std::pow(r1 / r0, static_cast<float>(i) / (rings - 1));
    for (int j = 0; j < segments; ++j) {
      const float a = 2.f * std::numbers::pi_v<float> * j / segments;
      v.push_back(r * std::cos(a));
      v.push_back(r * std::sin(a));
    }
  }
  // Indices wedge by wedge (all rings of one angular segment together), so
  // that the wedges in view are contiguous runs of the index buffer.
  std::vector<std::uint32_t> idx;
  for (int j = 0; j < segments; ++j) {
    idx.insert(idx.end(), {0u, static_cast<std::uint32_t>(1 + j),
                           static_cast<std::uint32_t>(1 + (j + 1) % segments)});
    for (int i = 0; i + 1 < rings; ++i) {
      const std::uint32_t a = 1 + i * segments + j, b = 1 + i * segments + (j + 1) % segments;
      const std::uint32_t c = a + segments, d = b + segments;
      idx.insert(idx.end(), {a, c, b, b, c, d});
    }
  }
  water_segments = segments;
  water_radius_m = r1;
  water_grid_step = {std::pow(r1 / r0, 1.f / (rings - 1)) - 1.f,
                     2.f * std::numbers::pi_v<float> / segments};
  glGenVertexArrays(1, &water_vao);
  glBindVertexArray(water_vao);
  glGenBuffers(1, &water_vbo);
  glBindBuffer(GL_ARRAY_BUFFER, water_vbo);
  glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(v.size() * sizeof(float)), v.data(),
               GL_STATIC_DRAW);
  glEnableVertexAttribArray(0);
  glVertexAttribPointer(0, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
  glGenBuffers(1, &water_ebo);
  glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, water_ebo);
  glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(idx.size() * 4), idx.data(),
               GL_STATIC_DRAW);
  water_count = static_cast<GLsizei>(idx.size());
  glBindVertexArray(0);
}

void StereoRenderer::Impl::color_target_(GLuint* fbo, GLuint* tex, unsigned format,
                                         GLuint* depth_rb, int W, int H, int levels) {
  glGenFramebuffers(1, fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, *fbo);
  glGenTextures(1, tex);
  glBindTexture(GL_TEXTURE_2D, *tex);
  glTexStorage2D(GL_TEXTURE_2D, levels, format, W, H);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, *tex, 0);
  if (depth_rb) {
    glGenRenderbuffers(1, depth_rb);
    glBindRenderbuffer(GL_RENDERBUFFER, *depth_rb);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, W, H);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, *depth_rb);
  }
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw InternalError("renderer: incomplete framebuffer");
}

void StereoRenderer::Impl::build_framebuffers() {
  const int W = rig.camera.width, H = rig.camera.height;
  const ReflectionResolution r = options.reflection_resolution;
  refl_width = r == ReflectionResolution::kHalf ? (W + 1) / 2 : W;
  refl_height = r == ReflectionResolution::kFull ? H : (H + 1) / 2;
  for (EyeTargets& e : eyes) build_eye_targets(&e);
  // Red: the linear depth; green: 1 where the surface belongs to a mover (render_truth).
  color_target_(&depth_fbo, &depth_tex, GL_RG32F, &depth_rb, W, H);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void StereoRenderer::Impl::build_eye_targets(EyeTargets* e) {
  const int W = rig.camera.width, H = rig.camera.height;
  const int samples = options.msaa_samples;
  multisample_target_(&e->msaa_fbo, &e->msaa_color, &e->msaa_depth, eye_format(), samples, W, H);

  color_target_(&e->resolve_fbo, &e->resolve_tex, eye_format(), nullptr, W, H);
  // The reflection pass (render.reflection_resolution): at full resolution
  // by default; at half resolution it costs a quarter of the fill, but its
  // edges snap the mirror image's sub-pixel motion to steps of two pixels,
  // which its own MSAA (render.reflection_msaa_samples) only halves. Its mip
  // levels (made only when wind ripples blur it) are the rough-mirror blur.
  const int RW = refl_width, RH = refl_height;
  refl_levels = mip_level_count(RW, RH);
  color_target_(&e->refl_fbo, &e->refl_tex, GL_R8, &e->refl_depth, RW, RH, refl_levels);
  if (options.reflection_msaa_samples > 1)
    multisample_target_(&e->refl_msaa_fbo, &e->refl_msaa_color, &e->refl_msaa_depth, GL_R8,
                        options.reflection_msaa_samples, RW, RH);
}

void StereoRenderer::Impl::multisample_target_(GLuint* fbo, GLuint* color, GLuint* depth,
                                               unsigned format, int samples, int W, int H) {
  glGenFramebuffers(1, fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, *fbo);
  glGenRenderbuffers(1, color);
  glBindRenderbuffer(GL_RENDERBUFFER, *color);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples > 1 ? samples : 0, format, W, H);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, *color);
  glGenRenderbuffers(1, depth);
  glBindRenderbuffer(GL_RENDERBUFFER, *depth);
  glRenderbufferStorageMultisample(GL_RENDERBUFFER, samples > 1 ? samples : 0,
                                   GL_DEPTH_COMPONENT32F, W, H);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, *depth);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw UserError(fmt::format("renderer: the {}x{} framebuffer with {} samples is not supported",
                                W, H, samples));
}

void StereoRenderer::upload(const SceneGeometry& scene) {
  Impl& m = *impl_;
  m.context->make_current();  // another renderer's context may be current on this thread
  for (auto& g : m.meshes) {
    glDeleteVertexArrays(1, &g.vao);
    glDeleteBuffers(1, &g.vbo);
    glDeleteBuffers(1, &g.ebo);
    if (g.sway_vbo != 0) glDeleteBuffers(1, &g.sway_vbo);
  }
  m.meshes.clear();
  if (!m.textures.empty())
    glDeleteTextures(static_cast<GLsizei>(m.textures.size()), m.textures.data());
  m.textures.clear();
  for (const Texture& t : scene.textures) m.textures.push_back(upload_texture(t));
  if (m.cloud_tex != 0) glDeleteTextures(1, &m.cloud_tex);
  m.cloud_tex = scene.sky_clouds.pixels.empty() ? 0 : upload_texture(scene.sky_clouds);
  glBindTexture(GL_TEXTURE_2D, 0);
  m.triangle_count = 0;
  // Batches: meshes of one material whose centres fall in the same square of
  // kBatchCell_m are drawn as one. Every draw call costs llvmpipe state
  // validation on this thread; the squares keep culling useful on long reaches.
  constexpr float kBatchCell_m = 50.f;
  std::vector<Mesh> merged;
  std::map<std::tuple<int, float, float, bool, long, long, bool, int, std::array<float, 3>>,
           std::size_t>
      batch_of;
  for (const Mesh& x : scene.meshes) {
    if (x.indices.empty()) continue;
    if (x.mover >= static_cast<int>(scene.movers.size()))
      throw InternalError(fmt::format("renderer: mesh '{}' names a missing mover", x.name));
    for (std::uint32_t i : x.indices)
      if (i >= x.vertices.size())
        throw InternalError(fmt::format("renderer: mesh '{}' has an index out of range", x.name));
    Box box;
    for (const Vertex& v : x.vertices) box.add(v);
    const Eigen::Vector3f c = box.centre();
    const auto key = std::make_tuple(
        x.material.texture, x.material.albedo, x.material.specular, x.material.double_sided,
        std::lround(std::floor(c.x() / kBatchCell_m)),
        std::lround(std::floor(c.y() / kBatchCell_m)), x.on_body, x.mover, x.material.colour);
    const auto [it, fresh] = batch_of.emplace(key, merged.size());
    if (fresh) {
      merged.push_back(x);
      continue;
    }
    Mesh& d = merged[it->second];
    const auto base = static_cast<std::uint32_t>(d.vertices.size());
    d.vertices.insert(d.vertices.end(), x.vertices.begin(), x.vertices.end());
    for (std::uint32_t i : x.indices) d.indices.push_back(base + i);
    append_sway(&d, base, x);
  }
  for (const Mesh& mesh : merged) {
    if (mesh.material.texture >= static_cast<int>(scene.textures.size()))
      throw InternalError(fmt::format("renderer: mesh '{}' names a missing texture", mesh.name));
    GpuMesh g;
    g.material = mesh.material;
    g.on_body = mesh.on_body;
    g.mover = mesh.mover;
    g.cutout = mesh.material.texture >= 0 &&
               !scene.textures[static_cast<std::size_t>(mesh.material.texture)].alpha.empty();
    Box box;
    for (const Vertex& v : mesh.vertices) box.add(v);
    g.centre = box.centre();
    g.radius = box.radius();
    g.runs = triangle_runs(mesh);
    glGenVertexArrays(1, &g.vao);
    glBindVertexArray(g.vao);
    glGenBuffers(1, &g.vbo);
    glBindBuffer(GL_ARRAY_BUFFER, g.vbo);
    glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.vertices.size() * sizeof(Vertex)),
                 mesh.vertices.data(), GL_STATIC_DRAW);
    glEnableVertexAttribArray(0);
    glVertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex), nullptr);
    glEnableVertexAttribArray(1);
    glVertexAttribPointer(1, 3, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<void*>(offsetof(Vertex, nx)));
    glEnableVertexAttribArray(2);
    glVertexAttribPointer(2, 2, GL_FLOAT, GL_FALSE, sizeof(Vertex),
                          reinterpret_cast<void*>(offsetof(Vertex, u)));
    if (!mesh.sway.empty()) {
      if (mesh.sway.size() != mesh.vertices.size())
        throw InternalError(
            fmt::format("renderer: mesh '{}' has a sway weight per vertex short", mesh.name));
      for (const auto& w : mesh.sway) g.sway_most = std::max({g.sway_most, w[0], w[1]});
      glGenBuffers(1, &g.sway_vbo);
      glBindBuffer(GL_ARRAY_BUFFER, g.sway_vbo);
      glBufferData(GL_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.sway.size() * 2 * sizeof(float)),
                   mesh.sway.data(), GL_STATIC_DRAW);
      glEnableVertexAttribArray(3);
      glVertexAttribPointer(3, 2, GL_FLOAT, GL_FALSE, 2 * sizeof(float), nullptr);
    }  // else attribute 3 keeps its current value, (0, 0): rigid
    glGenBuffers(1, &g.ebo);
    glBindBuffer(GL_ELEMENT_ARRAY_BUFFER, g.ebo);
    glBufferData(GL_ELEMENT_ARRAY_BUFFER, static_cast<GLsizeiptr>(mesh.indices.size() * 4),
                 mesh.indices.data(), GL_STATIC_DRAW);
    glBindVertexArray(0);
    m.meshes.push_back(g);
    m.triangle_count += mesh.indices.size() / 3;
  }
  m.scene.lighting = scene.lighting;
  m.scene.water = scene.water;
  m.movers = scene.movers;
  m.T_W_M.assign(m.movers.size(), Eigen::Matrix4f::Identity());
}

void StereoRenderer::set_ripples(std::shared_ptr<RippleMaps> maps) {
  Impl& m = *impl_;
  m.context->make_current();
  if (maps && maps->empty()) maps.reset();
  m.ripples = std::move(maps);
  m.ripple_t = std::numeric_limits<double>::quiet_NaN();
  const bool none = !m.ripples;
  if (!none && m.ripple_tex[0] == 0) {
    // Float moments, mip mapped (the levels come from RippleMaps), repeating.
    glGenTextures(RippleMaps::kTiles, m.ripple_tex.data());
    for (GLuint tex : m.ripple_tex) {
      glBindTexture(GL_TEXTURE_2D, tex);
      glTexStorage2D(GL_TEXTURE_2D, m.ripples->levels(), GL_RGBA32F, RippleMaps::kResolution,
                     RippleMaps::kResolution);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_REPEAT);
      glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_REPEAT);
    }
  }
  // The mirror image is sampled from its mip levels only when ripples blur it.
  for (const auto& e : m.eyes) {
    glBindTexture(GL_TEXTURE_2D, e.refl_tex);
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER,
                    none ? GL_LINEAR : GL_LINEAR_MIPMAP_LINEAR);
  }
  glBindTexture(GL_TEXTURE_2D, 0);
}

void StereoRenderer::Impl::upload_ripples(double t) {
  if (ripple_t == t) return;
  ripples->bake(t);
  for (int tile = 0; tile < RippleMaps::kTiles; ++tile) {
    glBindTexture(GL_TEXTURE_2D, ripple_tex[static_cast<std::size_t>(tile)]);
    for (int l = 0; l < ripples->levels(); ++l) {
      const int n = RippleMaps::kResolution >> l;
      glTexSubImage2D(GL_TEXTURE_2D, l, 0, 0, n, n, GL_RGBA, GL_FLOAT,
                      ripples->level(tile, l).data());
    }
  }
  glBindTexture(GL_TEXTURE_2D, 0);
  ripple_t = t;
}

void StereoRenderer::set_waves(const std::vector<WaveComponent>& components) {
  std::vector<WaveComponent> c = components;
  std::stable_sort(c.begin(), c.end(), [](const WaveComponent& a, const WaveComponent& b) {
    return a.amplitude_m > b.amplitude_m;
  });
  if (c.size() > static_cast<std::size_t>(kMaxShaderWaveComponents))
    c.resize(kMaxShaderWaveComponents);
  impl_->wave_a.clear();
  impl_->wave_phase.clear();
  impl_->wave_amplitude_sum_m = 0;
  impl_->wave_slope_sum = 0;
  for (const auto& w : c) {
    impl_->wave_a.insert(impl_->wave_a.end(),
                         {static_cast<float>(w.amplitude_m),
                          static_cast<float>(w.wavenumber_rad_m * std::cos(w.direction_rad)),
                          static_cast<float>(w.wavenumber_rad_m * std::sin(w.direction_rad)),
                          static_cast<float>(w.omega_rad_s)});
    impl_->wave_phase.push_back(static_cast<float>(w.phase_rad));
    impl_->wave_amplitude_sum_m += static_cast<float>(std::abs(w.amplitude_m));
    impl_->wave_slope_sum += static_cast<float>(std::abs(w.amplitude_m * w.wavenumber_rad_m));
  }
}

void StereoRenderer::Impl::set_sway_uniforms(GLuint prog, double t) const {
  constexpr int kMax = 8;  // u_sway's size
  const int n = sway.empty() ? 0 : std::min<int>(kMax, static_cast<int>(sway.components.size()));
  glUniform1i(loc(prog, "u_sway_n"), n);
  if (n == 0) return;
  const double two_pi = 2 * std::numbers::pi;
  std::array<float, 4 * kMax> c{};
  for (int k = 0; k < n; ++k) {
    const SwayComponent& s = sway.components[static_cast<std::size_t>(k)];
    c[4 * k] = static_cast<float>(s.amplitude_m);
    c[4 * k + 1] = static_cast<float>(s.wavenumber_rad_m);
    c[4 * k + 2] = static_cast<float>(std::fmod(s.omega_rad_s * t + s.phase_rad, two_pi));
  }
  glUniform4fv(loc(prog, "u_sway"), kMax, c.data());
  glUniform2f(loc(prog, "u_wind_dir"), static_cast<float>(sway.direction_W.x()),
              static_cast<float>(sway.direction_W.y()));
  glUniform2f(loc(prog, "u_flutter"), static_cast<float>(sway.flutter_amplitude_m),
              static_cast<float>(std::fmod(sway.flutter_omega_rad_s * t, two_pi)));
  glUniform2f(loc(prog, "u_sway_reach"), static_cast<float>(sway.sway_bound_m()),
              static_cast<float>(sway.flutter_amplitude_m));
}

void StereoRenderer::set_sway(const VegetationSway& sway) {
  impl_->sway = sway;
  impl_->sway_reach_m = static_cast<float>(sway.sway_bound_m() + 1.5 * sway.flutter_amplitude_m);
}

const Eigen::Matrix4f& StereoRenderer::Impl::model_of(const GpuMesh& g) const {
  static const Eigen::Matrix4f identity = Eigen::Matrix4f::Identity();
  if (g.on_body) return T_W_B;
  return g.mover >= 0 ? T_W_M[static_cast<std::size_t>(g.mover)] : identity;
}

void StereoRenderer::Impl::draw_scene(const Eigen::Matrix4f& view, const Eigen::Vector3f& eye,
                                      float mirror, int mode, double t) {
  for (std::size_t i = 0; i < movers.size(); ++i)
    T_W_M[i] = movers[i].T_W_M(t).matrix().cast<float>();
  const Lighting& L = scene.lighting;
  const int sun_variant = L.sun ? 1 : 0;
  const Eigen::Vector3f sun = L.sun_direction_W.normalized();
  const auto set_pass_uniforms = [&](GLuint prog) {
    glUseProgram(prog);
    set_mat4(prog, "u_view", view);
    set_mat4(prog, "u_proj", proj);
    glUniform1f(loc(prog, "u_mirror"), mirror);
    glUniform3f(loc(prog, "u_sun_dir"), sun.x(), sun.y(), sun.z());
    glUniform1f(loc(prog, "u_ambient"), L.ambient);
    glUniform1f(loc(prog, "u_diffuse"), L.diffuse);
    glUniform1f(loc(prog, "u_sky"), L.sky_brightness);
    glUniform1f(loc(prog, "u_fog"), L.fog_distance_m);
    glUniform3f(loc(prog, "u_eye"), eye.x(), eye.y(), eye.z() * mirror);
    glUniform1i(loc(prog, "u_tex"), 0);
    set_sway_uniforms(prog, t);
  };
  glActiveTexture(GL_TEXTURE0);
  // Meshes outside the view are skipped: a CPU rasteriser is bound by vertex work.
  // Nearest first, so that llvmpipe's early depth test skips shading hidden
  // fragments (the tree line and the banks overlap several times over).
  const auto planes = frustum_planes(proj * view);
  const Eigen::Vector3f eye_m(eye.x(), eye.y(), eye.z() * mirror);
  draw_order.clear();
  for (std::size_t i = 0; i < meshes.size(); ++i) {
    const GpuMesh& g = meshes[i];
    const Eigen::Vector3f w = (model_of(g) * g.centre.homogeneous()).head<3>();
    const Eigen::Vector3f c(w.x(), w.y(), w.z() * mirror);
    if (!sphere_visible(planes, c, g.radius + g.sway_most * sway_reach_m)) continue;
    draw_order.emplace_back(std::max(0.f, (c - eye_m).norm() - g.radius), i);
  }
  std::sort(draw_order.begin(), draw_order.end());
  // Back faces of one-sided meshes are skipped: a CPU rasteriser pays for every pixel a triangle
  // covers, also those the depth test rejects (in the river reach the tree crowns were 4 in 10
  // of the scene's covered pixels, and 1 in 25 of theirs was drawn). The optical frame's y points
  // down and the projection keeps it, so the image is flipped in GL's window coordinates: a face
  // wound counter-clockwise about its normal is clockwise on screen; the mirror image flips the
  // winding once more.
  glFrontFace(mirror > 0.f ? GL_CW : GL_CCW);
  // Opaque meshes first, then the alpha-tested ones (each group nearest first): a discarding
  // shader tests depth early but writes it late on llvmpipe, so cards drawn last meet a depth
  // buffer that already rejects what opaque surfaces hide.
  // A mesh that cannot sway (no weights, or no wind) is drawn by the variant without the sway's
  // vertex branch, in the same order: the branch leaves its vertices where they are.
  for (int cutout : {0, 1}) {
    std::array<bool, 2> ready = {};  // the pass's uniforms set on each variant's program
    GLuint bound = 0;
    for (const auto& [distance, index] : draw_order) {
      const GpuMesh& g = meshes[index];
      if (g.cutout != (cutout == 1)) continue;
      const int sways = !sway.empty() && g.sway_vbo != 0 ? 1 : 0;
      const GLuint prog = scene_progs[mode][sun_variant][cutout][sways];
      if (!ready[static_cast<std::size_t>(sways)])
        set_pass_uniforms(prog);
      else if (prog != bound)
        glUseProgram(prog);
      ready[static_cast<std::size_t>(sways)] = true;
      bound = prog;
      draw_mesh(prog, g, planes, mirror);
    }
  }
  glBindVertexArray(0);
  glDisable(GL_CULL_FACE);
}

void StereoRenderer::Impl::draw_mesh(GLuint prog, const GpuMesh& g,
                                     const std::array<Eigen::Vector4f, 6>& planes, float mirror) {
  if (g.material.double_sided)
    glDisable(GL_CULL_FACE);
  else
    glEnable(GL_CULL_FACE);
  const bool has_tex = g.material.texture >= 0;
  glUniform1i(loc(prog, "u_has_tex"), has_tex ? 1 : 0);
  if (has_tex) glBindTexture(GL_TEXTURE_2D, textures[static_cast<std::size_t>(g.material.texture)]);
  glUniform1f(loc(prog, "u_albedo"), g.material.albedo);
  glUniform1f(loc(prog, "u_specular"), g.material.specular);
  glUniform3fv(loc(prog, "u_tint"), 1, g.material.colour.data());
  set_mat4(prog, "u_model", model_of(g));
  glUniform1f(loc(prog, "u_moving"), g.mover >= 0 ? 1.f : 0.f);  // the moving mask
  glBindVertexArray(g.vao);
  // The runs that can be in the view, consecutive ones joined: a triangle outside the view
  // draws no pixel, and those drawn keep their order, so the image is the same.
  run_counts.clear();
  run_offsets.clear();
  const Eigen::Matrix4f& T = model_of(g);  // rigid: radii unchanged
  const float margin = g.sway_most * sway_reach_m;
  GLsizei end = -1;
  for (const GpuMesh::Run& r : g.runs) {
    const Eigen::Vector3f w = (T * r.centre.homogeneous()).head<3>();
    if (run_culling &&
        !sphere_visible(planes, Eigen::Vector3f(w.x(), w.y(), w.z() * mirror), r.radius + margin))
      continue;
    if (r.first == end) {
      run_counts.back() += r.count;
    } else {
      run_counts.push_back(r.count);
      run_offsets.push_back(reinterpret_cast<const void*>(sizeof(GLuint) * r.first));
    }
    end = r.first + r.count;
    triangles_submitted += static_cast<std::size_t>(r.count / 3);
  }
  if (!run_counts.empty())
    glMultiDrawElements(GL_TRIANGLES, run_counts.data(), GL_UNSIGNED_INT, run_offsets.data(),
                        static_cast<GLsizei>(run_counts.size()));
}

void StereoRenderer::Impl::draw_water(const Eigen::Matrix4f& view, const Eigen::Vector3f& eye,
                                      double t, int mode, GLuint reflection) {
  if (!scene.water.enabled) return;
  const Lighting& L = scene.lighting;
  const WaterAppearance& w = scene.water;
  const GLuint water_prog = water_progs[mode][L.sun ? 1 : 0][ripples ? 1 : 0];
  glUseProgram(water_prog);
  set_mat4(water_prog, "u_view", view);
  set_mat4(water_prog, "u_proj", proj);
  const int count = static_cast<int>(wave_phase.size());
  glUniform1i(loc(water_prog, "u_wave_count"), count);
  if (count > 0) {
    glUniform4fv(loc(water_prog, "u_wave_a"), count, wave_a.data());
    glUniform1fv(loc(water_prog, "u_wave_phase"), count, wave_phase.data());
  }
  // Time modulo a long period keeps float phases accurate.
  glUniform1f(loc(water_prog, "u_time"), static_cast<float>(t));
  glUniform2f(loc(water_prog, "u_centre"), eye.x(), eye.y());
  glUniform2f(loc(water_prog, "u_grid_step"), water_grid_step.x(), water_grid_step.y());
  glUniform3f(loc(water_prog, "u_eye"), eye.x(), eye.y(), eye.z());
  glUniform1i(loc(water_prog, "u_has_reflection"), reflection != 0 ? 1 : 0);
  glUniform2f(loc(water_prog, "u_viewport"), static_cast<float>(rig.camera.width),
              static_cast<float>(rig.camera.height));
  glUniform1f(loc(water_prog, "u_shift_max"), reflection_shift_max());
  glUniform1f(loc(water_prog, "u_body"), w.body_gray);
  glUniform1f(loc(water_prog, "u_turbidity"), w.turbidity);
  glUniform1f(loc(water_prog, "u_reflectivity"), w.reflectivity);
  glUniform1f(loc(water_prog, "u_sky"), L.sky_brightness);
  glUniform1f(loc(water_prog, "u_fog"), L.fog_distance_m);
  const Eigen::Vector3f sun = L.sun_direction_W.normalized();
  glUniform3f(loc(water_prog, "u_sun_dir"), sun.x(), sun.y(), sun.z());
  if (ripples && mode == 0) {
    lap(&RenderPassTimes::water_ms);  // what was drawn before (the clear)
    upload_ripples(t);
    lap(&RenderPassTimes::ripples_ms);
    // Texture coordinates relative to the eye, the eye's own reduced in double.
    for (int tile = 0; tile < RippleMaps::kTiles; ++tile) {
      const double L = ripples->tile_size_m(tile);
      const std::string i = std::to_string(tile);
      glUniform1f(loc(water_prog, ("u_ripple_inv_size" + i).c_str()), static_cast<float>(1.0 / L));
      glUniform2f(loc(water_prog, ("u_ripple_offset" + i).c_str()),
                  static_cast<float>(std::remainder(double(eye.x()), L) / L),
                  static_cast<float>(std::remainder(double(eye.y()), L) / L));
      glUniform1i(loc(water_prog, ("u_ripple_map" + i).c_str()), 1 + tile);
      glActiveTexture(static_cast<GLenum>(GL_TEXTURE1 + tile));
      glBindTexture(GL_TEXTURE_2D, ripple_tex[static_cast<std::size_t>(tile)]);
    }
  }
  glUniform2f(loc(water_prog, "u_focal"), static_cast<float>(rig.camera.fx),
              static_cast<float>(rig.camera.fy));
  glUniform1f(loc(water_prog, "u_refl_max_lod"), static_cast<float>(refl_levels - 1));
  glUniform1f(loc(water_prog, "u_refl_texel_px"),
              static_cast<float>(std::sqrt(double(rig.camera.width) * rig.camera.height /
                                           (double(refl_width) * refl_height))));
  glUniform1i(loc(water_prog, "u_reflection"), 0);
  glActiveTexture(GL_TEXTURE0);
  glBindTexture(GL_TEXTURE_2D, reflection);
  // Only the wedges of the grid that reach into the view are drawn: each
  // wedge lies inside the triangle (camera, two far corners) widened to hold
  // the arc, thickened by the sum of the wave amplitudes; it is skipped when
  // all six corners are outside one frustum plane.
  const auto planes = frustum_planes(proj * view);
  const float h = wave_amplitude_sum_m + 0.01f;
  const float reach = water_radius_m / std::cos(std::numbers::pi_v<float> / water_segments);
  auto wedge_visible = [&](int j) {
    const Eigen::Vector2f c(eye.x(), eye.y());
    std::array<Eigen::Vector2f, 3> xy;
    xy[0] = c;
    for (int k = 0; k < 2; ++k) {
      const float a = 2.f * std::numbers::pi_v<float> * static_cast<float>(j + k) / water_segments;
      xy[static_cast<std::size_t>(k + 1)] = c + reach * Eigen::Vector2f(std::cos(a), std::sin(a));
    }
    for (const auto& q : planes) {
      bool all_out = true;
      for (const auto& p : xy)
        for (float z : {-h, h})
          all_out = all_out && q.head<3>().dot(Eigen::Vector3f(p.x(), p.y(), z)) + q.w() < 0;
      if (all_out) return false;
    }
    return true;
  };
  const GLsizei per_wedge = water_count / water_segments;
  glBindVertexArray(water_vao);
  for (int j = 0; j < water_segments;) {
    if (!wedge_visible(j)) {
      ++j;
      continue;
    }
    int k = j + 1;
    while (k < water_segments && wedge_visible(k)) ++k;
    glDrawElements(GL_TRIANGLES, (k - j) * per_wedge, GL_UNSIGNED_INT,
                   reinterpret_cast<void*>(static_cast<std::uintptr_t>(j) * per_wedge * 4));
    j = k;
  }
  glBindVertexArray(0);
}

void StereoRenderer::Impl::draw_sky(const Eigen::Matrix4f& view, float mirror) {
  // The sky triangle lies on the far plane (depth 1): it passes the depth
  // test only where the cleared depth is left.
  glDepthFunc(GL_LEQUAL);
  glDepthMask(GL_FALSE);
  const Lighting& L = scene.lighting;
  const GLuint sky_prog = sky_progs[L.sun ? 1 : 0][cloud_tex != 0 ? 1 : 0];
  glUseProgram(sky_prog);
  // The sky is at infinity: its rays come from the view's rotation alone, so both eyes and
  // every position see the same sky, whatever the float rounding of a translated view.
  Eigen::Matrix4f rotation_only = view;
  rotation_only.block<3, 1>(0, 3).setZero();
  const Eigen::Matrix4f inv_vp = (proj * rotation_only).inverse();
  set_mat4(sky_prog, "u_inv_view_proj", inv_vp);
  glUniform1f(loc(sky_prog, "u_sky"), static_cast<float>(sky_horizon_luminance(L)));
  glUniform1f(loc(sky_prog, "u_gradient"), L.sky_zenith_ratio - 1.f);
  glUniform1f(loc(sky_prog, "u_knee"), L.sky_knee);
  glUniform1f(loc(sky_prog, "u_mirror"), mirror);
  const Eigen::Vector3f sun = L.sun_direction_W.normalized();
  glUniform3f(loc(sky_prog, "u_sun_dir"), sun.x(), sun.y(), sun.z());
  // The sun's image in the water is the water's glint, not a mirrored halo.
  glUniform1f(loc(sky_prog, "u_halo"), mirror > 0 ? 0.35f : 0.f);
  if (cloud_tex != 0) {
    glActiveTexture(GL_TEXTURE3);  // 0: scene or reflection, 1-2: ripples
    glBindTexture(GL_TEXTURE_2D, cloud_tex);
    glUniform1i(loc(sky_prog, "u_clouds"), 3);
    glUniform1f(loc(sky_prog, "u_cloud_scale"), L.cloud_height_over_tile);
    glUniform1f(loc(sky_prog, "u_cloud_gain"), L.cloud_contrast * 255.f / 32.f);
    glUniform1f(loc(sky_prog, "u_cloud_haze"), L.cloud_height_over_visibility);
  }
  glBindVertexArray(empty_vao);
  glDrawArrays(GL_TRIANGLES, 0, 3);
  glBindVertexArray(0);
  if (cloud_tex != 0) {
    glBindTexture(GL_TEXTURE_2D, 0);
    glActiveTexture(GL_TEXTURE0);
  }
  glDepthMask(GL_TRUE);
  glDepthFunc(GL_LESS);
}

std::pair<int, int> StereoRenderer::Impl::reflection_rows(int row_begin, int row_end) const {
  const int H = rig.camera.height, RH = refl_height;
  // Under wind ripples the lookup moves with the ripples' slope and is blurred along it
  // (kWaterFs): no simple bound, so the whole image.
  if (ripples || (row_begin == 0 && row_end == H)) return {0, RH};
  // Without them the water shader reads the texture bilinearly at uv = pixel centre /
  // viewport + 0.15 n.xy, n the upward normal of the waves at the pixel (kWaterWaves),
  // clamped to reflection_shift_max: |n.xy| <= min(1, |grad eta|) <= min(1, sum of
  // amplitude x wavenumber), the low-pass only lowering each component's slope.
  const double shift = reflection_shift_max();
  const double v_lo = (row_begin + 0.5) / H - shift, v_hi = (row_end - 0.5) / H + shift;
  // Texel rows: the bilinear pair about v RH - 0.5, and two more on each side for rounding.
  const int first = static_cast<int>(std::floor(v_lo * RH - 0.5)) - 2;
  const int last = static_cast<int>(std::floor(v_hi * RH - 0.5)) + 4;
  return {std::clamp(first, 0, RH), std::clamp(last, 0, RH)};
}

void StereoRenderer::Impl::draw_reflection(const SE3& T_W_C, double t, int eye_index, int row_begin,
                                           int row_end) {
  const EyeTargets& e = eyes[static_cast<std::size_t>(eye_index)];
  const Eigen::Matrix4f view = to_view(T_W_C);
  const Eigen::Vector3f eye = T_W_C.translation().cast<float>();
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  const int RW = refl_width, RH = refl_height;
  const bool multisampled = options.reflection_msaa_samples > 1;
  glBindFramebuffer(GL_FRAMEBUFFER, multisampled ? e.refl_msaa_fbo : e.refl_fbo);
  glViewport(0, 0, RW, RH);
  // A band of a rolling-shutter image draws only the mirror rows it reads (the rest of the
  // texture keeps an earlier band's rows, which it never samples).
  const auto [first, last] = reflection_rows(row_begin, row_end < 0 ? rig.camera.height : row_end);
  const bool scissored = first > 0 || last < RH;
  if (scissored) {
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, first, RW, last - first);
  }
  glClearColor(scene.lighting.sky_brightness, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_CLIP_DISTANCE0);
  draw_scene(view, eye, -1.f, 0, t);
  // The mirrored sky where the ray looks down; where it looks up, the clear colour is the
  // sky at the horizon, so ripples that sample across the line see no step.
  if (!uniform_sky()) draw_sky(view, -1.f);
  glDisable(GL_CLIP_DISTANCE0);
  if (multisampled) {
    glBindFramebuffer(GL_READ_FRAMEBUFFER, e.refl_msaa_fbo);
    glBindFramebuffer(GL_DRAW_FRAMEBUFFER, e.refl_fbo);
    glBlitFramebuffer(0, 0, RW, RH, 0, 0, RW, RH, GL_COLOR_BUFFER_BIT, GL_NEAREST);
  }
  if (scissored) glDisable(GL_SCISSOR_TEST);
  lap(&RenderPassTimes::mirror_ms);
  if (ripples) {
    mip_chain->build(e.refl_tex, RW, RH, refl_levels);
    lap(&RenderPassTimes::mirror_mips_ms);
  }
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void StereoRenderer::Impl::clear_eye(int eye_index) {
  const EyeTargets& e = eyes[static_cast<std::size_t>(eye_index)];
  glBindFramebuffer(GL_FRAMEBUFFER, e.msaa_fbo);
  glViewport(0, 0, rig.camera.width, rig.camera.height);
  glClearColor(0, 0, 0, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
}

void StereoRenderer::Impl::draw_eye_rows(const SE3& T_W_C, double t, int eye_index, int row_begin,
                                         int row_end) {
  const EyeTargets& e = eyes[static_cast<std::size_t>(eye_index)];
  const int W = rig.camera.width, H = rig.camera.height;
  const Eigen::Matrix4f view = to_view(T_W_C);
  const Eigen::Vector3f eye = T_W_C.translation().cast<float>();
  glEnable(GL_DEPTH_TEST);
  glDepthFunc(GL_LESS);
  glDisable(GL_CULL_FACE);
  glBindFramebuffer(GL_FRAMEBUFFER, e.msaa_fbo);
  glViewport(0, 0, W, H);
  // Window row = image row (see projection_from_intrinsics), so the band is the scissor box.
  const bool band = row_begin > 0 || row_end < H;
  if (band) {
    glEnable(GL_SCISSOR_TEST);
    glScissor(0, row_begin, W, row_end - row_begin);
  }
  // The water and the scene nearest first, then the sky on the far plane where nothing was
  // drawn. Calm, the water goes first (near and large, it hides much of the banks below it);
  // with ripples its shader is the costliest (the mirror's taps), so it goes after the scene
  // and llvmpipe's early depth test skips it behind the banks. Where the water meets a surface
  // at the same depth the pixel shows the water either way (GL_LEQUAL when it comes second):
  // the same bytes in both orders.
  const GLuint reflection = reflects() ? e.refl_tex : 0;
  const bool water_last =
      water_order == WaterOrder::kByCost ? ripples != nullptr : water_order == WaterOrder::kLast;
  if (!water_last) {
    draw_water(view, eye, t, 0, reflection);
    lap(&RenderPassTimes::water_ms);
  }
  draw_scene(view, eye, 1.f, 0, t);
  lap(&RenderPassTimes::scene_ms);
  if (water_last) {
    glDepthFunc(GL_LEQUAL);
    draw_water(view, eye, t, 0, reflection);
    glDepthFunc(GL_LESS);
    lap(&RenderPassTimes::water_ms);
  }
  draw_sky(view, 1.f);
  lap(&RenderPassTimes::sky_ms);
  if (band) glDisable(GL_SCISSOR_TEST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void StereoRenderer::Impl::resolve_eye(int eye_index, int row_begin, int row_end) {
  if (options.msaa_samples <= 1) return;
  const EyeTargets& e = eyes[static_cast<std::size_t>(eye_index)];
  const int W = rig.camera.width;
  if (row_end < 0) row_end = rig.camera.height;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, e.msaa_fbo);
  glBindFramebuffer(GL_DRAW_FRAMEBUFFER, e.resolve_fbo);
  glBlitFramebuffer(0, row_begin, W, row_end, 0, row_begin, W, row_end, GL_COLOR_BUFFER_BIT,
                    GL_NEAREST);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
}

void StereoRenderer::Impl::draw_eye(const SE3& T_W_C, double t, int eye_index) {
  clear_eye(eye_index);
  draw_eye_rows(T_W_C, t, eye_index, 0, rig.camera.height);
  resolve_eye(eye_index);
}

void StereoRenderer::Impl::use_left_mask_target() {
  if (left_mask_target) return;
  DRIFTLAB_DEMAND(!colour && options.msaa_samples == 1);
  EyeTargets& e = eyes[0];
  glBindFramebuffer(GL_FRAMEBUFFER, e.msaa_fbo);
  glDeleteRenderbuffers(1, &e.msaa_color);
  glGenRenderbuffers(1, &e.msaa_color);
  glBindRenderbuffer(GL_RENDERBUFFER, e.msaa_color);
  glRenderbufferStorage(GL_RENDERBUFFER, GL_RG8, rig.camera.width, rig.camera.height);
  glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, e.msaa_color);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
    throw InternalError("renderer: incomplete framebuffer for the moving mask");
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  left_mask_target = true;
}

GrayImage StereoRenderer::Impl::read_eye(int eye_index, unsigned channel) {
  const EyeTargets& e = eyes[static_cast<std::size_t>(eye_index)];
  const int W = rig.camera.width, H = rig.camera.height;
  // Without multisampling the colour buffer is read directly (no resolve).
  glBindFramebuffer(GL_READ_FRAMEBUFFER, options.msaa_samples > 1 ? e.resolve_fbo : e.msaa_fbo);
  GrayImage img;
  img.width = W;
  img.height = H;
  img.pixels.resize(static_cast<std::size_t>(W) * H);
  glReadPixels(0, 0, W, H, channel, GL_UNSIGNED_BYTE, img.pixels.data());
  lap(&RenderPassTimes::readback_ms);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  return img;
}

TruthImages StereoRenderer::Impl::render_truth(const SE3& T_W_C, double t) {
  const int W = rig.camera.width, H = rig.camera.height;
  const Eigen::Matrix4f view = to_view(T_W_C);
  const Eigen::Vector3f eye = T_W_C.translation().cast<float>();
  glBindFramebuffer(GL_FRAMEBUFFER, depth_fbo);
  glViewport(0, 0, W, H);
  glClearColor(0, 0, 0, 0);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glEnable(GL_DEPTH_TEST);
  // As in the eye pass (draw_eye_rows, in either order): where the water and a surface meet at
  // the same depth, the pixel shows the water, in the image and here.
  draw_water(view, eye, t, 1, 0);
  draw_scene(view, eye, 1.f, 1, t);
  glFinish();
  const std::size_t n = static_cast<std::size_t>(W) * H;
  std::vector<float> rg(2 * n);
  glReadPixels(0, 0, W, H, GL_RG, GL_FLOAT, rg.data());
  lap(&RenderPassTimes::truth_ms);
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  TruthImages out;
  out.depth.width = out.moving.width = W;
  out.depth.height = out.moving.height = H;
  out.depth.depth_m.resize(n);
  out.moving.pixels.resize(n);
  for (std::size_t i = 0; i < n; ++i) {
    out.depth.depth_m[i] = rg[2 * i];
    out.moving.pixels[i] = rg[2 * i + 1] > 0.5f ? 255 : 0;
  }
  return out;
}

TruthImages StereoRenderer::render_truth(const SE3& T_W_C, double t_s) {
  impl_->context->make_current();
  impl_->lap_start();
  ++impl_->times.truths;
  return impl_->render_truth(T_W_C, t_s);
}

void StereoRenderer::Impl::lap_start() {
  if (!profiling) return;
  glFinish();
  lap_mark = SteadyClock::now();
}

void StereoRenderer::Impl::lap(double RenderPassTimes::*slot) {
  if (!profiling) return;
  glFinish();
  const auto now = SteadyClock::now();
  times.*slot += std::chrono::duration<double, std::milli>(now - lap_mark).count();
  lap_mark = now;
}

void StereoRenderer::set_profiling(bool on) {
  impl_->profiling = on;
  impl_->times = {};
}

const RenderPassTimes& StereoRenderer::pass_times() const { return impl_->times; }

double RenderPassTimes::total_ms() const {
  return mirror_ms + mirror_mips_ms + ripples_ms + water_ms + scene_ms + sky_ms + readback_ms +
         truth_ms;
}

std::string describe_passes(const RenderPassTimes& t) {
  const double total = t.total_ms();
  const auto share = [&](double ms) { return total > 0 ? 100.0 * ms / total : 0.0; };
  const double pairs = std::max(t.renders, 1), truths = std::max(t.truths, 1);
  std::string out = fmt::format(
      "{} stereo pairs, {} truth passes; ms a pair (glFinish after each "
      "pass), share of the renderer's time:\n",
      t.renders, t.truths);
  const std::pair<const char*, double> rows[] = {
      {"mirror images (scene and sky mirrored)", t.mirror_ms},
      {"mirror blur levels", t.mirror_mips_ms},
      {"ripple slope maps (bake and upload)", t.ripples_ms},
      {"water", t.water_ms},
      {"scene meshes", t.scene_ms},
      {"sky", t.sky_ms},
      {"resolve and read back", t.readback_ms}};
  for (const auto& [name, ms] : rows)
    out += fmt::format("  {:<40} {:8.2f} ms {:5.1f} %\n", name, ms / pairs, share(ms));
  out += fmt::format("  {:<40} {:8.2f} ms {:5.1f} % (ms a truth pass)\n",
                     "truth: depth and moving mask", t.truth_ms / truths, share(t.truth_ms));
  return out;
}

bool StereoRenderer::has_moving_things() const {
  const Impl& m = *impl_;
  return !m.movers.empty() ||
         (!m.sway.empty() && std::any_of(m.meshes.begin(), m.meshes.end(),
                                         [](const GpuMesh& g) { return g.sway_vbo != 0; }));
}

void StereoRenderer::set_water_order(WaterOrder order) { impl_->water_order = order; }

void StereoRenderer::set_run_culling(bool on) { impl_->run_culling = on; }

std::size_t StereoRenderer::triangles_submitted() const { return impl_->triangles_submitted; }

void StereoRenderer::set_body_pose(const SE3& T_W_B) {
  impl_->T_W_B = T_W_B.matrix().cast<float>();
}

ColourImage StereoRenderer::render_colour(const SE3& T_W_C, double t_s) {
  Impl& m = *impl_;
  DRIFTLAB_DEMAND_MSG(m.colour, "render_colour: the renderer draws gray images");
  m.context->make_current();
  m.lap_start();
  ++m.times.renders;  // one eye's image
  if (m.reflects()) m.draw_reflection(T_W_C, t_s, 0);
  m.draw_eye(T_W_C, t_s, 0);
  const Impl::EyeTargets& e = m.eyes[0];
  const int W = m.rig.camera.width, H = m.rig.camera.height;
  glBindFramebuffer(GL_READ_FRAMEBUFFER, m.options.msaa_samples > 1 ? e.resolve_fbo : e.msaa_fbo);
  std::vector<std::uint8_t> rgba(static_cast<std::size_t>(W) * H * 4);
  glReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
  glBindFramebuffer(GL_FRAMEBUFFER, 0);
  ColourImage img;
  img.width = W;
  img.height = H;
  img.bgr.resize(static_cast<std::size_t>(W) * H * 3);
  for (std::size_t i = 0; i < static_cast<std::size_t>(W) * H; ++i)
    for (std::size_t c = 0; c < 3; ++c) img.bgr[3 * i + c] = rgba[4 * i + 2 - c];
  return img;
}

void StereoRenderer::set_right_camera(const SE3& T_left_right) {
  impl_->T_left_right = T_left_right;
}

StereoImages StereoRenderer::render(const SE3& T_W_C_left, double t_s, bool with_depth) {
  return impl_->render_pair(T_W_C_left, t_s, with_depth, false);
}

StereoImages StereoRenderer::Impl::render_pair(const SE3& T_W_C_left, double t_s, bool with_depth,
                                               bool moving_mask) {
  context->make_current();
  lap_start();
  ++times.renders;
  if (with_depth) ++times.truths;
  if (moving_mask) use_left_mask_target();
  StereoImages out;
  const SE3 T_W_C_right = T_W_C_left * T_left_right;
  // Both mirror images first: an eye's image samples its own, and llvmpipe makes this thread
  // wait until a texture it samples is rasterised; so the right mirror image's vertices are
  // processed while the left one is rasterised, and so on (6 % faster than eye by eye).
  if (reflects()) {
    draw_reflection(T_W_C_left, t_s, 0);
    draw_reflection(T_W_C_right, t_s, 1);
  }
  draw_eye(T_W_C_left, t_s, 0);
  draw_eye(T_W_C_right, t_s, 1);
  if (with_depth) out.depth_left = render_truth(T_W_C_left, t_s).depth;
  out.left = read_eye(0);
  out.right = read_eye(1);
  if (moving_mask) out.moving_left = read_eye(0, GL_GREEN);
  return out;
}

StereoImages StereoRenderer::render_bands(const std::vector<RowBand>& left,
                                          const std::vector<RowBand>& right, bool moving_mask) {
  Impl& m = *impl_;
  DRIFTLAB_DEMAND(!moving_mask || (left.size() == 1 && !m.colour && m.options.msaa_samples == 1));
  const int H = m.rig.camera.height;
  const std::array<const std::vector<RowBand>*, 2> bands = {&left, &right};
  for (const auto* eye_bands : bands) {
    int next_row = 0;
    for (const RowBand& b : *eye_bands) {
      DRIFTLAB_DEMAND(b.row_begin == next_row && b.row_end > b.row_begin);
      next_row = b.row_end;
    }
    DRIFTLAB_DEMAND(next_row == H);
  }
  if (left.size() == 1 && right.size() == 1 && left[0].t_s == right[0].t_s &&
      left[0].T_W_C.matrix() == right[0].T_W_C.matrix())
    return m.render_pair(left[0].T_W_C, left[0].t_s, false, moving_mask);
  m.context->make_current();
  m.lap_start();
  ++m.times.renders;
  if (moving_mask) m.use_left_mask_target();
  // Band by band: each band's mirror image from its own pose, then its rows.
  for (int eye = 0; eye < 2; ++eye) {
    m.clear_eye(eye);
    for (const RowBand& b : *bands[static_cast<std::size_t>(eye)]) {
      const SE3 T_W_C = eye == 0 ? b.T_W_C : b.T_W_C * m.T_left_right;
      if (m.reflects()) m.draw_reflection(T_W_C, b.t_s, eye, b.row_begin, b.row_end);
      m.draw_eye_rows(T_W_C, b.t_s, eye, b.row_begin, b.row_end);
      // Resolved band by band: with multisampling llvmpipe's scissor box lets the next band's
      // triangles into this band's last row (Render.BandsEqualWholeFramesAtEachBandsPose).
      m.resolve_eye(eye, b.row_begin, b.row_end);
    }
  }
  StereoImages out;
  out.left = m.read_eye(0);
  out.right = m.read_eye(1);
  if (moving_mask) out.moving_left = m.read_eye(0, GL_GREEN);
  return out;
}

}  // namespace driftlab::sim
