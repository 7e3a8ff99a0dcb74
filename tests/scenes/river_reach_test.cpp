// Tests of the river reach scene: its tiles, banks, vegetation, bridge and quay, haze and its
// options. Expectations come from the options and the papers (river paper Table 4 for feature
// depths), not from the code.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/yaml_io.hpp"
#include "scenes/river_reach.hpp"
#include "scenes/scene_options.hpp"
#include "scenes/trees.hpp"
#include "sim/physics/wind/gusts.hpp"
#include "tests/scenes/scenes_fixtures.hpp"

namespace driftlab::scenes {
namespace {

using fixtures::default_reach;
using fixtures::expect_well_formed;
using fixtures::find_mesh;
using fixtures::kSeed;
using fixtures::name_has;
using fixtures::pos;
using fixtures::RayCaster;
using fixtures::river_defaults;
using fixtures::Vec3;

struct DepthStats {
  std::size_t hits = 0, water = 0, sky = 0;
  double p10 = 0, median = 0, mean = 0, p90 = 0;
};

// Depth (along the optical axis) of what a 640 x 480, f = 500 px camera
// (the river_crossing scenario's rig) sees on a 40 x 30 grid of rays, from
// `o` at the given headings, level. Rays that meet the water first (its
// features are reflections, not structure) or nothing (sky) are counted apart.
DepthStats feature_depths(const RayCaster& rc, const std::vector<Vec3>& origins,
                          const std::vector<double>& headings_deg) {
  DepthStats s;
  std::vector<double> d;
  for (const Vec3& o : origins)
    for (double h : headings_deg) {
      const double psi = h * std::numbers::pi / 180;
      const Vec3 fwd(std::cos(psi), std::sin(psi), 0), right(-std::sin(psi), std::cos(psi), 0),
          down(0, 0, 1);
      for (int j = 0; j < 30; ++j)
        for (int i = 0; i < 40; ++i) {
          const double u = (i + 0.5) * 16 - 320, v = (j + 0.5) * 16 - 240;
          const Vec3 ray = (fwd + u / 500 * right + v / 500 * down).normalized();
          const double t = rc.cast(o, ray);
          const double t_water =
              ray.z() > 0 ? -o.z() / ray.z() : std::numeric_limits<double>::infinity();
          if (t_water < t) {
            ++s.water;
          } else if (!std::isfinite(t)) {
            ++s.sky;
          } else {
            d.push_back(t * ray.dot(fwd));
          }
        }
    }
  std::sort(d.begin(), d.end());
  s.hits = d.size();
  if (d.empty()) return s;
  auto q = [&](double f) {
    return d[static_cast<std::size_t>(f * static_cast<double>(d.size() - 1))];
  };
  s.p10 = q(0.1);
  s.median = q(0.5);
  s.p90 = q(0.9);
  for (double x : d) s.mean += x;
  s.mean /= static_cast<double>(d.size());
  return s;
}

TEST(RiverReach, MeshesAreWellFormed) {
  const auto& g = default_reach();
  expect_well_formed(g);
  EXPECT_FALSE(g.lighting.sun);
}

TEST(RiverReach, SameSeedSameSceneOtherSeedOtherScene) {
  const auto& a = default_reach();
  const auto b = build_river_reach(river_defaults(), Sky::kOvercast, kSeed, 0, 120);
  const auto c = build_river_reach(river_defaults(), Sky::kOvercast, kSeed + 1, 0, 120);
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (std::size_t i = 0; i < a.meshes.size(); ++i) {
    ASSERT_EQ(a.meshes[i].vertices.size(), b.meshes[i].vertices.size());
    EXPECT_EQ(0, std::memcmp(a.meshes[i].vertices.data(), b.meshes[i].vertices.data(),
                             a.meshes[i].vertices.size() * sizeof(sim::Vertex)))
        << a.meshes[i].name;
    EXPECT_EQ(a.meshes[i].indices, b.meshes[i].indices);
  }
  ASSERT_EQ(a.textures.size(), b.textures.size());
  for (std::size_t i = 0; i < a.textures.size(); ++i)
    EXPECT_EQ(a.textures[i].pixels, b.textures[i].pixels);
  const auto* ta = find_mesh(a, "tile0.tree_leaves_broad_e0");
  const auto* tc = find_mesh(c, "tile0.tree_leaves_broad_e0");
  ASSERT_TRUE(ta && tc);
  EXPECT_NE(ta->vertices.size() == tc->vertices.size() &&
                0 == std::memcmp(ta->vertices.data(), tc->vertices.data(),
                                 ta->vertices.size() * sizeof(sim::Vertex)),
            true);
}

TEST(RiverReach, TilesCoverTheRangeAndDoNotDependOnIt) {
  const RiverReachOptions o = river_defaults();
  const auto small = build_river_reach(o, Sky::kOvercast, kSeed, 10, 100);    // tile 0
  const auto large = build_river_reach(o, Sky::kOvercast, kSeed, -200, 663);  // tiles -2 .. 5
  EXPECT_TRUE(find_mesh(small, "tile0.plain_east"));
  EXPECT_FALSE(find_mesh(small, "tile1.plain_east"));
  for (int k = -2; k <= 5; ++k)
    EXPECT_TRUE(find_mesh(large, "tile" + std::to_string(k) + ".plain_west")) << k;
  EXPECT_FALSE(find_mesh(large, "tile6.plain_west"));
  for (const auto& m : small.meshes) {
    if (m.name.rfind("tile0.", 0) != 0) continue;
    const auto* other = find_mesh(large, m.name);
    ASSERT_TRUE(other) << m.name;
    ASSERT_EQ(m.vertices.size(), other->vertices.size()) << m.name;
    EXPECT_EQ(0, std::memcmp(m.vertices.data(), other->vertices.data(),
                             m.vertices.size() * sizeof(sim::Vertex)))
        << m.name;
  }
  // The view margin (default 150 m) extends the range on both sides, in whole tiles.
  const auto margin = build_river_reach(RiverReachOptions{}, Sky::kOvercast, kSeed, 10, 100);
  EXPECT_TRUE(find_mesh(margin, "tile-2.plain_east"));
  EXPECT_TRUE(find_mesh(margin, "tile2.plain_east"));
  EXPECT_FALSE(find_mesh(margin, "tile3.plain_east"));
  EXPECT_FALSE(find_mesh(margin, "tile-3.plain_east"));
  // The valley is closed by a wooded bend at both ends of the built tiles.
  for (const char* name : {"river_bend_north", "river_bend_south"}) {
    const auto* bend = find_mesh(large, name);
    ASSERT_TRUE(bend) << name;
    const double x = bend->vertices.front().x;
    EXPECT_NEAR(x, std::string(name) == "river_bend_north" ? 6 * 120.0 : -2 * 120.0, 1e-3);
  }
}

TEST(RiverReach, WaterEdgeAtTheConfiguredBankDistance) {
  for (double bank : {10.0, 15.0, 6.0}) {
    RiverReachOptions o = river_defaults();
    o.bank_distance_m = bank;
    o.river_width_m = 2 * bank;
    const auto g = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
    // Inside |y| < bank nothing stands above the water but the structures
    // that belong there (bridge, piers, quay) and vegetation that leans over it.
    int above = 0, terrain_vertices_at_edge = 0;
    for (const auto& m : g.meshes) {
      const bool may_overhang = name_has(m, "bridge") || name_has(m, "quay") ||
                                name_has(m, "reeds") || name_has(m, "tree_") ||
                                name_has(m, "bushes") || name_has(m, "river_bend") ||
                                name_has(m, "stones") ||  // sunk into the bed at the edge
                                name_has(m, "roots");     // arching out over the toe
      const bool terrain = name_has(m, "bank_") || name_has(m, "plain_");
      for (const auto& v : m.vertices) {
        // Trees may lean over the water, but keep the boats' part of it clear.
        if (name_has(m, "tree_")) {
          EXPECT_GE(std::abs(v.y), bank - std::min(2.0, 0.2 * bank)) << m.name;
        }
        if (std::abs(v.y) < bank - 1e-4 && v.z < -0.01 && !may_overhang) {
          ++above;
          ADD_FAILURE() << m.name << " vertex at y " << v.y << " z " << v.z << " (bank " << bank
                        << ")";
          if (above > 5) return;
        }
        if (terrain && std::abs(std::abs(v.y) - bank) < 1e-4) {
          ++terrain_vertices_at_edge;
          EXPECT_NEAR(v.z, 0.0, 1e-5) << m.name;  // the terrain meets the water exactly at the edge
        }
      }
    }
    EXPECT_GT(terrain_vertices_at_edge, 100);
    // And the bank climbs to the configured height at the configured slope.
    const double run = o.bank_height_m / std::tan(o.bank_slope_deg * std::numbers::pi / 180);
    EXPECT_NEAR(river_terrain_z(o, kSeed, 33.0, bank + run / 2), -o.bank_height_m / 2, 1e-9);
    EXPECT_NEAR(river_terrain_z(o, kSeed, 33.0, -(bank + run)), -o.bank_height_m, 1e-9);
    EXPECT_GT(river_terrain_z(o, kSeed, 33.0, bank - 0.5), 0.0);
  }
}

TEST(RiverReach, TreeHeightsWithinTheConfiguredRange) {
  for (double h : {12.0, 6.0, 20.0}) {
    RiverReachOptions o = river_defaults();
    o.tree_height_m = h;
    const auto L = plan_river_tile(o, kSeed, 0);
    ASSERT_GT(L.trees.size(), 20u);
    double lo = 1e9, hi = 0;
    for (const auto& t : L.trees) {
      lo = std::min(lo, t.height_m);
      hi = std::max(hi, t.height_m);
      // Trunks stand behind the water's edge, about the tree line distance back.
      const double s = std::abs(t.base_W.y()) - o.bank_distance_m;
      EXPECT_GT(s, t.trunk_radius_m);
      EXPECT_LT(s, o.tree_line_distance_m + 6.0 + 2.0 + 1e-9);
    }
    EXPECT_GE(lo, 0.75 * h);
    EXPECT_LE(hi, 1.25 * h);
    EXPECT_LT(lo, 0.85 * h);  // the range is used, not just its middle
    EXPECT_GT(hi, 1.15 * h);
    // The geometry has each tree's apex at its planned height, and nothing higher.
    const auto g = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
    // Each trunk's top at its planned height (leaning trees: within their lean, at most 25 deg,
    // of the base), and nothing higher than the highest top.
    std::vector<const sim::Mesh*> trees;
    for (const auto& m : g.meshes)
      if (m.name.rfind("tile0.tree_", 0) == 0) trees.push_back(&m);
    ASSERT_GE(trees.size(), 4u);
    double highest = 0;
    for (const auto& t : L.trees) {
      const double apex_z = t.base_W.z() - t.height_m;
      highest = std::min(highest, apex_z);
      bool found = false;
      for (const auto* m : trees)
        for (const auto& v : m->vertices)
          found = found || (std::abs(v.z - apex_z) < 1e-3 &&
                            (pos(v) - t.base_W).head<2>().norm() < 0.47 * t.height_m);
      EXPECT_TRUE(found) << "apex of the tree at x " << t.base_W.x();
    }
    for (const auto* m : trees)
      for (const auto& v : m->vertices) ASSERT_GE(v.z, highest - 1e-4) << m->name;
    EXPECT_GT(highest, -(1.25 * h + o.bank_height_m + 2.0));
  }
}

TEST(RiverReach, VegetationDensityZeroIsBare) {
  RiverReachOptions o = river_defaults();
  o.vegetation_density = 0;
  const auto g = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  for (const auto& m : g.meshes) EXPECT_FALSE(name_has(m, "tree_")) << m.name;
  EXPECT_FALSE(find_mesh(g, "tile0.reeds"));
  EXPECT_FALSE(find_mesh(g, "tile0.bushes"));
  o.vegetation_density = 1.0;
  const auto dense = plan_river_tile(o, kSeed, 0);
  o.vegetation_density = 0.3;
  const auto sparse = plan_river_tile(o, kSeed, 0);
  EXPECT_GT(dense.trees.size(), 2 * sparse.trees.size());
}

TEST(RiverReach, BridgeAndQuayFollowTheirOptions) {
  RiverReachOptions o = river_defaults();
  const auto& with = default_reach();
  const auto* bridge = find_mesh(with, "tile0.bridge");
  ASSERT_TRUE(bridge);
  EXPECT_TRUE(find_mesh(with, "tile0.bridge_railings"));
  EXPECT_TRUE(find_mesh(with, "tile0.quay_piling"));
  // The deck spans the river; the piers stand in the water.
  const RiverTileLayout L = plan_river_tile(o, kSeed, 0);
  ASSERT_EQ(L.pier_y_m.size(), 2u);
  for (double yp : L.pier_y_m) EXPECT_LT(std::abs(yp), o.bank_distance_m);
  RayCaster rc(with);
  std::string what;
  // Looking up from the water under the deck: the deck's underside.
  const double up = rc.cast({L.bridge_x_m, 0, -0.5}, {0, 0, -1}, &what);
  EXPECT_EQ(what, "tile0.bridge");
  EXPECT_NEAR(up, -0.5 - L.bridge_deck_bottom_z_m, 1e-3);
  // Looking east from beside a pier at water level: the pier.
  rc.cast({L.bridge_x_m, 0, -0.3}, {0, L.pier_y_m[1] > 0 ? 1.0 : -1.0, 0}, &what);
  EXPECT_EQ(what, "tile0.bridge");
  // Sheet piling faces the river along the quay, at the water's edge.
  const double to_quay = rc.cast({(L.quay_x0_m + L.quay_x1_m) / 2, 0, -0.5}, {0, 1, 0}, &what);
  EXPECT_EQ(what, "tile0.quay_piling");
  EXPECT_GE(to_quay, o.bank_distance_m - 1e-6);
  EXPECT_LE(to_quay, o.bank_distance_m + 0.25);

  o.bridge = false;
  o.quay_wall = false;
  const auto without = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  for (const auto& m : without.meshes) {
    EXPECT_FALSE(name_has(m, "bridge")) << m.name;
    EXPECT_FALSE(name_has(m, "quay")) << m.name;
  }
  // The shipped bollard stands in the scene either way.
  EXPECT_TRUE(find_mesh(with, "tile0.bollards"));
  EXPECT_TRUE(find_mesh(without, "tile0.bollards"));
}

// quay_ladder_spacing_m: ladders on the piling's face every that many metres, the first half a
// spacing from the quay's south end, each two rails 0.45 m apart from 1 m below the water to
// 0.9 m above the capping beam; quay_stain_height_m: the piling from the water up to that height
// a separate, darker mesh. By default a ladder every 15 m and a 0.5 m band; at 0 neither (one
// piling mesh).
TEST(RiverReach, QuayLaddersAndWetBandFollowTheirOptions) {
  EXPECT_TRUE(find_mesh(default_reach(), "tile0.quay_ladders"));
  EXPECT_TRUE(find_mesh(default_reach(), "tile0.quay_piling_wet"));
  RiverReachOptions o = river_defaults();
  EXPECT_EQ(o.quay_ladder_spacing_m, 15);
  EXPECT_EQ(o.quay_stain_height_m, 0.5);
  o.quay_ladder_spacing_m = 0;
  o.quay_stain_height_m = 0;
  const auto bare = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  EXPECT_FALSE(find_mesh(bare, "tile0.quay_ladders"));
  EXPECT_FALSE(find_mesh(bare, "tile0.quay_piling_wet"));
  o.quay_ladder_spacing_m = 10;
  o.quay_stain_height_m = 0.6;
  const auto g = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  const RiverTileLayout L = plan_river_tile(o, kSeed, 0);
  ASSERT_TRUE(L.quay);
  const sim::Mesh* ladders = find_mesh(g, "tile0.quay_ladders");
  const sim::Mesh* wet = find_mesh(g, "tile0.quay_piling_wet");
  const sim::Mesh* dry = find_mesh(g, "tile0.quay_piling");
  ASSERT_TRUE(ladders && wet && dry);
  EXPECT_LT(wet->material.albedo, dry->material.albedo);
  for (const sim::Vertex& v : wet->vertices) {
    EXPECT_GE(v.z, -0.6f - 1e-5f);
    EXPECT_LE(v.z, 1.0f + 1e-5f);
  }
  const double b = o.bank_distance_m, z_cap_top = -(o.bank_height_m + 0.9);
  // Rails and rungs within 3 cm of the plane 0.25 m off the piling, from z 1 up to the handholds.
  float z_min = 1e9f, z_max = -1e9f;
  for (const sim::Vertex& v : ladders->vertices) {
    EXPECT_NEAR(v.y, b - 0.25, 0.026);
    z_min = std::min(z_min, v.z);
    z_max = std::max(z_max, v.z);
  }
  EXPECT_NEAR(z_min, z_cap_top - 0.9, 0.03);
  EXPECT_NEAR(z_max, 1.0, 0.03);
  // 30 m of quay: ladders at 5, 15 and 25 m from its south end, found by rays from mid-river
  // towards the bank 0.225 m either side of each centre, just above the water.
  RayCaster rc(g);
  std::string what;
  for (double along : {5.0, 15.0, 25.0})
    for (double dx : {-0.225, 0.225}) {
      const double d = rc.cast({L.quay_x0_m + along + dx, 0, -0.1}, {0, 1, 0}, &what);
      EXPECT_EQ(what, "tile0.quay_ladders") << along << " " << dx;
      EXPECT_NEAR(d, b - 0.25 - 0.025, 0.01) << along << " " << dx;
    }
  // Between ladders the piling: wet below 0.6 m above the water, dry above it.
  const double between = L.quay_x0_m + 10.05;
  rc.cast({between, 0, -0.3}, {0, 1, 0}, &what);
  EXPECT_EQ(what, "tile0.quay_piling_wet");
  rc.cast({between, 0, -0.9}, {0, 1, 0}, &what);
  EXPECT_EQ(what, "tile0.quay_piling");
}

TEST(RiverReach, BuildingsPerOption) {
  RiverReachOptions o = river_defaults();
  for (int n : {0, 1, 4, 7}) {
    o.buildings = n;
    const auto L = plan_river_tile(o, kSeed, 0);
    EXPECT_EQ(static_cast<int>(L.buildings.size()), n);
    for (const auto& b : L.buildings) {
      EXPECT_GT(std::min(std::abs(b.y0_m), std::abs(b.y1_m)),
                o.bank_distance_m + o.tree_line_distance_m + 5.0);  // behind the tree line
      EXPECT_LT(b.eave_z_m, b.ground_z_m);
      EXPECT_LT(b.ridge_z_m, b.eave_z_m);
    }
  }
}

TEST(RiverReach, TriangleBudgetOfA120mReach) {
  const auto& g = default_reach();
  const std::size_t n = g.triangle_count();
  std::printf(
      "[ river reach ] 120 m reach (one tile, defaults): %zu triangles in %zu meshes, %zu "
      "textures\n",
      n, g.meshes.size(), g.textures.size());
  ::testing::Test::RecordProperty("river_reach_triangles_120m", static_cast<int>(n));
  EXPECT_GT(n, 5000u);
  EXPECT_LE(n, 200000u);
  // The 663 m survey track with the default 150 m view margins stays affordable.
  const auto survey = build_river_reach(RiverReachOptions{}, Sky::kOvercast, kSeed, 0, 663);
  std::printf("[ river reach ] 663 m survey with 150 m view margins: %zu triangles\n",
              survey.triangle_count());
  EXPECT_LE(survey.triangle_count(), 200000u * 9);
}

TEST(RiverReach, FeatureDepthsLikeRiverPaperTable4) {
  // River paper Table 4: section-mean depth of sparse features 4.1 - 39.4 m,
  // mean 21.6, median 20.5. From mid-river, 0.5 m above the water, looking
  // 45 deg off the bank direction (up- and downstream, both banks), the bulk
  // of what the cameras see should lie at those depths.
  const auto g = build_river_reach(river_defaults(), Sky::kOvercast, kSeed, -150, 270);
  const RayCaster rc(g);
  const std::vector<double> headings{45, -45, 135, -135};
  const DepthStats c = feature_depths(rc, {{0, 0, -0.5}, {30, 0, -0.5}}, headings);
  std::printf(
      "[ river reach ] depth from mid-river: p10 %.1f median %.1f mean %.1f p90 %.1f m "
      "(%zu hits, %zu water, %zu sky rays)\n",
      c.p10, c.median, c.mean, c.p90, c.hits, c.water, c.sky);
  ::testing::Test::RecordProperty("depth_mid_river_median_m", std::to_string(c.median));
  ::testing::Test::RecordProperty("depth_mid_river_p10_m", std::to_string(c.p10));
  ::testing::Test::RecordProperty("depth_mid_river_p90_m", std::to_string(c.p90));
  EXPECT_GT(c.hits, 2000u);
  EXPECT_GE(c.median, 10.0);
  EXPECT_LE(c.median, 30.0);
  EXPECT_GE(c.p10, 4.0);
  EXPECT_LE(c.p10, 15.0);
  EXPECT_GE(c.p90, 30.0);
  // 75: rays through the skeleton trees' crowns reach the wood beyond (62 m and more): p90
  // 57.4 m (was 41 under the ellipsoid crowns); the far trees (62-87 m) catch rays that went
  // to the sky before (1,030 sky rays -> 896) and 45 leaf cards a near tree let more through
  // to the wood: p90 68.1 m, the median 22.8 -> 23.9 m.
  EXPECT_LE(c.p90, 75.0);
  // Off-centre (the crossings of the river_crossing scenario run to 3.25 m
  // from the banks) the near end reaches the paper's ~4 m.
  const DepthStats off = feature_depths(rc, {{0, 6, -0.5}, {30, -6, -0.5}}, headings);
  std::printf("[ river reach ] depth 4 m from a bank: p10 %.1f median %.1f mean %.1f p90 %.1f m\n",
              off.p10, off.median, off.mean, off.p90);
  EXPECT_LE(off.p10, 7.0);
  EXPECT_GE(off.median, 10.0);
  EXPECT_LE(off.median, 30.0);
}

TEST(RiverReach, InvalidOptionsAreUserErrors) {
  RiverReachOptions o = river_defaults();
  o.vegetation_density = 2;
  EXPECT_THROW(build_river_reach(o, Sky::kOvercast, kSeed, 0, 10), UserError);
  o = river_defaults();
  o.river_width_m = 30;  // bank_distance_m still 10
  try {
    build_river_reach(o, Sky::kOvercast, kSeed, 0, 10);
    ADD_FAILURE() << "expected a UserError";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("bank_distance_m"), std::string::npos) << e.what();
  }
}

TEST(RiverReach, SkyPicksTheLighting) {
  const auto sun = build_river_reach(river_defaults(), Sky::kSun, kSeed, 0, 10);
  EXPECT_TRUE(sun.lighting.sun);
  EXPECT_LT(sun.lighting.sun_direction_W.z(), 0.f);  // the sun is above the horizon
  EXPECT_NEAR(sun.lighting.sun_direction_W.norm(), 1.f, 1e-6f);
  const auto cloud = build_river_reach(river_defaults(), Sky::kOvercast, kSeed, 0, 10);
  EXPECT_FALSE(cloud.lighting.sun);
  EXPECT_GT(cloud.lighting.ambient, sun.lighting.ambient);
}

// scene.river_reach.visibility_m: the haze's extinction length is the visibility over
// -ln(0.02) = 3.912 (Koschmieder's law: at the visibility 2 % of a contrast is left, as the
// renderer's exp(-d / fog_distance_m) gives); 9 km by default (the river paper's survey day);
// null keeps the sky's own haze.
TEST(RiverReach, VisibilitySetsTheHazeByKoschmiedersLaw) {
  RiverReachOptions o = river_defaults();
  EXPECT_EQ(o.visibility_m, 9000.0);
  o.visibility_m = std::nullopt;
  for (const Sky sky : {Sky::kOvercast, Sky::kSun})
    EXPECT_EQ(build_river_reach(o, sky, kSeed, 0, 10).lighting.fog_distance_m,
              outdoor_lighting(sky).fog_distance_m);
  EXPECT_EQ(outdoor_lighting(Sky::kOvercast).fog_distance_m, 400.f);
  o.visibility_m = 9000;
  const float fog = build_river_reach(o, Sky::kOvercast, kSeed, 0, 10).lighting.fog_distance_m;
  EXPECT_NEAR(fog, 9000 / 3.912, 0.01);
  EXPECT_NEAR(std::exp(-9000 / fog), 0.02, 1e-4);
  o.visibility_m = 5;
  try {
    build_river_reach(o, Sky::kOvercast, kSeed, 0, 10);
    ADD_FAILURE() << "a visibility of 5 m was accepted";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("visibility_m"), std::string::npos) << e.what();
  }
}

// The vegetation's sway weights (sim::Mesh::sway): trees and bushes bend as a cantilever's
// first mode, h^2 of their height, scaled by their height over the reference tree's; leaves
// flutter, wood does not; reeds bend from the foot; the rest of the reach is rigid.
TEST(RiverReach, VegetationSwaysAndTheRestIsRigid) {
  const auto& g = default_reach();
  int swaying = 0;
  for (const sim::Mesh& m : g.meshes) {
    const bool plant = name_has(m, "tree_") || name_has(m, "bushes_") || name_has(m, "reeds");
    if (!plant) {
      EXPECT_TRUE(m.sway.empty()) << m.name;
      continue;
    }
    ASSERT_EQ(m.sway.size(), m.vertices.size()) << m.name;
    ++swaying;
    const bool leaves = name_has(m, "leaves");
    float most = 0;
    for (const auto& w : m.sway) {
      EXPECT_GE(w[0], 0.f) << m.name;
      // The tallest tree's top (leaf cards may reach above it: clamped at 1 of its height).
      EXPECT_LE(
          w[0],
          kTreeHeightMax * river_defaults().tree_height_m / sim::kReferenceTreeHeight_m + 1e-6)
          << m.name;
      if (!name_has(m, "reeds")) {
        EXPECT_EQ(w[1], leaves ? 1.f : 0.f) << m.name;
      }
      most = std::max(most, w[0]);
    }
    EXPECT_GT(most, 0.1f) << m.name;
  }
  EXPECT_GT(swaying, 3);
  // One tree, by hand: its foot does not move, its top by height / 12 m, half-way a quarter.
  sim::Mesh stem;
  for (double z : {0.0, -5.0, -10.0})
    stem.vertices.push_back(sim::Vertex{1, 2, static_cast<float>(z), 0, 0, -1, 0, 0});
  set_plant_sway(&stem, Vec3(1, 2, 0), 10.0, 0.f);
  EXPECT_EQ(stem.sway[0][0], 0.f);
  EXPECT_NEAR(stem.sway[1][0], 0.25 * 10 / 12, 1e-6);
  EXPECT_NEAR(stem.sway[2][0], 10.0 / 12, 1e-6);
}

// reed_model cards: each clump three crossed upright cards in the drawn reed-clump texture
// (alpha), feet in the bank and tops above the water, as many clumps as the blades' within the
// quay's and bridge's gaps (6 triangles a clump against 28; the clumps' places are drawn from
// the same stream, which the blades advance further), bending from the foot as the blades do.
// Cards by default.
TEST(RiverReach, ReedCardsAreThreeCrossedUprightCardsAClump) {
  RiverReachOptions o = river_defaults();
  EXPECT_EQ(o.reed_model, ReedModel::kCards);
  o.reed_model = ReedModel::kBlades;
  const auto blade_scene = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  const sim::Mesh* cards = find_mesh(default_reach(), "tile0.reeds");
  const sim::Mesh* blades = find_mesh(blade_scene, "tile0.reeds");
  const sim::SceneGeometry& g = default_reach();
  ASSERT_TRUE(cards && blades);
  ASSERT_GE(cards->material.texture, 0);
  const sim::Texture& t = g.textures[static_cast<std::size_t>(cards->material.texture)];
  EXPECT_EQ(t.name, "reeds_clump");
  EXPECT_FALSE(t.alpha.empty());
  EXPECT_TRUE(cards->material.double_sided);
  ASSERT_EQ(cards->indices.size() % 18, 0u);
  const double clumps = static_cast<double>(blades->indices.size()) / (3 * 28);
  EXPECT_NEAR(static_cast<double>(cards->indices.size()) / 18, clumps, 0.1 * clumps);
  ASSERT_EQ(cards->sway.size(), cards->vertices.size());
  for (std::size_t i = 0; i < cards->vertices.size(); ++i) {
    const sim::Vertex& v = cards->vertices[i];
    EXPECT_NEAR(v.nz, 0.f, 1e-6);  // upright: the normal is horizontal
    const float h = 1.f - v.v;
    EXPECT_EQ(cards->sway[i][0], h * h);
    if (v.v == 0.f) {
      EXPECT_LT(v.z, -0.99f);  // the top at least 1 m above the water
    }
  }
  // A card's four corners (MeshBuilder::card: v 0, 0, 1, 1): 1-2 m of reed above the water or
  // the bank, its foot 0.2 m into the ground.
  for (std::size_t q = 0; q + 3 < cards->vertices.size(); q += 4) {
    const sim::Vertex &top = cards->vertices[q], &foot = cards->vertices[q + 3];
    ASSERT_EQ(top.v, 0.f);
    ASSERT_EQ(foot.v, 1.f);
    EXPECT_GE(foot.z - top.z, 1.2f - 1e-4f);
    EXPECT_LE(foot.z - top.z, 3.0f);
  }
  // The blades' scene does not carry the clump texture.
  for (const sim::Texture& d : blade_scene.textures) EXPECT_NE(d.name, "reeds_clump");
}

// bank_roots_per_tree: that many tubes of bark in front of each tree within 6 m of the water's
// edge, each from the bank slope (a quarter to 0.9 of its run up) arching at most 15 cm out of
// the ground to the toe just under the water; 4 by default, none at 0.
TEST(RiverReach, BankRootsRunFromTheSlopeIntoTheWater) {
  RiverReachOptions o = river_defaults();
  EXPECT_EQ(o.bank_roots_per_tree, 4);
  o.bank_roots_per_tree = 0;
  EXPECT_FALSE(find_mesh(build_river_reach(o, Sky::kOvercast, kSeed, 0, 120), "tile0.bank_roots"));
  o.bank_roots_per_tree = 4;
  const auto g = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  const sim::Mesh* roots = find_mesh(g, "tile0.bank_roots");
  ASSERT_TRUE(roots);
  const RiverTileLayout L = plan_river_tile(o, kSeed, 0);
  std::size_t near_trees = 0;
  for (const TreeSpec& t : L.trees) near_trees += std::abs(t.base_W.y()) - o.bank_distance_m <= 6.0;
  ASSERT_GT(near_trees, 0u);
  const std::size_t n = near_trees * 4;
  // A tube of 6 points and 5 sides: 5 segments of 10 triangles.
  ASSERT_EQ(roots->indices.size(), n * 5 * 10 * 3);
  ASSERT_EQ(roots->vertices.size() % n, 0u);
  const std::size_t per_root = roots->vertices.size() / n;
  const double b = o.bank_distance_m;
  const double run = o.bank_height_m / std::tan(o.bank_slope_deg * std::numbers::pi / 180.0);
  for (std::size_t r = 0; r < n; ++r) {
    double y_in = 1e9, y_out = 0;
    for (std::size_t i = r * per_root; i < (r + 1) * per_root; ++i) {
      const sim::Vertex& v = roots->vertices[i];
      const double s = std::abs(v.y) - b;
      y_in = std::min(y_in, s);
      y_out = std::max(y_out, s);
      // Never more than the arch and the root's thickness out of the ground.
      EXPECT_GE(v.z, river_terrain_z(o, kSeed, v.x, v.y) - 0.15 - 0.05 - 0.02) << r;
    }
    EXPECT_GE(y_out, 0.25 * run - 0.06) << r;  // from the slope
    EXPECT_LE(y_out, 0.9 * run + 0.06) << r;
    EXPECT_LE(y_in, 0.01) << r;  // into the water
    EXPECT_GE(y_in, -0.2 - 0.03) << r;
  }
}

// bank_undercut_share: stretches of bank where a lip of earth overhangs the water's edge with
// the slope's foot in its shade under it; none by default. Rays from mid-river just above the
// water find the shade where the bank is undercut and the bare slope elsewhere; rays down
// through the water's edge find the lip's top 0.15-0.6 m above the water.
TEST(RiverReach, UndercutBanksOverhangTheWatersEdge) {
  EXPECT_FALSE(find_mesh(default_reach(), "tile0.bank_undercut"));
  RiverReachOptions o = river_defaults();
  EXPECT_EQ(o.bank_undercut_share, 0);
  o.vegetation_density = 0;  // nothing between the rays and the bank
  o.waterline_stones_per_m = 0;
  o.bank_roots_per_tree = 0;
  const double b = o.bank_distance_m;
  auto shaded_share = [&](double share, double* lip_hits) {
    o.bank_undercut_share = share;
    const auto g = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
    const RiverTileLayout L = plan_river_tile(o, kSeed, 0);
    RayCaster rc(g);
    int shaded = 0, bare = 0, lips = 0, downs = 0;
    for (double x = L.x0_m + 0.1; x < L.x1_m; x += 0.5) {
      if (L.bridge && std::abs(x - L.bridge_x_m) < L.bridge_half_width_m + 1.5) continue;
      if (L.quay && x > L.quay_x0_m - 1.5 && x < L.quay_x1_m + 1.5) continue;
      std::string what;
      rc.cast({x, 0, -0.03}, {0, 1, 0}, &what);
      shaded += what == "tile0.bank_undercut_hollow";
      bare += what == "tile0.bank_east";
      const double down = rc.cast({x, b - 0.05, -3.0}, {0, 0, 1}, &what);
      if (what != "tile0.bank_undercut") continue;
      ++downs;
      const double h = 3.0 - down;  // the lip's top above the water
      lips += h >= 0.15 - 1e-6 && h <= 0.6 + 1e-6;
    }
    *lip_hits = downs > 0 ? static_cast<double>(lips) / downs : 0;
    return static_cast<double>(shaded) / std::max(1, shaded + bare);
  };
  double lip_ok = 0;
  const double all = shaded_share(1.0, &lip_ok);
  EXPECT_GT(all, 0.5);  // the stretches' tapered ends leave the rest bare
  EXPECT_EQ(lip_ok, 1.0);
  const double some = shaded_share(0.3, &lip_ok);
  EXPECT_GT(some, 0.05);
  EXPECT_LT(some, all);
  EXPECT_EQ(lip_ok, 1.0);
  // No lip where there is no slope to undercut.
  o.bank_undercut_share = 1;
  o.bank_slope_deg = 90;
  EXPECT_FALSE(
      find_mesh(build_river_reach(o, Sky::kOvercast, kSeed, 0, 120), "tile0.bank_undercut"));
}

// waterline_stones_per_m: that many stones a metre of bank on each side (less the quay's and
// the bridge's gaps), each a faceted lump within 0.43 m of its centre near the water's edge;
// 1.5 by default; none at 0.
TEST(RiverReach, WaterlineStonesLieAtTheWatersEdge) {
  EXPECT_TRUE(find_mesh(default_reach(), "tile0.stones"));
  RiverReachOptions o = river_defaults();
  EXPECT_EQ(o.waterline_stones_per_m, 1.5);
  o.waterline_stones_per_m = 0;
  EXPECT_FALSE(find_mesh(build_river_reach(o, Sky::kOvercast, kSeed, 0, 120), "tile0.stones"));
  o.waterline_stones_per_m = 1.0;
  const auto g = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  const sim::Mesh* stones = find_mesh(g, "tile0.stones");
  ASSERT_TRUE(stones);
  // A lump of 5 sides and 3 bands: 5 triangles at each pole band and 10 in the middle one.
  constexpr std::size_t kTriangles = 20;
  const std::size_t n = stones->indices.size() / (3 * kTriangles);
  ASSERT_EQ(stones->indices.size() % (3 * kTriangles), 0u);
  // Uniform along the tile: the expected count less the quay's (one side) and the bridge's
  // (both sides) gaps, each 1 m wider at both ends; binomial spread.
  const RiverTileLayout L = plan_river_tile(o, kSeed, 0);
  const double len = L.x1_m - L.x0_m, per_side = o.waterline_stones_per_m * o.reach_length_m;
  const double quay = L.quay ? (L.quay_x1_m - L.quay_x0_m + 2) / len : 0;
  const double bridge = L.bridge ? 2 * (L.bridge_half_width_m + 1) / len : 0;
  const double expected = per_side * ((1 - quay - bridge) + (1 - bridge));
  EXPECT_NEAR(static_cast<double>(n), expected, 4 * std::sqrt(expected)) << quay << " " << bridge;
  const double edge = o.river_width_m / 2;
  for (std::size_t t = 0; t < stones->indices.size(); t += 3) {
    const sim::Vertex& a = stones->vertices[stones->indices[t]];
    const sim::Vertex& b = stones->vertices[stones->indices[t + 1]];
    const sim::Vertex& c = stones->vertices[stones->indices[t + 2]];
    // Faceted: the three corners carry the face's normal.
    const Vec3 face = (Vec3(b.x - a.x, b.y - a.y, b.z - a.z))
                          .cross(Vec3(c.x - a.x, c.y - a.y, c.z - a.z))
                          .normalized();
    for (const sim::Vertex* v : {&a, &b, &c}) {
      EXPECT_NEAR(std::abs(Vec3(v->nx, v->ny, v->nz).dot(face)), 1.0, 1e-4);
      // Within the stones' band about the water's edge (s in [-0.5, 0.6] m), and low.
      EXPECT_NEAR(std::abs(v->y), edge + 0.05, 0.55 + 0.43 * 1.25 + 1e-3);
      EXPECT_GT(v->z, -2.0f);
    }
  }
}

// far_trees_per_m: on each side that many trees a metre, each two upright cards at right angles
// (world-fixed crossed billboards) 10-16 m tall and 0.7 of that wide in the billboard texture;
// 0.1 by default; none at 0.
TEST(RiverReach, FarTreesAreCrossedUprightBillboards) {
  EXPECT_TRUE(find_mesh(default_reach(), "tile0.far_trees_east"));
  RiverReachOptions o = river_defaults();
  EXPECT_EQ(o.far_trees_per_m, 0.1);
  o.far_trees_per_m = 0;
  EXPECT_FALSE(
      find_mesh(build_river_reach(o, Sky::kOvercast, kSeed, 0, 120), "tile0.far_trees_east"));
  o.far_trees_per_m = 0.25;
  const auto g = build_river_reach(o, Sky::kOvercast, kSeed, 0, 120);
  for (const char* name : {"tile0.far_trees_east", "tile0.far_trees_west"}) {
    const sim::Mesh* m = find_mesh(g, name);
    ASSERT_TRUE(m) << name;
    EXPECT_EQ(g.textures[static_cast<std::size_t>(m->material.texture)].name, "tree_billboard");
    const std::size_t trees = std::lround(o.far_trees_per_m * o.reach_length_m);
    ASSERT_EQ(m->vertices.size(), 8 * trees) << name;  // two cards of four corners a tree
    for (std::size_t t = 0; t < trees; ++t) {
      const sim::Vertex* v = &m->vertices[8 * t];
      const Vec3 u0(v[1].x - v[0].x, v[1].y - v[0].y, v[1].z - v[0].z);
      const Vec3 u1(v[5].x - v[4].x, v[5].y - v[4].y, v[5].z - v[4].z);
      const double height = v[3].z - v[0].z;  // foot (v = 1) below top (v = 0)
      EXPECT_NEAR(u0.z(), 0.0, 1e-4);         // the cards' u edges are level: upright cards
      EXPECT_NEAR(u0.dot(u1), 0.0, 1e-3 * u0.squaredNorm());  // at right angles
      EXPECT_GE(height, 10.0 - 1e-3);
      EXPECT_LE(height, 16.0 + 1e-3);
      EXPECT_NEAR(u0.norm(), 0.7 * height, 1e-3);
      // Behind the far wood's front (2 m behind the far field's start), within 25 m of it.
      const double y = std::abs(v[0].y + v[1].y + v[2].y + v[3].y) / 4;
      EXPECT_GE(y, o.river_width_m / 2 + kFarFieldStart_m + 2 - 1e-3);
      EXPECT_LE(y, o.river_width_m / 2 + kFarFieldStart_m + 27 + 1e-3);
    }
  }
}

TEST(RiverReach, ExtremeOptionsStillGiveWellFormedScenes) {
  std::vector<RiverReachOptions> cases(6, river_defaults());
  cases[0].bank_slope_deg = 90;  // a vertical bank
  cases[1].bank_height_m = 0;    // no bank at all
  cases[1].tree_line_distance_m = 0;
  cases[2].reach_length_m = 10;  // the shortest tile, crowded
  cases[2].buildings = 100;
  cases[2].vegetation_density = 1;
  cases[3].bank_distance_m = 0.5;  // a ditch
  cases[3].river_width_m = 1.0;
  cases[4].bank_slope_deg = 1;  // a bank that is almost a beach
  cases[4].texture_contrast = 4;
  for (auto& c : cases) c.bank_undercut_share = 1;  // every bank undercut where it can be
  cases[5].bank_distance_m = 60;                    // a wide river
  cases[5].river_width_m = 120;
  cases[5].tree_height_m = 30;
  for (std::size_t i = 0; i < cases.size(); ++i) {
    SCOPED_TRACE("case " + std::to_string(i));
    const auto g = build_river_reach(cases[i], Sky::kOvercast, kSeed, -5, 25);
    expect_well_formed(g);
  }
}

// river_width_m and bank_distance_m are one quantity: a scenario may set either.
TEST(RiverReachOptions, WidthAndBankDistanceFollowEachOther) {
  auto read = [](const std::string& text) {
    SceneOptions s;
    yaml::read_into(yaml::load_string(text, "test.yaml"), {"test.yaml", true}, &s);
    return s.river_reach;
  };
  const RiverReachOptions w = read("river_reach: {river_width_m: 30}\n");
  EXPECT_DOUBLE_EQ(w.bank_distance_m, 15.0);
  const RiverReachOptions b = read("river_reach: {bank_distance_m: 7}\n");
  EXPECT_DOUBLE_EQ(b.river_width_m, 14.0);
  const RiverReachOptions both = read("river_reach: {river_width_m: 24, bank_distance_m: 12}\n");
  EXPECT_DOUBLE_EQ(both.bank_distance_m, 12.0);
  EXPECT_THROW(read("river_reach: {river_width_m: 24, bank_distance_m: 10}\n"), UserError);
  // An override on top of a loaded document moves both.
  SceneOptions s;
  yaml::read_into(yaml::load_string("river_reach: {river_width_m: 20, bank_distance_m: 10}\n", "a"),
                  {"a", true}, &s);
  yaml::read_into(yaml::override_document("river_reach.river_width_m=40"), {"--set", false}, &s);
  EXPECT_DOUBLE_EQ(s.river_reach.bank_distance_m, 20.0);
  EXPECT_EQ(yaml::validate(s), "");
}

}  // namespace
}  // namespace driftlab::scenes
