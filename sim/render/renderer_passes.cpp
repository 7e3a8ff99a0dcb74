#include "sim/render/renderer_impl.hpp"

namespace driftlab::sim {

using namespace render;  // the passes' helpers (renderer_impl.hpp)

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

}  // namespace driftlab::sim
