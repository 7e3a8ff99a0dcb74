#include "sim/render/renderer.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <memory>
#include <numbers>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "sim/physics/waves/wave_field.hpp"
#include "sim/physics/wind/gusts.hpp"
#include "sim/render/mip_chain.hpp"
#include "tests/sim/render_disc_fixtures.hpp"
#include "tests/sim/render_fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

using fixtures::camera_at;
using fixtures::checker_disc_over_water;
using fixtures::dark_scene;
using fixtures::disc;
using fixtures::rig_640;

TEST(Projection, MapsPixelCentresToNdc) {
  const PinholeCamera cam;
  const Eigen::Matrix4f P = projection_from_intrinsics(cam, 0.1f, 100.f);
  // A point that projects to pixel (u, v) lands on the centre of window pixel (u, v).
  const Eigen::Vector4f p(0.7f, -0.3f, 10.f, 1.f);
  const Eigen::Vector4f c = P * p;
  const double u = 500 * 0.07 + 319.5, v = 500 * -0.03 + 239.5;
  EXPECT_NEAR((c.x() / c.w() + 1) / 2 * 640 - 0.5, u, 1e-4);
  EXPECT_NEAR((c.y() / c.w() + 1) / 2 * 480 - 0.5, v, 1e-4);
  EXPECT_NEAR(P(2, 2) * 10 + P(2, 3), 10 * (-1 + 2 * (10 - 0.1) * 100 / (10 * 99.9)), 1e-3);
}

// Largest error of the x shift of a small bright disc's mirror image on the
// water as the camera steps sideways in tenths of a pixel of image motion,
// against the pinhole's f dx / Z; the disc itself (above the horizon) too.
struct SubPixelShiftError {
  double mirror_px = 0, direct_px = 0;
};
SubPixelShiftError sub_pixel_shift_error(const RenderOptions& options) {
  StereoRenderer renderer(rig_640(), options);
  SceneGeometry s = dark_scene();
  s.water.enabled = true;
  const double Z = 8.0;
  s.meshes.push_back(disc(Vec3(Z, 0, -1.0), 0.15));  // 19 px across, 9 px in the mirror pass
  renderer.upload(s);
  renderer.set_waves({});
  SceneGeometry empty = s;
  empty.meshes.clear();
  StereoRenderer background_renderer(rig_640(), options);
  background_renderer.upload(empty);
  background_renderer.set_waves({});
  // Centroid of (image - background) over rows [y0, y1).
  auto centroid_x = [](const GrayImage& img, const GrayImage& bg, int y0, int y1) {
    double sx = 0, sw = 0;
    for (int y = y0; y < y1; ++y)
      for (int x = 0; x < img.width; ++x) {
        const double w = std::max(0, img.at(x, y) - bg.at(x, y));
        sx += w * x;
        sw += w;
      }
    EXPECT_GT(sw, 0.0);
    return sx / sw;
  };
  SubPixelShiftError worst;
  double mirror0 = 0, direct0 = 0;
  for (int k = 0; k <= 10; ++k) {
    const double dx = -0.1 * k * Z / 500;  // the camera west: the image moves east (+u)
    const SE3 T_W_C = camera_at(Vec3(0, dx, -0.5));
    const GrayImage img = renderer.render(T_W_C, 0.0, false).left;
    const GrayImage bg = background_renderer.render(T_W_C, 0.0, false).left;
    // The disc (1 m up, 0.5 m above the camera) is near row 208; its mirror
    // image (1 m down, 1.5 m below the camera) near row 333; the horizon at 239.5.
    const double direct = centroid_x(img, bg, 150, 235), mirror = centroid_x(img, bg, 245, 400);
    if (k == 0) {
      direct0 = direct;
      mirror0 = mirror;
    }
    const double expected = 0.1 * k;
    worst.direct_px = std::max(worst.direct_px, std::abs(direct - direct0 - expected));
    worst.mirror_px = std::max(worst.mirror_px, std::abs(mirror - mirror0 - expected));
  }
  return worst;
}

TEST(Render, SubPixelMotionOfOutlinesAndReflectionsKeepsItsSize) {
  // Without anti-aliasing a 19 px disc's bright_centroid wanders by about
  // sqrt(60 edge px) * 0.29 px * 7 px / 283 px^2 = 0.06 px about its true
  // position: the floor of this measurement. With the shipped defaults the
  // mirror image moves at its true size to the same floor as the disc.
  const SubPixelShiftError shipped = sub_pixel_shift_error(RenderOptions{});
  EXPECT_LT(shipped.direct_px, 0.08);
  EXPECT_LT(shipped.mirror_px, 0.08);
  // A half-resolution mirror pass (`reflection_resolution: half`) snaps the
  // motion to its 2 px texels, and 4x MSAA in it only halves that.
  RenderOptions half;
  half.reflection_resolution = ReflectionResolution::kHalf;
  const double half_mirror = sub_pixel_shift_error(half).mirror_px;
  EXPECT_GT(half_mirror, 0.15);
  half.reflection_msaa_samples = 4;
  const double half_msaa_mirror = sub_pixel_shift_error(half).mirror_px;
  EXPECT_GT(half_msaa_mirror, 0.08);
  std::printf(
      "[ measured ] largest sub-pixel shift error [px]: disc %.3f, mirror %.3f (shipped), "
      "%.3f (half resolution), %.3f (half resolution, 4x MSAA)\n",
      shipped.direct_px, shipped.mirror_px, half_mirror, half_msaa_mirror);
}

// A planar quad (corners in order around its edge) with normal n, wound counter-clockwise
// about n as Material::double_sided = false requires; textured so that it is not flat grey.
Mesh quad_mesh(const std::array<Vec3, 4>& p, const Vec3& n, bool double_sided) {
  Mesh m;
  m.name = "quad";
  m.material.albedo = 0.9f;
  m.material.double_sided = double_sided;
  for (const Vec3& q : p)
    m.vertices.push_back(Vertex{static_cast<float>(q.x()), static_cast<float>(q.y()),
                                static_cast<float>(q.z()), static_cast<float>(n.x()),
                                static_cast<float>(n.y()), static_cast<float>(n.z()), 0.f, 0.f});
  const bool ccw = (p[1] - p[0]).cross(p[2] - p[0]).dot(n) > 0;
  for (std::uint32_t i : ccw ? std::array<std::uint32_t, 6>{0, 1, 2, 0, 2, 3}
                             : std::array<std::uint32_t, 6>{0, 2, 1, 0, 3, 2})
    m.indices.push_back(i);
  return m;
}

// A closed box [lo, hi], each face wound counter-clockwise about its outward normal.
std::vector<Mesh> box_meshes(const Vec3& lo, const Vec3& hi, bool double_sided) {
  std::vector<Mesh> faces;
  for (int axis = 0; axis < 3; ++axis)
    for (int side : {-1, 1}) {
      const int a = (axis + 1) % 3, b = (axis + 2) % 3;
      std::array<Vec3, 4> p;
      for (int k = 0; k < 4; ++k) {
        Vec3 q;
        q[axis] = side < 0 ? lo[axis] : hi[axis];
        q[a] = (k == 1 || k == 2) ? hi[a] : lo[a];
        q[b] = (k >= 2) ? hi[b] : lo[b];
        p[static_cast<std::size_t>(k)] = q;
      }
      faces.push_back(quad_mesh(p, side * Vec3::Unit(axis), double_sided));
    }
  return faces;
}

int differing_pixels(const GrayImage& a, const GrayImage& b) {
  int n = 0;
  for (std::size_t i = 0; i < a.pixels.size(); ++i) n += a.pixels[i] != b.pixels[i];
  return n;
}

TEST(Render, OneSidedMeshesSkipOnlyTheirBackFaces) {
  // Over calm water, in the default light: each scene's left and right images, mirror images
  // included, with the meshes one-sided and two-sided.
  auto render = [](const std::vector<Mesh>& meshes) {
    SceneGeometry s;
    s.water.enabled = true;
    s.meshes = meshes;
    StereoRenderer renderer(rig_640(), RenderOptions{});
    renderer.upload(s);
    renderer.set_waves({});
    return renderer.render(camera_at(Vec3(0, 0.3, -0.8)), 0.0, false);
  };
  const StereoImages empty = render({});
  // A closed box, 1 m, 8 m ahead: the same images either way (its far faces are hidden).
  const Vec3 lo(8, -0.5, -2.0), hi(9, 0.5, -1.0);
  const StereoImages box2 = render(box_meshes(lo, hi, true)),
                     box1 = render(box_meshes(lo, hi, false));
  EXPECT_GT(differing_pixels(box2.left, empty.left), 5000);
  EXPECT_EQ(differing_pixels(box1.left, box2.left), 0);
  EXPECT_EQ(differing_pixels(box1.right, box2.right), 0);
  // A sheet 2 m x 1.5 m across the view: facing the camera (normal south) it shows, with its
  // mirror image, the same one-sided or two-sided; facing away a one-sided one is not drawn.
  const std::array<Vec3, 4> sheet{Vec3(6, -1, -2), Vec3(6, 1, -2), Vec3(6, 1, -0.5),
                                  Vec3(6, -1, -0.5)};
  const StereoImages front1 = render({quad_mesh(sheet, -Vec3::UnitX(), false)});
  const StereoImages front2 = render({quad_mesh(sheet, -Vec3::UnitX(), true)});
  EXPECT_GT(differing_pixels(front2.left, empty.left), 20000);
  EXPECT_EQ(differing_pixels(front1.left, front2.left), 0);
  EXPECT_EQ(differing_pixels(front1.right, front2.right), 0);
  const StereoImages away1 = render({quad_mesh(sheet, Vec3::UnitX(), false)});
  const StereoImages away2 = render({quad_mesh(sheet, Vec3::UnitX(), true)});
  EXPECT_GT(differing_pixels(away2.left, empty.left), 20000);
  EXPECT_EQ(differing_pixels(away1.left, empty.left), 0);
  EXPECT_EQ(differing_pixels(away1.right, empty.right), 0);
}

TEST(Render, MipLevelsOfTheMirrorImageAreTwoByTwoMeans) {
  // The blur levels of the rippled mirror image, drawn on llvmpipe's raster threads: each texel
  // the mean of the 2x2 texels above it, an odd last row or column left out, rounded to the
  // nearest 8-bit level (either neighbour at an exact half). Odd and even sizes, down to 1x1.
  for (const auto& [W, H] : {std::pair{64, 48}, std::pair{37, 20}}) {
    GrayImage base;
    base.width = W;
    base.height = H;
    Rng rng = RngStreams(5).stream("mip");
    for (int i = 0; i < W * H; ++i)
      base.pixels.push_back(static_cast<std::uint8_t>(rng.uniform_int(256)));
    const std::vector<GrayImage> levels = draw_mip_levels(base, RenderBackend::kOsmesa);
    ASSERT_EQ(static_cast<int>(levels.size()) + 1, mip_level_count(W, H));
    EXPECT_EQ(levels.back().width * levels.back().height, 1);
    const GrayImage* above = &base;
    for (const GrayImage& level : levels) {
      ASSERT_EQ(level.width, std::max(1, above->width / 2));
      ASSERT_EQ(level.height, std::max(1, above->height / 2));
      double worst = 0;
      for (int y = 0; y < level.height; ++y)
        for (int x = 0; x < level.width; ++x) {
          double sum = 0;
          for (int dy : {0, 1})
            for (int dx : {0, 1})
              sum += above->at(std::min(2 * x + dx, above->width - 1),
                               std::min(2 * y + dy, above->height - 1));
          worst = std::max(worst, std::abs(level.at(x, y) - sum / 4));
        }
      EXPECT_LE(worst, 0.5) << W << "x" << H << " level " << level.width << "x" << level.height;
      above = &level;
    }
  }
}

TEST(Render, ProfilingTimesEachPassDrawnAndLeavesTheImagesAsTheyAre) {
  // The same frames with and without the passes timed (glFinish after each), calm and rippled;
  // a pass that is drawn takes time, one that is not (the blur levels and the ripples' maps on
  // calm water) none, and the passes add up to the total.
  StereoRenderer r(rig_640(), RenderOptions{});
  r.upload(checker_disc_over_water(Vec3(8, 0, -1.5), 1.2, 30, 220));
  const SE3 T_W_C = camera_at(Vec3(0, 0, -0.5));
  WindOptions w;
  w.speed_mps = 3.0;
  for (const bool rippled : {false, true}) {
    r.set_ripples(rippled ? std::make_shared<RippleMaps>(w, CurrentOptions{},
                                                         RngStreams(3).stream("water.ripples"))
                          : nullptr);
    r.set_profiling(false);
    const StereoImages plain = r.render(T_W_C, 2.0, false);
    const TruthImages plain_truth = r.render_truth(T_W_C, 2.0);
    r.set_profiling(true);
    const StereoImages timed = r.render(T_W_C, 2.0, false);
    const TruthImages timed_truth = r.render_truth(T_W_C, 2.0);
    EXPECT_EQ(plain.left.pixels, timed.left.pixels) << rippled;
    EXPECT_EQ(plain.right.pixels, timed.right.pixels) << rippled;
    EXPECT_EQ(plain_truth.depth.depth_m, timed_truth.depth.depth_m) << rippled;
    const RenderPassTimes& t = r.pass_times();
    EXPECT_EQ(t.renders, 1);
    EXPECT_EQ(t.truths, 1);
    for (const double ms :
         {t.mirror_ms, t.water_ms, t.scene_ms, t.sky_ms, t.readback_ms, t.truth_ms})
      EXPECT_GT(ms, 0.0) << rippled;
    EXPECT_EQ(t.mirror_mips_ms > 0.0, rippled);
    EXPECT_EQ(t.ripples_ms > 0.0, rippled);
    EXPECT_DOUBLE_EQ(t.total_ms(), t.mirror_ms + t.mirror_mips_ms + t.ripples_ms + t.water_ms +
                                       t.scene_ms + t.sky_ms + t.readback_ms + t.truth_ms);
    const std::string text = describe_passes(t);
    EXPECT_NE(text.find("mirror blur levels"), std::string::npos) << text;
    r.set_profiling(false);
    EXPECT_EQ(r.pass_times().renders, 0);
  }
}

TEST(Render, TheWaterBeforeOrAfterTheSceneGivesTheSameBytes) {
  // A bank sloping out of the water beside a disc: its near part under the water (the water
  // hides it), its far part above (it hides the water behind it). Calm, with a wave, with
  // ripples; single-sampled and 4x multisampled: the water drawn first or last, the same bytes.
  SceneGeometry scene = checker_disc_over_water(Vec3(8, 0, -1.2), 1.0, 40, 220);
  scene.meshes.push_back(quad_mesh(
      {Vec3(5, -2.5, 0.4), Vec3(5, -0.5, 0.4), Vec3(12, -0.5, -1.0), Vec3(12, -2.5, -1.0)},
      Vec3(-0.2, 0, -1).normalized(), true));
  const SE3 T_W_C = camera_at(Vec3(0, 0, -0.5));
  WindOptions wind;
  wind.speed_mps = 3.0;
  const WaveComponent wave{0.02, 2 * std::numbers::pi / 1.5, 3.0, 0.3, 0.1};
  using Order = StereoRenderer::WaterOrder;
  for (const int samples : {1, 4}) {
    RenderOptions o;
    o.msaa_samples = samples;
    StereoRenderer r(rig_640(), o);
    r.upload(scene);
    for (const int water : {0, 1, 2}) {  // calm, a wave, ripples
      r.set_waves(water == 1 ? std::vector<WaveComponent>{wave} : std::vector<WaveComponent>{});
      r.set_ripples(water == 2 ? std::make_shared<RippleMaps>(wind, CurrentOptions{},
                                                              RngStreams(3).stream("water.ripples"))
                               : nullptr);
      std::vector<StereoImages> got;
      for (const Order order : {Order::kFirst, Order::kLast, Order::kByCost}) {
        r.set_water_order(order);
        got.push_back(r.render(T_W_C, 1.25, false));
      }
      for (std::size_t k : {1u, 2u}) {
        EXPECT_TRUE(got[0].left.pixels == got[k].left.pixels)
            << samples << " " << water << " " << k;
        EXPECT_TRUE(got[0].right.pixels == got[k].right.pixels) << samples << " " << water;
      }
    }
  }
  // Both kinds of hiding happen (columns left of the disc, rows below the horizon): the depth
  // with the water against the bank's own depth (the water switched off).
  StereoRenderer r(rig_640(), RenderOptions{});
  r.upload(scene);
  const DepthImage wet = r.render_truth(T_W_C, 1.25).depth;
  scene.water.enabled = false;
  r.upload(scene);
  const DepthImage dry = r.render_truth(T_W_C, 1.25).depth;
  int water_hides_bank = 0, bank_hides_water = 0;
  for (int y = 241; y < 480; ++y)
    for (int x = 0; x < 250; ++x) {
      if (dry.at(x, y) <= 0.f) continue;
      water_hides_bank += wet.at(x, y) < dry.at(x, y) - 1e-3f;
      bank_hides_water += wet.at(x, y) == dry.at(x, y);
    }
  EXPECT_GT(water_hides_bank, 2000);
  EXPECT_GT(bank_hides_water, 2000);
}

// Runs of triangles outside a pass's view are skipped (StereoRenderer::set_run_culling): two
// rows of 400 posts along y from -24 to 24 m, one rigid, one with its tops swaying in a gale,
// mirrored in the water, seen by cameras turned so that the edges of the view cut the runs at
// many places (the fine sweep of yaws brings the right edge past a run of swaying posts whose
// tops the gust at t = 0.4 s leans into the view: without the sway's margin it would be
// culled); drawn with the runs culled and without: the same images and truth, and most of the
// rows' triangles never sent.
TEST(Render, CullingRunsOfTrianglesGivesTheSameBytes) {
  SceneGeometry scene = checker_disc_over_water(Vec3(8, 0, -1.2), 1.0, 40, 220);
  for (const bool sways : {false, true})  // rigid posts 6 m north, swaying ones 9 m, above them
    for (int i = 0; i < 400; ++i) {
      const double x = sways ? 9 : 6, y = -24 + 0.12 * i, z = sways ? -1.0 : -0.1;
      Mesh post = quad_mesh(
          {Vec3(x, y, z), Vec3(x, y + 0.08, z), Vec3(x, y + 0.08, z - 0.8), Vec3(x, y, z - 0.8)},
          -Vec3::UnitX(), true);
      post.material.albedo = sways ? 0.6f : 0.9f;  // in a batch of its own
      if (sways) post.sway = {{0.f, 0.f}, {0.f, 0.f}, {3.f, 0.5f}, {3.f, 0.5f}};
      scene.meshes.push_back(post);
    }
  WindOptions wind;
  wind.speed_mps = 8;
  wind.direction_deg = 90;  // across the view: posts at its edges sway in and out of it
  std::vector<GrayImage> images;
  std::vector<std::vector<float>> depths;
  std::vector<std::size_t> sent;
  for (const bool cull : {true, false}) {
    StereoRenderer r(rig_640(), RenderOptions{});
    r.upload(scene);
    r.set_sway(vegetation_sway(wind, Rng(5)));
    r.set_run_culling(cull);
    for (int k = 0; k < 20; ++k) {
      const double yaw_deg = k < 3 ? -21.0 + 24 * k : -3.0 + 0.25 * (k - 3);
      const Mat3 R = Eigen::AngleAxisd(deg2rad(yaw_deg), Vec3::UnitZ()).toRotationMatrix();
      const SE3 T_W_C(R * R_frd_optical(), Vec3(0, 0, -0.5));
      for (double t : {0.4, 3.3}) {
        const StereoImages pair = r.render(T_W_C, t, false);
        images.push_back(pair.left);
        images.push_back(pair.right);
        depths.push_back(r.render_truth(T_W_C, t).depth.depth_m);
      }
    }
    sent.push_back(r.triangles_submitted());
  }
  const std::size_t n = depths.size() / 2;
  int differ = 0;
  for (std::size_t k = 0; k < n; ++k) {
    differ += images[2 * k].pixels != images[2 * (k + n)].pixels;
    differ += images[2 * k + 1].pixels != images[2 * (k + n) + 1].pixels;
    differ += depths[k] != depths[k + n];
  }
  EXPECT_EQ(differ, 0);
  // Culling sent fewer than half the triangles: each pass (two mirror images, two eyes, the
  // truth) sees 8 to 12 m of each row's 48.
  EXPECT_LT(static_cast<double>(sent[0]), 0.5 * static_cast<double>(sent[1]));
  EXPECT_GT(sent[0], 0u);
}

// A rolling-shutter image, band by band, against its second method: each band's rows cut out of
// a whole frame rendered at that band's pose and time. The bands draw only the rows of their
// mirror images that their rows read (StereoRenderer::Impl::reflection_rows), so steep waves,
// which move the reflection lookup by up to 0.15 x 0.6 of the image (about 43 rows), and a
// camera that moves and turns from band to band would show any row read from an earlier band.
TEST(Render, BandsEqualWholeFramesAtEachBandsPose) {
  SceneGeometry scene = checker_disc_over_water(Vec3(8, 0, -1.2), 1.0, 40, 220);
  // And a copy of the disc moving east behind it at 3 m/s (4 px from band to band), so that
  // each band draws the movers, and their mirror images, at its own time.
  scene.meshes.push_back(scene.meshes[0]);
  scene.meshes.back().mover = 0;
  MoverMotion east;
  east.p0_W = Vec3(4, -1.5, 0);
  east.v_W = Vec3(0, 3, 0);
  scene.movers.push_back(east);
  // Two trains of steep short waves: slope sum 2 x 0.02 x 2 pi / 0.4 = 0.63.
  std::vector<WaveComponent> waves;
  for (double dir : {0.3, 1.9}) {
    const double k = 2 * std::numbers::pi / 0.4;
    waves.push_back(WaveComponent{0.02, k, std::sqrt(9.81 * k), dir, 0.7 * dir});
  }
  RenderOptions msaa;
  msaa.msaa_samples = 4;
  msaa.reflection_msaa_samples = 4;
  RenderOptions half;
  half.reflection_resolution = ReflectionResolution::kHalf;
  for (const RenderOptions& options : {RenderOptions{}, msaa, half}) {
    StereoRenderer r(rig_640(), options);
    r.upload(scene);
    r.set_waves(waves);
    std::vector<RowBand> bands;
    const int kBands = 8, H = 480;
    for (int i = 0; i < kBands; ++i) {
      const SE3 turn(Eigen::AngleAxisd(0.02 * i, Vec3::UnitZ()).toRotationMatrix(), Vec3::Zero());
      bands.push_back(RowBand{turn * camera_at(Vec3(0, 0.05 * i, -1.0 - 0.01 * i)), 0.03 * i,
                              i * H / kBands, (i + 1) * H / kBands});
    }
    const StereoImages banded = r.render_bands(bands, bands);
    StereoImages expected = banded;
    for (const RowBand& b : bands) {
      const StereoImages whole = r.render(b.T_W_C, b.t_s, false);
      for (int y = b.row_begin; y < b.row_end; ++y)
        for (int x = 0; x < 640; ++x) {
          expected.left.pixels[static_cast<std::size_t>(y) * 640 + x] = whole.left.at(x, y);
          expected.right.pixels[static_cast<std::size_t>(y) * 640 + x] = whole.right.at(x, y);
        }
    }
    EXPECT_EQ(differing_pixels(banded.left, expected.left), 0)
        << "msaa " << options.msaa_samples << ", reflection " << options.reflection_msaa_samples;
    EXPECT_EQ(differing_pixels(banded.right, expected.right), 0);
    // The test sees the reflection: the bands' images differ from a whole frame at one pose.
    EXPECT_GT(differing_pixels(banded.left, r.render(bands[0].T_W_C, 0, false).left), 1000);
  }
}

// Haze: a surface d metres away keeps exp(-d / fog_distance_m) of its contrast against the
// sky's grey (the scene shader's transmittance; scene.river_reach.visibility_m sets the
// distance by Koschmieder's law). A quad 0.1 d wide (50 px at any d), dark on its west half and
// bright on its east half, its contrast in haze over its contrast in clear air, at 25-400 m.
TEST(Render, HazeKeepsExpMinusDistanceOverItsLengthOfTheContrast) {
  const auto contrast = [](double d, float fog_distance_m) {
    SceneGeometry s = dark_scene();
    s.lighting.ambient = 1.0f;  // no texel saturates: 240 x 0.675 / 255
    s.lighting.sky_brightness = 0.5f;
    s.lighting.fog_distance_m = fog_distance_m;
    Texture t;
    t.name = "halves";
    t.width = t.height = 64;
    for (int y = 0; y < 64; ++y)
      for (int x = 0; x < 64; ++x) t.pixels.push_back(x < 32 ? 40 : 240);
    s.textures.push_back(t);
    const double w = 0.05 * d;
    Mesh m = quad_mesh({Vec3(d, -w, -w), Vec3(d, w, -w), Vec3(d, w, w), Vec3(d, -w, w)},
                       Vec3(-1, 0, 0), true);
    m.material.texture = 0;
    for (auto& v : m.vertices) {
      v.u = static_cast<float>((v.y + w) / (2 * w));
      v.v = static_cast<float>((v.z + w) / (2 * w));
    }
    s.meshes.push_back(m);
    StereoRenderer r(rig_640(), RenderOptions{});
    r.upload(s);
    const GrayImage img = r.render(camera_at(Vec3::Zero()), 0, false).left;
    double dark = 0, bright = 0;
    for (int y = 225; y < 255; ++y)
      for (int x = 0; x < 12; ++x) {
        dark += img.at(300 + x, y);
        bright += img.at(327 + x, y);
      }
    return (bright - dark) / (30 * 12);
  };
  for (double d : {25.0, 100.0, 400.0}) {
    const double clear = contrast(d, 1e9f), hazy = contrast(d, 200.f);
    ASSERT_GT(clear, 100.0) << d;
    EXPECT_NEAR(hazy / clear, std::exp(-d / 200.0), 1.0 / clear) << "at " << d << " m";
  }
}

// Water, a static wall (its meshes first: *statics of them), a hull rolling and heaving across
// the view behind it and a square sliding east (the movers).
SceneGeometry movers_scene(std::size_t* statics) {
  SceneGeometry with = dark_scene();
  with.water.enabled = true;
  with.meshes = box_meshes(Vec3(7, 0.4, -2.5), Vec3(7.5, 1.5, -0.6), false);  // a static wall
  *statics = with.meshes.size();
  for (Mesh m : box_meshes(Vec3(-0.3, -0.8, -0.9), Vec3(0.3, 0.8, 0.3), false)) {
    m.mover = 0;  // a hull in its own frame, 0.3 m of it under the water
    with.meshes.push_back(m);
  }
  Mesh square =
      quad_mesh({Vec3(0, -0.5, -1.5), Vec3(0, 0.5, -1.5), Vec3(0, 0.5, -0.5), Vec3(0, -0.5, -0.5)},
                -Vec3::UnitX(), false);
  square.mover = 1;
  with.meshes.push_back(square);
  MoverMotion hull;
  hull.p0_W = Vec3(10, -2.0, 0);
  hull.v_W = Vec3(0, 1.5, 0);
  hull.roll = {0.1, 2.0, 0.3};
  hull.heave = {0.05, 1.5, 0.0};
  MoverMotion sliding;
  sliding.p0_W = Vec3(20, -3.0, -0.5);
  sliding.v_W = Vec3(0, 1.37, 0);
  with.movers = {hull, sliding};
  return with;
}

// The moving things' mask: a mover's mask is exactly the pixels whose depth
// differs from a render of the scene without it (a second method), over water (its part under
// the waterline is hidden) and behind a static wall that hides a part of it; and the mover is
// where its closed-form motion puts it: a square facing the camera, moving east, has its mask's
// centroid on the projection of its centre at each instant (a fronto-parallel square projects
// affinely, so its area's centroid is its centre's image).
TEST(Render, MoversMaskIsWhereTheirDepthDiffersFromTheSceneWithoutThem) {
  std::size_t statics = 0;
  const SceneGeometry with = movers_scene(&statics);
  const MoverMotion sliding = with.movers[1];
  SceneGeometry without = with;
  without.meshes.resize(statics);
  without.movers.clear();
  StereoRenderer a(rig_640(), RenderOptions{}), b(rig_640(), RenderOptions{});
  a.upload(with);
  b.upload(without);
  EXPECT_TRUE(a.has_moving_things());
  EXPECT_FALSE(b.has_moving_things());
  const SE3 T_W_C = camera_at(Vec3(0, 0, -1.0));
  for (double t : {0.1, 0.8, 1.9}) {
    const TruthImages moving = a.render_truth(T_W_C, t), still = b.render_truth(T_W_C, t);
    int set = 0, wrong = 0, square_px = 0;
    double square_u = 0;
    const double z_square = 20 - T_W_C.translation().x();
    for (std::size_t i = 0; i < moving.moving.pixels.size(); ++i) {
      const bool differs = moving.depth.depth_m[i] != still.depth.depth_m[i];
      const bool masked = moving.moving.pixels[i] == 255;
      set += masked;
      wrong += masked != differs || (moving.moving.pixels[i] != 0 && !masked);
      if (masked && std::abs(moving.depth.depth_m[i] - z_square) < 1e-3) {
        ++square_px;
        square_u += static_cast<double>(i % 640);
      }
    }
    EXPECT_EQ(wrong, 0) << "t " << t;
    EXPECT_GT(set, 3000) << "t " << t;
    EXPECT_GT(square_px, 500) << "t " << t;
    // The pixel centres whose columns the square's edges enclose (half-open, as rasterised).
    const double east = sliding.T_W_M(t).translation().y() - T_W_C.translation().y();
    const double first = std::ceil(319.5 + 500 * (east - 0.5) / z_square);
    const double last = std::ceil(319.5 + 500 * (east + 0.5) / z_square) - 1;
    EXPECT_NEAR(square_u / square_px, (first + last) / 2, 0.01) << "t " << t;
  }
  // The wall hides a part of the hull at t = 1.9 (east of 0.4 m, behind x = 7): the mask there
  // shows the wall, not the hull.
  const TruthImages late = a.render_truth(T_W_C, 1.9);
  const int u_wall = static_cast<int>(319.5 + 500 * 1.0 / 7.0);
  const int v_wall = static_cast<int>(239.5 + 500 * (-1.0 - -1.0) / 7.0) + 20;
  EXPECT_EQ(late.moving.at(u_wall, v_wall), 0);
  EXPECT_NEAR(late.depth.at(u_wall, v_wall), 7.0, 0.01);
  EXPECT_EQ(late.moving.at(u_wall, v_wall + 16), 255);  // below the wall: the hull
  EXPECT_GT(late.depth.at(u_wall, v_wall + 16), 9.6);
}

// The wind in the vegetation: a sheet whose vertices sway with weight 1 is drawn, at each
// instant, where sim::VegetationSway::sway_m puts each vertex (its edges moved downwind, east
// here), so its mask's centroid is the centre of the pixel columns between the moved edges; it
// is in the mask of moving things, a rigid sheet beside it is not.
TEST(Render, SwayingSheetIsWhereItsGustsPutItAndInTheMask) {
  SceneGeometry scene = dark_scene();
  Mesh sheet = quad_mesh(
      {Vec3(10, -0.5, -1.5), Vec3(10, 0.5, -1.5), Vec3(10, 0.5, -0.5), Vec3(10, -0.5, -0.5)},
      -Vec3::UnitX(), true);
  sheet.sway.assign(4, {1.f, 0.f});
  scene.meshes.push_back(sheet);
  Mesh rigid = quad_mesh(
      {Vec3(10, -2.5, -1.5), Vec3(10, -1.5, -1.5), Vec3(10, -1.5, -0.5), Vec3(10, -2.5, -0.5)},
      -Vec3::UnitX(), true);
  scene.meshes.push_back(rigid);
  WindOptions wind;
  wind.speed_mps = 8;
  wind.direction_deg = 90;  // towards the east: across the view
  VegetationSway sway = vegetation_sway(wind, Rng(11));
  sway.flutter_amplitude_m = 0;
  StereoRenderer r(rig_640(), RenderOptions{});
  r.upload(scene);
  EXPECT_FALSE(r.has_moving_things());  // no wind yet
  r.set_sway(sway);
  EXPECT_TRUE(r.has_moving_things());
  const SE3 T_W_C = camera_at(Vec3(0, 0, -1.0));
  double moved = 0;
  for (double t : {1.3, 7.1, 22.6}) {
    const TruthImages truth = r.render_truth(T_W_C, t);
    int n = 0, rigid_masked = 0;
    double u = 0;
    for (int y = 0; y < 480; ++y)
      for (int x = 0; x < 640; ++x) {
        if (truth.moving.at(x, y) == 0) continue;
        if (x < 270) ++rigid_masked;
        ++n;
        u += x;
      }
    const double west = -0.5 + sway.sway_m(Eigen::Vector2d(10, -0.5), t);
    const double east = 0.5 + sway.sway_m(Eigen::Vector2d(10, 0.5), t);
    const double first = std::ceil(319.5 + 50 * west), last = std::ceil(319.5 + 50 * east) - 1;
    ASSERT_GT(n, 1000) << t;
    EXPECT_EQ(rigid_masked, 0) << t;
    EXPECT_NEAR(u / n, (first + last) / 2, 0.02) << "t " << t;
    moved = std::max(moved, std::abs(west + 0.5));
  }
  EXPECT_GT(moved * 50, 1.0);  // the gusts moved it by a pixel or more
}

// The left eye's pass writes the moving mask beside its image (render_bands' moving_mask): the
// same pixels as render_truth's pass (a second method), movers and a swaying sheet, with the
// pair in step or the right image later; the images the same bytes as a renderer's that never
// drew a mask. A rolling shutter's bands or multisampling cannot give it.
TEST(Render, LeftPassMaskIsTheTruthPasssMask) {
  std::size_t statics = 0;
  SceneGeometry scene = movers_scene(&statics);
  Mesh sheet = quad_mesh(
      {Vec3(12, -3.5, -2.5), Vec3(12, -2.5, -2.5), Vec3(12, -2.5, -1.5), Vec3(12, -3.5, -1.5)},
      -Vec3::UnitX(), true);
  sheet.sway.assign(4, {1.f, 0.f});
  scene.meshes.push_back(sheet);
  WindOptions wind;
  wind.speed_mps = 8;
  const VegetationSway sway = vegetation_sway(wind, Rng(11));
  StereoRenderer r(rig_640(), RenderOptions{}), plain(rig_640(), RenderOptions{});
  for (StereoRenderer* x : {&r, &plain}) {
    x->upload(scene);
    x->set_sway(sway);
  }
  const SE3 T_W_C = camera_at(Vec3(0, 0, -1.0));
  for (double t : {0.1, 0.8, 1.9}) {
    const TruthImages truth = r.render_truth(T_W_C, t);
    for (double right_later_s : {0.0, 0.02}) {
      const std::vector<RowBand> left{{T_W_C, t, 0, 480}};
      const std::vector<RowBand> right{{T_W_C, t + right_later_s, 0, 480}};
      const StereoImages got = r.render_bands(left, right, true);
      const StereoImages want = plain.render_bands(left, right);
      EXPECT_TRUE(got.moving_left.pixels == truth.moving.pixels) << "t " << t;
      EXPECT_GT(std::count(got.moving_left.pixels.begin(), got.moving_left.pixels.end(), 255), 3000)
          << "t " << t;
      EXPECT_TRUE(got.left.pixels == want.left.pixels) << "t " << t;
      EXPECT_TRUE(got.right.pixels == want.right.pixels) << "t " << t;
      EXPECT_TRUE(want.moving_left.pixels.empty());
    }
  }
  const std::vector<RowBand> two{{T_W_C, 0.1, 0, 240}, {T_W_C, 0.1, 240, 480}};
  EXPECT_THROW(r.render_bands(two, two, true), InternalError);
  RenderOptions msaa;
  msaa.msaa_samples = 4;
  StereoRenderer multisampled(rig_640(), msaa);
  const std::vector<RowBand> one{{T_W_C, 0.1, 0, 480}};
  EXPECT_THROW(multisampled.render_bands(one, one, true), InternalError);
}

TEST(Render, BadRigIsAClearError) {
  StereoRig rig = rig_640();
  rig.camera.fx = -1;
  try {
    StereoRenderer r(rig, RenderOptions{});
    FAIL();
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("fx"), std::string::npos) << e.what();
  }
}

TEST(Render, MixingBackendsIsAClearError) {
  // Mesa's OSMesa and its EGL driver share one dispatch: an OSMesa renderer used after an EGL
  // one was created reads back wrong frames (a depth image of zeros), so a
  // second backend in one process is refused, naming both; after the first is gone it works.
  RenderOptions egl;
  egl.backend = RenderBackend::kEgl;
  {
    StereoRenderer osmesa(rig_640(), RenderOptions{});
    try {
      StereoRenderer second(rig_640(), egl);
      ADD_FAILURE() << "an EGL renderer was created beside an OSMesa one";
    } catch (const UserError& e) {
      const std::string what = e.what();
      EXPECT_NE(what.find("render.backend egl"), std::string::npos) << what;
      EXPECT_NE(what.find("osmesa is still alive"), std::string::npos) << what;
    }
  }
  EXPECT_NO_THROW(StereoRenderer(rig_640(), RenderOptions{}));
}

TEST(Render, EglBackendWorksOrSaysWhy) {
#if defined(DRIFTLAB_TEST_ASAN)
  // Mesa's EGL loads its DRI driver (swrast_dri.so), whose once-only globals it leaves behind
  // when eglTerminate unloads the driver: LeakSanitizer then reports 128 bytes from a module
  // without a name, which no suppression can match. The normal build runs this test.
  GTEST_SKIP() << "EGL under AddressSanitizer: Mesa's unloaded DRI driver leaks its globals";
#endif
  RenderOptions o;
  o.backend = RenderBackend::kEgl;
  try {
    StereoRenderer r(rig_640(), o);
    std::cout << "EGL: " << r.context_description() << "\n";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("render.backend egl"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace driftlab::sim
