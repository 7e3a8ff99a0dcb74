// Textured discs that the renderer's tests draw (render_test.cpp, render_backends_test.cpp).
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>

#include "sim/render/renderer.hpp"
#include "tests/sim/render_fixtures.hpp"

namespace driftlab::sim::fixtures {

// A disc of `radius` facing north (towards a camera south of it), centred at c.
inline Mesh disc(const Vec3& c, double radius, int segments = 64) {
  Mesh m;
  m.name = "marker";
  m.material.albedo = 1.0f;
  auto vert = [&](double e, double d) {
    return Vertex{static_cast<float>(c.x()),
                  static_cast<float>(c.y() + e),
                  static_cast<float>(c.z() + d),
                  -1.f,
                  0.f,
                  0.f,
                  0.f,
                  0.f};
  };
  m.vertices.push_back(vert(0, 0));
  for (int i = 0; i < segments; ++i) {
    const double a = 2 * std::numbers::pi * i / segments;
    m.vertices.push_back(vert(radius * std::cos(a), radius * std::sin(a)));
  }
  for (int i = 0; i < segments; ++i) {
    m.indices.push_back(0);
    m.indices.push_back(1 + i);
    m.indices.push_back(1 + (i + 1) % segments);
  }
  return m;
}

// A disc with an 8 x 8 checkerboard of grey levels `dark` and `bright` over
// water, lit by the default (overcast) light.
inline SceneGeometry checker_disc_over_water(const Vec3& centre, double radius, std::uint8_t dark,
                                             std::uint8_t bright) {
  SceneGeometry s = dark_scene();
  s.lighting = Lighting{};
  s.water.enabled = true;
  Texture t;
  t.name = "checker";
  t.width = t.height = 64;
  for (int y = 0; y < 64; ++y)
    for (int x = 0; x < 64; ++x) t.pixels.push_back(((x / 8 + y / 8) % 2) ? bright : dark);
  s.textures.push_back(t);
  Mesh m = disc(centre, radius);
  m.material.texture = 0;
  for (auto& v : m.vertices) {
    v.u = v.y;
    v.v = v.z;
  }
  s.meshes.push_back(m);
  return s;
}

}  // namespace driftlab::sim::fixtures
