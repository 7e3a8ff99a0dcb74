#include "sim/render/renderer_impl.hpp"

namespace driftlab::sim {

using namespace render;  // the passes' helpers (renderer_impl.hpp)

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
