// The mesh sky obstruction against the brute-force PrimitiveObstruction (every triangle
// tested) on the real river scene, and the steel anomalies against the meshes they follow.
#include "scenes/sky_obstruction.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "scenes/build_scene.hpp"

namespace driftlab::scenes {
namespace {

TEST(MeshSkyObstruction, AgreesWithBruteForceOnTheRiverScene) {
  SceneOptions options;
  const sim::SceneGeometry scene = build_scene(options, 7, -30.0, 30.0);
  const MeshSkyObstruction grid(scene);
  sim::PrimitiveObstruction brute;
  for (const sim::Mesh& m : scene.meshes)
    for (std::size_t k = 0; k + 2 < m.indices.size(); k += 3) {
      auto at = [&m](std::uint32_t i) {
        return Vec3(m.vertices[i].x, m.vertices[i].y, m.vertices[i].z);
      };
      brute.add_triangle(at(m.indices[k]), at(m.indices[k + 1]), at(m.indices[k + 2]));
    }
  ASSERT_EQ(grid.triangle_count(), brute.triangles().size());
  Rng rng(3);
  int blocked = 0;
  const int n = 300;
  for (int i = 0; i < n; ++i) {
    // Antennas over the river and the banks, 1 m above still water; skyward rays above 5 deg.
    const Vec3 from(rng.uniform(-25.0, 25.0), rng.uniform(-15.0, 15.0), -1.0);
    const double az = rng.uniform(0.0, 2 * M_PI), el = rng.uniform(0.09, 1.5);
    const Vec3 d(std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), -std::sin(el));
    const bool expected = brute.blocked(from, d);
    EXPECT_EQ(grid.blocked(from, d), expected) << "ray " << i;
    blocked += expected ? 1 : 0;
  }
  // The test means something only if both outcomes occur often.
  EXPECT_GT(blocked, n / 10);
  EXPECT_LT(blocked, n - n / 10);
}

TEST(MeshSkyObstruction, EmptySceneAndBadCell) {
  const sim::SceneGeometry empty;
  EXPECT_FALSE(MeshSkyObstruction(empty).blocked(Vec3::Zero(), Vec3(0, 0, -1)));
  EXPECT_THROW(MeshSkyObstruction(empty, 0.0), UserError);
}

TEST(SteelAnomalies, FollowTheLongSideOfEachSteelMesh) {
  sim::SceneGeometry scene;
  sim::Mesh quay;
  quay.name = "tile0.quay_piling";
  for (const Vec3& p : {Vec3(10, 8, -2), Vec3(40, 9, 1), Vec3(25, 8.5, 0)})
    quay.vertices.push_back({float(p.x()), float(p.y()), float(p.z()), 0, 0, -1, 0, 0});
  sim::Mesh trees = quay;
  trees.name = "tile0.tree_crowns";
  sim::Mesh bridge = quay;
  bridge.name = "tile1.bridge";
  bridge.vertices.clear();
  for (const Vec3& p : {Vec3(100, -20, -6), Vec3(104, 20, -4)})
    bridge.vertices.push_back({float(p.x()), float(p.y()), float(p.z()), 0, 0, -1, 0, 0});
  scene.meshes = {quay, trees, bridge};
  const auto a = steel_anomalies(scene, {1000, 0, 0}, 2.0, 3.0);
  ASSERT_EQ(a.size(), 2u);
  EXPECT_EQ(a[0].name, "tile0.quay_piling");
  EXPECT_DOUBLE_EQ(a[0].from_ned_m[0], 10.0);
  EXPECT_DOUBLE_EQ(a[0].to_ned_m[0], 40.0);
  EXPECT_DOUBLE_EQ(a[0].from_ned_m[1], 8.5);
  EXPECT_DOUBLE_EQ(a[0].from_ned_m[2], -0.5);
  EXPECT_EQ(a[1].name, "tile1.bridge");  // spans east: the segment runs east-west
  EXPECT_DOUBLE_EQ(a[1].from_ned_m[0], 102.0);
  EXPECT_DOUBLE_EQ(a[1].from_ned_m[1], -20.0);
  EXPECT_DOUBLE_EQ(a[1].to_ned_m[1], 20.0);
  EXPECT_DOUBLE_EQ(a[1].decay_length_m, 2.0);
  EXPECT_DOUBLE_EQ(a[1].field_ned_nt[0], 1000.0);
}

}  // namespace
}  // namespace driftlab::scenes
