// Tests of the tree generator (scenes/trees.hpp) and the leaf-cluster textures
// (scenes/leaf_textures.hpp). Expectations come from the species parameters and Weber & Penn
// (1995) (ShapeRatio is written out here from the paper), not from the code's output.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "core/rng.hpp"
#include "scenes/leaf_textures.hpp"
#include "scenes/mesh_builder.hpp"
#include "scenes/trees.hpp"

namespace driftlab::scenes {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr TreeSpecies kAllSpecies[] = {TreeSpecies::kAlder, TreeSpecies::kWillow,
                                       TreeSpecies::kWeepingWillow, TreeSpecies::kPoplar};

// Weber & Penn (1995), table of shapes: the ratio of a limb's length to the longest at r.
double paper_shape_ratio(int shape, double r) {
  switch (shape) {
    case 0:
      return 0.2 + 0.8 * r;  // conical
    case 1:
      return 0.2 + 0.8 * std::sin(kPi * r);  // spherical
    case 2:
      return 0.2 + 0.8 * std::sin(kPi * r / 2);  // hemispherical
    case 5:
      return r <= 0.7 ? r / 0.7 : (1 - r) / 0.3;  // flame
    default:
      return 1.0;  // not used by the species
  }
}

TreeForm form(TreeSpecies sp, int lod, int seed) {
  TreeForm f;
  f.base_W = Vec3(3.0 * seed, -20.0, -1.5);
  f.height_m = 10 + 0.37 * seed;
  f.crown_radius_m = 0.27 * f.height_m;
  f.trunk_radius_m = 0.1 + 0.02 * f.height_m;
  f.species = sp;
  f.lod = lod;
  f.lean_dir_W = Vec3(std::cos(seed), std::sin(seed), 0);
  f.lean_rad = (seed % 4) * 0.08;
  return f;
}

Rng rng_for(int seed) { return RngStreams(7).stream("test.tree." + std::to_string(seed)); }

double radius_at(const Stem& s, double t) {
  const double f = t * (s.radii.size() - 1);
  const std::size_t k = std::min(s.radii.size() - 2, static_cast<std::size_t>(f));
  return s.radii[k] + (s.radii[k + 1] - s.radii[k]) * (f - k);
}

TEST(TreeSkeleton, CountsAndLengthsFollowTheParameters) {
  for (TreeSpecies sp : kAllSpecies)
    for (int lod = 0; lod < 2; ++lod)
      for (int seed = 0; seed < 20; ++seed) {
        SCOPED_TRACE(std::string(species_params(sp).name) + " lod " + std::to_string(lod) +
                     " seed " + std::to_string(seed));
        const SpeciesParams& p = species_params(sp);
        const TreeForm f = form(sp, lod, seed);
        Rng rng = rng_for(seed);
        const TreeSkeleton s = grow_tree(f, &rng);
        ASSERT_FALSE(s.stems.empty());
        EXPECT_EQ(s.stems[0].level, 0);
        const double l0 = f.height_m / std::cos(f.lean_rad);
        int n1 = 0, n2 = 0, expected_n2 = 0;
        double longest = 0;
        for (const Stem& st : s.stems)
          if (st.level == 1) longest = std::max(longest, st.length_m);
        for (std::size_t i = 0; i < s.stems.size(); ++i) {
          const Stem& st = s.stems[i];
          ASSERT_EQ(st.points.size(), st.radii.size());
          for (std::size_t k = 1; k < st.radii.size(); ++k) EXPECT_LE(st.radii[k], st.radii[k - 1]);
          for (const Vec3& q : st.points) EXPECT_GE(q.z(), s.top_W.z() - 1e-12);
          if (st.level == 0) continue;
          ASSERT_GE(st.parent, 0);
          const Stem& parent = s.stems[st.parent];
          EXPECT_EQ(parent.level, st.level - 1);
          EXPECT_LE(st.radii[0], radius_at(parent, st.fork_t) + 1e-12);
          if (st.level == 1) {
            ++n1;
            EXPECT_GT(st.fork_t * l0, p.base_size * l0);
            EXPECT_LT(st.fork_t, 1.0);
            const double sr = paper_shape_ratio(p.shape, (1 - st.fork_t) / (1 - p.base_size));
            const double nominal = sr * p.n_length1 * l0 * s.length_scale;
            EXPECT_GE(st.length_m, nominal * (1 - p.length_v1) - 1e-9);
            EXPECT_LE(st.length_m, nominal * (1 + p.length_v1) + 1e-9);
            if (lod == 0)
              expected_n2 +=
                  static_cast<int>(std::lround(p.n2 * (0.2 + 0.8 * st.length_m / longest)));
          } else {
            ++n2;
          }
        }
        EXPECT_EQ(n1, p.n1[lod]);
        EXPECT_EQ(n2, expected_n2);
        if (lod == 1) {
          EXPECT_EQ(n2, 0);
        }
        // The apex: exactly h above the base, along the lean.
        EXPECT_NEAR(s.top_W.z(), f.base_W.z() - f.height_m, 1e-9);
        EXPECT_NEAR((s.top_W - f.base_W).head<2>().norm(), f.height_m * std::tan(f.lean_rad), 1e-9);
        // The spread measured here: max horizontal distance from the base-top axis.
        double spread = 0;
        for (const Stem& st : s.stems)
          for (const Vec3& q : st.points) {
            const double h = f.base_W.z() - q.z();
            const Vec3 axis = f.base_W + (s.top_W - f.base_W) * (h / f.height_m);
            spread = std::max(spread, (q - axis).head<2>().norm());
          }
        EXPECT_NEAR(spread, f.crown_radius_m, 0.1 * f.crown_radius_m);
      }
}

TEST(TreeSkeleton, SameSeedSameTreeOtherSeedOtherTree) {
  const TreeForm f = form(TreeSpecies::kWillow, 0, 3);
  Rng a = rng_for(1), b = rng_for(1), c = rng_for(2);
  const TreeSkeleton sa = grow_tree(f, &a), sb = grow_tree(f, &b), sc = grow_tree(f, &c);
  ASSERT_EQ(sa.stems.size(), sb.stems.size());
  for (std::size_t i = 0; i < sa.stems.size(); ++i)
    EXPECT_EQ(sa.stems[i].points, sb.stems[i].points);
  EXPECT_NE(sa.stems[1].points.back(), sc.stems[1].points.back());
}

void expect_well_formed(const sim::Mesh& m) {
  ASSERT_EQ(m.indices.size() % 3, 0u);
  for (auto i : m.indices) ASSERT_LT(i, m.vertices.size());
  for (const auto& v : m.vertices) {
    for (float x : {v.x, v.y, v.z, v.nx, v.ny, v.nz, v.u, v.v}) ASSERT_TRUE(std::isfinite(x));
    EXPECT_NEAR(std::sqrt(double(v.nx) * v.nx + double(v.ny) * v.ny + double(v.nz) * v.nz), 1.0,
                1e-5);
  }
  int wrong = 0;
  for (std::size_t i = 0; i < m.indices.size(); i += 3) {
    const auto& a = m.vertices[m.indices[i]];
    const auto& b = m.vertices[m.indices[i + 1]];
    const auto& c = m.vertices[m.indices[i + 2]];
    const Vec3 pa(a.x, a.y, a.z), pb(b.x, b.y, b.z), pc(c.x, c.y, c.z);
    const Vec3 n = Vec3(a.nx, a.ny, a.nz) + Vec3(b.nx, b.ny, b.nz) + Vec3(c.nx, c.ny, c.nz);
    wrong += (pb - pa).cross(pc - pa).dot(n) > 0 ? 0 : 1;
  }
  EXPECT_EQ(wrong, 0);
}

TEST(TreeMeshes, TriangleAndCardCountsFromTheTable) {
  constexpr int kCards = 90;
  for (TreeSpecies sp : kAllSpecies)
    for (int lod = 0; lod < 2; ++lod)
      for (int seed = 0; seed < 5; ++seed) {
        SCOPED_TRACE(std::string(species_params(sp).name) + " lod " + std::to_string(lod));
        const TreeForm f = form(sp, lod, seed);
        Rng rng = rng_for(seed);
        const TreeSkeleton s = grow_tree(f, &rng);
        MeshBuilder wood("wood", {}), leaves("leaves", {});
        dress_tree(f, s, kCards, &rng, &wood, &leaves);
        int n1 = 0, n2 = 0;
        for (const Stem& st : s.stems) {
          if (st.level == 1) ++n1;
          if (st.level == 2) ++n2;
        }
        // Section 1's table: trunk 6 x 5 = 54 / 5 x 3 = 25, limbs 20 / 9; twigs carry cards
        // but are not drawn (the leaf-cluster texture draws them).
        EXPECT_EQ(n2 > 0, lod == 0);
        const int wood_tri = lod == 0 ? 54 + 20 * n1 : 25 + 9 * n1;
        const int cards = lod == 0 ? kCards : kCards / 2;
        EXPECT_EQ(static_cast<int>(wood.triangle_count()), wood_tri);
        EXPECT_EQ(static_cast<int>(leaves.triangle_count()), 2 * cards);
        EXPECT_EQ(static_cast<int>(leaves.vertex_count()), 4 * cards);
        EXPECT_EQ(tree_triangle_count(s, lod, kCards), wood_tri + 2 * cards);
        const sim::Mesh w = wood.take(), l = leaves.take();
        expect_well_formed(w);
        expect_well_formed(l);
        // Nothing above the apex, and the apex is in the wood.
        float top = 1e9f;
        for (const auto& v : w.vertices) top = std::min(top, v.z);
        EXPECT_NEAR(top, s.top_W.z(), 1e-4);
        for (const auto& v : l.vertices) EXPECT_GE(v.z, s.top_W.z() - 1e-4);
        // Card edges: species factor x h x U(0.85, 1.15), x sqrt 2 at lod 1.
        const double nominal = species_params(sp).card_edge_over_height * f.height_m *
                               (lod == 0 ? 1.0 : std::sqrt(2.0));
        for (std::size_t k = 0; k < l.vertices.size(); k += 4) {
          const auto& a = l.vertices[k];
          const auto& b = l.vertices[k + 1];
          const double edge = Vec3(b.x - a.x, b.y - a.y, b.z - a.z).norm();
          EXPECT_GE(edge, 0.85 * nominal - 1e-4);
          EXPECT_LE(edge, 1.15 * nominal + 1e-4);
        }
      }
}

TEST(TreeMeshes, TubeAndCardFollowTheBuilderConvention) {
  MeshBuilder b("t", {});
  b.tube({Vec3(0, 0, 0), Vec3(0, 0, -1), Vec3(0.2, 0, -2)}, {0.3, 0.2, 0.1}, 5, 1.5);
  EXPECT_EQ(b.triangle_count(), 2u * 5 * 2);  // no tip: 2 segments x 5 sides x 2
  b.tube({Vec3(0, 0, 0), Vec3(0, 0, -1), Vec3(0.2, 0, -2)}, {0.3, 0.2, 0.0}, 4, 1.5);
  EXPECT_EQ(b.triangle_count(), 20u + 4 * 2 + 4);  // tip: 1 ring gap + a fan of 4
  b.card(Vec3(1, 1, -1), Vec3(0.5, 0, 0), Vec3(0, 0, 0.5), Vec3(0, -1, 0));
  EXPECT_EQ(b.triangle_count(), 34u);
  expect_well_formed(b.take());
}

double coverage(const sim::Texture& t) {
  long n = 0;
  for (auto a : t.alpha) n += a >= sim::kAlphaOpaqueFrom ? 1 : 0;
  return static_cast<double>(n) / static_cast<double>(t.alpha.size());
}

// A square cutout texture counted: the alpha in its 2 px border, and its opaque texels (all,
// in the lower half, and their mean grey).
struct Opaque {
  int border_alpha = 0;
  long texels = 0, lower_half = 0;
  double mean_grey = 0;
};
Opaque opaque_texels(const sim::Texture& t) {
  const int w = t.width;
  Opaque o;
  double sum = 0;
  for (int y = 0; y < w; ++y)
    for (int x = 0; x < w; ++x) {
      const std::size_t i = static_cast<std::size_t>(y) * w + x;
      if (x < 2 || y < 2 || x >= w - 2 || y >= w - 2) o.border_alpha += t.alpha[i];
      if (t.alpha[i] < sim::kAlphaOpaqueFrom) continue;
      sum += t.pixels[i], ++o.texels;
      o.lower_half += y >= w / 2 ? 1 : 0;
    }
  o.mean_grey = sum / static_cast<double>(std::max(o.texels, 1L));
  return o;
}

TEST(LeafTextures, CoverageBorderAndDilation) {
  for (LeafShape shape : {LeafShape::kBroad, LeafShape::kNarrow}) {
    const double target = shape == LeafShape::kBroad ? 0.60 : 0.50;
    EXPECT_EQ(leaf_target_coverage(shape), target);
    Rng rng = RngStreams(11).stream("scene.texture.leaves");
    const sim::Texture t = make_leaf_cluster(shape, &rng, 100.0, 0.35);
    SCOPED_TRACE(t.name);
    EXPECT_EQ(t.name, shape == LeafShape::kBroad ? "leaves_broad" : "leaves_narrow");
    ASSERT_EQ(t.width, 256);
    ASSERT_EQ(t.height, 256);
    ASSERT_EQ(t.pixels.size(), 256u * 256u);
    ASSERT_EQ(t.alpha.size(), 256u * 256u);
    const double c = coverage(t);
    EXPECT_GE(c, target);
    EXPECT_LE(c, target + 0.03);
    const int w = t.width;
    auto at = [&](const std::vector<std::uint8_t>& v, int x, int y) { return v[y * w + x]; };
    int border = 0;
    for (int y = 0; y < w; ++y)
      for (int x = 0; x < w; ++x)
        if (x < 2 || y < 2 || x >= w - 2 || y >= w - 2) border += at(t.alpha, x, y);
    EXPECT_EQ(border, 0);
    // A transparent texel next to an opaque one has the grey of one of its opaque neighbours.
    int checked = 0, wrong = 0;
    double sum = 0;
    long opaque = 0;
    for (int y = 1; y < w - 1; ++y)
      for (int x = 1; x < w - 1; ++x) {
        if (at(t.alpha, x, y) >= sim::kAlphaOpaqueFrom) {
          sum += at(t.pixels, x, y), ++opaque;
          continue;
        }
        bool has = false, match = false;
        for (int dy = -1; dy <= 1; ++dy)
          for (int dx = -1; dx <= 1; ++dx)
            if (at(t.alpha, x + dx, y + dy) >= sim::kAlphaOpaqueFrom) {
              has = true;
              match |= at(t.pixels, x + dx, y + dy) == at(t.pixels, x, y);
            }
        if (!has) continue;
        ++checked;
        wrong += match ? 0 : 1;
      }
    EXPECT_GT(checked, 100);
    EXPECT_EQ(wrong, 0);
    EXPECT_NEAR(sum / opaque, 100.0, 1.0);
    // Far transparent texels are not black (the border takes the nearest leaf's grey).
    EXPECT_GT(at(t.pixels, 0, 0), 0);
  }
}

TEST(LeafTextures, ReedClumpCoverageBorderGreyAndSeed) {
  Rng rng = RngStreams(11).stream("scene.texture.reeds_clump");
  const sim::Texture t = make_reed_clump(&rng, 80.0, 0.3);
  EXPECT_EQ(t.name, "reeds_clump");
  ASSERT_EQ(t.width, 256);
  ASSERT_EQ(t.alpha.size(), 256u * 256u);
  const double c = coverage(t);
  EXPECT_GE(c, reed_target_coverage());
  EXPECT_LE(c, reed_target_coverage() + 0.03);
  const Opaque o = opaque_texels(t);
  EXPECT_EQ(o.border_alpha, 0);
  EXPECT_NEAR(o.mean_grey, 80.0, 1.0);
  // Blades taper from their feet at the bottom edge: most of the cover is in the lower half.
  EXPECT_GT(static_cast<double>(o.lower_half) / static_cast<double>(o.texels), 0.6);
  Rng a = RngStreams(1).stream("x"), b = RngStreams(1).stream("x"), d = RngStreams(2).stream("x");
  const sim::Texture ta = make_reed_clump(&a, 90, 0.3), tb = make_reed_clump(&b, 90, 0.3),
                     td = make_reed_clump(&d, 90, 0.3);
  EXPECT_EQ(ta.alpha, tb.alpha);
  EXPECT_EQ(ta.pixels, tb.pixels);
  EXPECT_NE(ta.alpha, td.alpha);
}

TEST(LeafTextures, TreeBillboardCoverageBorderAndGrey) {
  Rng rng = RngStreams(11).stream("scene.texture.tree_billboard");
  const sim::Texture t = make_tree_billboard(&rng, 70.0, 0.3);
  EXPECT_EQ(t.name, "tree_billboard");
  const double c = coverage(t);
  EXPECT_GE(c, billboard_target_coverage());
  EXPECT_LE(c, billboard_target_coverage() + 0.03);
  const Opaque o = opaque_texels(t);
  EXPECT_EQ(o.border_alpha, 0);
  EXPECT_NEAR(o.mean_grey, 70.0, 1.0);
  // The trunk reaches the bottom: an opaque texel in the bottom rows' middle.
  const int w = t.width;
  bool trunk = false;
  for (int x = w / 3; x < 2 * w / 3; ++x)
    trunk |= t.alpha[(w - 4) * w + x] >= sim::kAlphaOpaqueFrom;
  EXPECT_TRUE(trunk);
}

TEST(LeafTextures, SameSeedSameBytesOtherSeedOtherBytes) {
  for (LeafShape shape : {LeafShape::kBroad, LeafShape::kNarrow}) {
    Rng a = RngStreams(1).stream("x"), b = RngStreams(1).stream("x"), c = RngStreams(2).stream("x");
    const sim::Texture ta = make_leaf_cluster(shape, &a, 90, 0.3);
    const sim::Texture tb = make_leaf_cluster(shape, &b, 90, 0.3);
    const sim::Texture tc = make_leaf_cluster(shape, &c, 90, 0.3);
    EXPECT_EQ(ta.pixels, tb.pixels);
    EXPECT_EQ(ta.alpha, tb.alpha);
    EXPECT_NE(ta.alpha, tc.alpha);
    EXPECT_NE(ta.pixels, tc.pixels);
  }
}

}  // namespace
}  // namespace driftlab::scenes
