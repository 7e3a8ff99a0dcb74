// Alpha-tested textures (leaf-cluster cards): the coverage-preserving mip levels, and what the
// renderer draws of a card in colour, depth and the mirror pass.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/rotation.hpp"
#include "sim/render/alpha_mips.hpp"
#include "sim/render/renderer.hpp"
#include "tests/sim/render_fixtures.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::sim {
namespace {

// A W x W texture, white where `inside(x, y)` (texel centres, in texels), alpha 255 there and
// 0 elsewhere; the grey of transparent texels is black, so a leak would show.
template <class Inside>
Texture alpha_texture(int W, Inside inside) {
  Texture t;
  t.name = "leaves";
  t.width = t.height = W;
  for (int y = 0; y < W; ++y)
    for (int x = 0; x < W; ++x) {
      const bool in = inside(x + 0.5, y + 0.5);
      t.pixels.push_back(in ? 255 : 0);
      t.alpha.push_back(in ? 255 : 0);
    }
  return t;
}

// A centred disc of radius r W: coverage pi r^2 (analytic).
Texture disc_texture(int W, double r) {
  return alpha_texture(
      W, [=](double x, double y) { return std::hypot(x - 0.5 * W, y - 0.5 * W) < r * W; });
}

// Leaves: 300 discs of radius 5 texels at random centres (a fine-grained cover whose gaps are
// about as large as the leaves, as a leaf cluster's).
Texture speckle_texture(int W) {
  Rng rng(7);
  std::vector<std::array<double, 2>> c(300);
  for (auto& p : c) p = {rng.uniform(8.0, W - 8.0), rng.uniform(8.0, W - 8.0)};
  return alpha_texture(W, [&](double x, double y) {
    for (const auto& p : c)
      if (std::hypot(x - p[0], y - p[1]) < 5.0) return true;
    return false;
  });
}

std::vector<std::uint8_t> alpha_of(const AlphaMipLevel& L) {
  std::vector<std::uint8_t> a;
  for (std::size_t i = 1; i < L.grey_alpha.size(); i += 2) a.push_back(L.grey_alpha[i]);
  return a;
}

TEST(AlphaMips, EveryLevelCoversWhatLevelZeroCovers) {
  for (const Texture& t : {disc_texture(256, 0.4), speckle_texture(256)}) {
    const double c0 = alpha_coverage(t.alpha);
    const std::vector<AlphaMipLevel> levels = coverage_preserving_mips(t);
    ASSERT_EQ(levels.size(), 9u);  // 256 .. 1
    for (std::size_t k = 0; k < levels.size(); ++k) {
      const double n = static_cast<double>(levels[k].width) * levels[k].height;
      EXPECT_EQ(levels[k].width, 256 >> k);
      // round(c0 N) texels pass: within half a texel of c0.
      EXPECT_LE(std::abs(alpha_coverage(alpha_of(levels[k])) - c0), 0.5 / n + 1e-12)
          << t.name << " level " << k;
    }
  }
  // The analytic coverage of the disc, to the texel grid's error.
  EXPECT_NEAR(alpha_coverage(disc_texture(256, 0.4).alpha), std::numbers::pi * 0.16, 2e-3);
}

TEST(AlphaMips, ABoxFilterWouldThinTheLeavesOut) {
  // The negative control: level 4 of a plain 16 x 16 box mean keeps far less than level 0.
  const Texture t = speckle_texture(256);
  const double c0 = alpha_coverage(t.alpha);
  int passing = 0;
  for (int j = 0; j < 16; ++j)
    for (int i = 0; i < 16; ++i) {
      double s = 0;
      for (int y = 16 * j; y < 16 * j + 16; ++y)
        for (int x = 16 * i; x < 16 * i + 16; ++x)
          s += t.alpha[static_cast<std::size_t>(y * 256 + x)];
      passing += std::lround(s / 256) >= kAlphaOpaqueFrom;
    }
  EXPECT_GT(std::abs(passing / 256.0 - c0), 0.05) << "c0 " << c0 << ", box " << passing / 256.0;
}

TEST(AlphaMips, OpaqueGreyIsTheBlockMeanAndRepeatable) {
  Texture t;
  t.name = "opaque";
  t.width = 8;
  t.height = 4;
  for (int i = 0; i < 32; ++i) {
    t.pixels.push_back(static_cast<std::uint8_t>((i * 37) % 251));
    t.alpha.push_back(255);
  }
  const std::vector<AlphaMipLevel> levels = coverage_preserving_mips(t);
  ASSERT_EQ(levels.size(), 4u);  // 8x4, 4x2, 2x1, 1x1
  // Level 1 texel (i, j): the mean of level 0's 2 x 2 block, computed here.
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 4; ++i) {
      double s = 0;
      for (int y = 2 * j; y < 2 * j + 2; ++y)
        for (int x = 2 * i; x < 2 * i + 2; ++x) s += t.pixels[static_cast<std::size_t>(y * 8 + x)];
      EXPECT_EQ(levels[1].grey_alpha[static_cast<std::size_t>(2 * (j * 4 + i))],
                std::lround(s / 4));
      EXPECT_EQ(levels[1].grey_alpha[static_cast<std::size_t>(2 * (j * 4 + i) + 1)], 255);
    }
  double all = 0;
  for (std::uint8_t p : t.pixels) all += p;
  EXPECT_EQ(levels[3].grey_alpha[0], std::lround(all / 32));
  EXPECT_EQ(coverage_preserving_mips(t)[2].grey_alpha, levels[2].grey_alpha);
  t.alpha.pop_back();
  EXPECT_THROW(coverage_preserving_mips(t), InternalError);
}

// ---------------------------------------------------------------------------
// The renderer.

// A vertical quad facing south (towards cameras looking north) at north x, spanning east
// [y0, y1] and down [z0, z1]; uv (0, 0) at (y0, z0), (1, 1) at (y1, z1).
Mesh card(double x, double y0, double y1, double z0, double z1, int texture) {
  Mesh m;
  m.name = "card";
  m.material.texture = texture;
  m.material.albedo = 1.0f;
  const auto v = [&](double y, double z, float u, float w) {
    return Vertex{
        static_cast<float>(x), static_cast<float>(y), static_cast<float>(z), -1.f, 0.f, 0.f, u, w};
  };
  m.vertices = {v(y0, z0, 0, 0), v(y1, z0, 1, 0), v(y1, z1, 1, 1), v(y0, z1, 0, 1)};
  m.indices = {0, 1, 2, 0, 2, 3};
  return m;
}

int bright_pixels(const GrayImage& img) {
  int n = 0;
  for (std::uint8_t p : img.pixels) n += p > 127;
  return n;
}

TEST(Cutout, ACardCoversWhatItsTextureCoversAtEveryDistance) {
  // A 5.12 m card of 256 texels: 1, 2, 4 and 8 texels a pixel at 10, 20, 40 and 80 m.
  const Texture t = speckle_texture(256);
  const double c0 = alpha_coverage(t.alpha);
  StereoRenderer renderer(fixtures::rig_640(), RenderOptions{});
  for (double d : {10.0, 20.0, 40.0, 80.0}) {
    SceneGeometry s = fixtures::dark_scene();
    s.textures.push_back(t);
    s.meshes.push_back(card(d, -2.56, 2.56, -2.56, 2.56, 0));
    renderer.upload(s);
    const StereoImages img = renderer.render(fixtures::camera_at(Vec3::Zero()), 0.0, false);
    const double side_px = 500 * 5.12 / d;
    const double covered = bright_pixels(img.left) / (side_px * side_px);
    EXPECT_NEAR(covered, c0, 0.02) << d << " m";
  }
}

TEST(Cutout, ACardLooksLikeTheGeometryItsAlphaCovers) {
  // Over calm water in daylight: a card opaque in its upper half only against a quad that is
  // that half, in both eyes, the mirror image and the depth image. Only the half's cut edge
  // (one texel row filtered across the threshold) may differ.
  const Texture half = alpha_texture(64, [](double, double y) { return y < 32.0; });
  const auto render = [&](const Mesh& m) {
    SceneGeometry s;
    s.water.enabled = true;
    Texture white = half;
    white.name = "white";
    white.alpha.clear();
    std::fill(white.pixels.begin(), white.pixels.end(), std::uint8_t{255});
    s.textures = {half, white};
    s.meshes = {m};
    StereoRenderer renderer(fixtures::rig_640(), RenderOptions{});
    renderer.upload(s);
    renderer.set_waves({});
    return renderer.render(fixtures::camera_at(Vec3(0, 0.3, -1.0)), 0.0, true);
  };
  const StereoImages cut = render(card(8, -1.5, 1.5, -3.0, -1.0, 0));
  const StereoImages geo = render(card(8, -1.5, 1.5, -3.0, -2.0, 1));  // texels are white there
  const StereoImages none = render(Mesh{});
  const int card_px = 500 * 3 / 8 * 500 * 1 / 8;  // the half, in pixels
  for (const auto& [a, b] : {std::pair{&cut.left, &geo.left}, std::pair{&cut.right, &geo.right}}) {
    int differ = 0, shown = 0;
    for (std::size_t i = 0; i < a->pixels.size(); ++i) {
      differ += std::abs(a->pixels[i] - b->pixels[i]) > 8;
      shown += std::abs(b->pixels[i] - none.left.pixels[i]) > 8;
    }
    EXPECT_GT(shown, 0.9 * card_px);  // the half (and its dim mirror image) is drawn
    EXPECT_LT(differ, 2 * 2 * 190);   // at most two rows along the cut, direct and mirrored
  }
  int depth_differ = 0;
  for (std::size_t i = 0; i < cut.depth_left.depth_m.size(); ++i)
    depth_differ += std::abs(cut.depth_left.depth_m[i] - geo.depth_left.depth_m[i]) > 1e-3f;
  EXPECT_LT(depth_differ, 2 * 190);
}

TEST(Cutout, DepthShowsExactlyTheColourImagesHoles) {
  const Texture t = speckle_texture(256);
  SceneGeometry s = fixtures::dark_scene();
  s.textures.push_back(t);
  s.meshes.push_back(card(15, -2.56, 2.56, -2.56, 2.56, 0));
  StereoRenderer renderer(fixtures::rig_640(), RenderOptions{});
  renderer.upload(s);
  const StereoImages a = renderer.render(fixtures::camera_at(Vec3::Zero()), 0.0, true);
  int mismatched = 0, drawn = 0, off_plane = 0;
  for (std::size_t i = 0; i < a.left.pixels.size(); ++i) {
    const bool colour = a.left.pixels[i] > 127, depth = a.depth_left.depth_m[i] > 0;
    mismatched += colour != depth;
    drawn += colour;
    if (depth) off_plane += std::abs(a.depth_left.depth_m[i] - 15.0) > 1e-3;
  }
  EXPECT_GT(drawn, 5000);
  EXPECT_EQ(mismatched, 0);
  EXPECT_EQ(off_plane, 0);
  const StereoImages b = renderer.render(fixtures::camera_at(Vec3::Zero()), 0.0, true);
  EXPECT_EQ(a.left.pixels, b.left.pixels);
  EXPECT_EQ(a.right.pixels, b.right.pixels);
}

}  // namespace
}  // namespace driftlab::sim
