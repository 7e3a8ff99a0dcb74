#include "scenes/ship_model.hpp"

#include <cmath>
#include <numbers>

#include "scenes/mesh_builder.hpp"

namespace driftlab::scenes {
namespace {

constexpr int kDiscSides = 48;

sim::Material flat(float albedo, std::array<float, 3> colour) {
  sim::Material m;
  m.albedo = albedo;
  m.colour = colour;
  return m;
}

// A disc facing up (-z) at height z, as a fan of triangles.
sim::Mesh disc(const char* name, const sim::Material& material, double x, double y, double z,
               double radius) {
  MeshBuilder b(name, material);
  const Vec3 up(0, 0, -1);
  const std::uint32_t c = b.vertex({x, y, z}, up, 0.5, 0.5);
  std::vector<std::uint32_t> rim;
  for (int i = 0; i < kDiscSides; ++i) {
    const double a = 2 * std::numbers::pi * i / kDiscSides;
    rim.push_back(b.vertex({x + radius * std::cos(a), y + radius * std::sin(a), z}, up,
                           0.5 + 0.5 * std::cos(a), 0.5 + 0.5 * std::sin(a)));
  }
  for (int i = 0; i < kDiscSides; ++i)
    b.triangle(c, rim[static_cast<std::size_t>(i)],
               rim[static_cast<std::size_t>((i + 1) % kDiscSides)], up);
  sim::Mesh m = b.take();
  m.on_body = true;
  return m;
}

}  // namespace

double marker_face_z_B(const sim::HullOptions& hull) { return -(hull.depth_m - hull.kg_m) - 0.001; }

std::vector<sim::Mesh> ship_model_meshes(const sim::HullOptions& hull,
                                         const sim::MarkerOptions& markers) {
  std::vector<sim::Mesh> out;
  // The body origin is the centre of gravity, kg_m above the keel, at mid-length and mid-beam.
  MeshBuilder h("ship_model_hull", flat(0.85f, {1.0f, 1.0f, 1.0f}));
  h.box({-hull.length_m / 2, -hull.beam_m / 2, -(hull.depth_m - hull.kg_m)},
        {hull.length_m / 2, hull.beam_m / 2, hull.kg_m}, 1.0);
  out.push_back(h.take());
  out.back().on_body = true;
  // Matt paints: the red and green that the tracker's thresholds look for.
  const double z = marker_face_z_B(hull), r = markers.diameter_m / 2;
  const double x0 = markers.centre_forward_m, d = markers.separation_m / 2;
  out.push_back(disc("marker_red", flat(1.0f, {0.80f, 0.06f, 0.05f}), x0 + d, 0, z, r));
  out.push_back(disc("marker_green", flat(1.0f, {0.06f, 0.55f, 0.12f}), x0 - d, 0, z, r));
  return out;
}

}  // namespace driftlab::scenes
