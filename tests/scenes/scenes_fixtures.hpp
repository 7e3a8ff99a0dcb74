// Helpers the scene tests share (scenes_test.cpp, river_reach_test.cpp): a well-formed scene's
// checks, lookups of meshes by name, a brute-force ray caster and the default river reach.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "scenes/river_reach.hpp"
#include "scenes/scene_options.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes::fixtures {

using Vec3 = Eigen::Vector3d;
inline constexpr std::uint64_t kSeed = 2013;

inline Vec3 pos(const sim::Vertex& v) { return {v.x, v.y, v.z}; }

inline bool name_has(const sim::Mesh& m, const std::string& part) {
  return m.name.find(part) != std::string::npos;
}

inline const sim::Mesh* find_mesh(const sim::SceneGeometry& g, const std::string& name) {
  for (const auto& m : g.meshes)
    if (m.name == name) return &m;
  return nullptr;
}

// Every vertex finite with a unit normal, every index in range, every
// triangle non-degenerate and wound counter-clockwise seen from the side its
// vertex normals point to (the winding convention of scenes/mesh_builder.hpp).
inline void expect_well_formed(const sim::SceneGeometry& g) {
  for (const auto& m : g.meshes) {
    SCOPED_TRACE(m.name);
    ASSERT_FALSE(m.indices.empty());
    ASSERT_EQ(m.indices.size() % 3, 0u);
    EXPECT_GE(m.material.texture, -1);
    EXPECT_LT(m.material.texture, static_cast<int>(g.textures.size()));
    EXPECT_GE(m.material.albedo, 0.f);
    EXPECT_LE(m.material.albedo, 1.f);
    int bad_normal = 0, nan = 0, bad_index = 0, degenerate = 0, wrong_winding = 0;
    for (const auto& v : m.vertices) {
      const float vals[8] = {v.x, v.y, v.z, v.nx, v.ny, v.nz, v.u, v.v};
      for (float f : vals) nan += std::isfinite(f) ? 0 : 1;
      const double len = std::sqrt(double(v.nx) * v.nx + double(v.ny) * v.ny + double(v.nz) * v.nz);
      bad_normal += std::abs(len - 1.0) < 1e-4 ? 0 : 1;
    }
    for (auto i : m.indices) bad_index += i < m.vertices.size() ? 0 : 1;
    ASSERT_EQ(bad_index, 0);
    for (std::size_t i = 0; i < m.indices.size(); i += 3) {
      const auto& a = m.vertices[m.indices[i]];
      const auto& b = m.vertices[m.indices[i + 1]];
      const auto& c = m.vertices[m.indices[i + 2]];
      const Vec3 face = (pos(b) - pos(a)).cross(pos(c) - pos(a));
      if (face.norm() < 1e-9) {
        ++degenerate;
        continue;
      }
      const Vec3 n = Vec3(a.nx, a.ny, a.nz) + Vec3(b.nx, b.ny, b.nz) + Vec3(c.nx, c.ny, c.nz);
      wrong_winding += face.dot(n) > 0 ? 0 : 1;
    }
    EXPECT_EQ(nan, 0);
    EXPECT_EQ(bad_normal, 0);
    EXPECT_EQ(degenerate, 0);
    EXPECT_EQ(wrong_winding, 0);
  }
  for (const auto& t : g.textures) {
    EXPECT_GT(t.width, 0);
    EXPECT_EQ(t.pixels.size(), static_cast<std::size_t>(t.width) * t.height) << t.name;
  }
}

// Brute-force ray casting against every triangle, with a bounding box per mesh.
class RayCaster {
 public:
  explicit RayCaster(const sim::SceneGeometry& g) {
    for (const auto& m : g.meshes) {
      Part p;
      p.name = m.name;
      for (auto i : m.indices) {
        p.p.push_back(pos(m.vertices[i]));
        p.box.extend(p.p.back());
      }
      parts_.push_back(std::move(p));
    }
  }
  // Distance along unit direction d to the first surface, or +inf; the hit
  // mesh's name in *what.
  double cast(const Vec3& o, const Vec3& d, std::string* what = nullptr) const {
    double best = std::numeric_limits<double>::infinity();
    const Vec3 inv(1 / d.x(), 1 / d.y(), 1 / d.z());
    for (const auto& part : parts_) {
      double t0 = 0, t1 = best;
      for (int a = 0; a < 3; ++a) {
        double ta = (part.box.min()[a] - o[a]) * inv[a], tb = (part.box.max()[a] - o[a]) * inv[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
      }
      if (t0 > t1) continue;
      for (std::size_t k = 0; k < part.p.size(); k += 3) {  // Moeller-Trumbore
        const Vec3 e1 = part.p[k + 1] - part.p[k], e2 = part.p[k + 2] - part.p[k];
        const Vec3 q = d.cross(e2);
        const double det = e1.dot(q);
        if (std::abs(det) < 1e-12) continue;
        const Vec3 s = o - part.p[k];
        const double u = s.dot(q) / det;
        if (u < 0 || u > 1) continue;
        const Vec3 r = s.cross(e1);
        const double v = d.dot(r) / det;
        if (v < 0 || u + v > 1) continue;
        const double t = e2.dot(r) / det;
        if (t > 1e-6 && t < best) {
          best = t;
          if (what) *what = part.name;
        }
      }
    }
    return best;
  }

 private:
  struct Part {
    std::string name;
    std::vector<Vec3> p;
    Eigen::AlignedBox3d box;
  };
  std::vector<Part> parts_;
};

// Defaults, but without the view margin, so that a range inside [0, 120) is one tile.
inline RiverReachOptions river_defaults() {
  RiverReachOptions o;
  o.view_margin_m = 0;
  return o;
}

// The default 120 m reach (tile 0), built once for the tests that only read it.
inline const sim::SceneGeometry& default_reach() {
  static const sim::SceneGeometry g =
      build_river_reach(river_defaults(), Sky::kOvercast, kSeed, 0, 120);
  return g;
}

}  // namespace driftlab::scenes::fixtures
