#include "sim/render/renderer_impl.hpp"

namespace driftlab::sim {

using namespace render;  // the passes' helpers (renderer_impl.hpp)

namespace {

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

}  // namespace driftlab::sim
