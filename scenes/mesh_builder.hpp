// Helpers that append textured primitives (quads, boxes, prisms) to a
// sim::Mesh in the world NED frame. Winding convention for every triangle the
// scenes emit: (b - a) x (c - a) points to the front, the side the vertex
// normals point to (counter-clockwise seen from the front, right-handed NED).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes {

using Vec3 = Eigen::Vector3d;

/// A material of texture `texture` (-1: none), `albedo` and sun-glint `specular`, seen from
/// both sides.
inline sim::Material material(int texture, float albedo, float specular = 0.0f) {
  sim::Material m;
  m.texture = texture;
  m.albedo = albedo;
  m.specular = specular;
  return m;
}

class MeshBuilder {
 public:
  MeshBuilder(std::string name, sim::Material material);

  /// Appends a vertex (normal normalised here); returns its index.
  std::uint32_t vertex(const Vec3& p, const Vec3& n, double u, double v);
  /// Appends triangle (a, b, c), reordered if needed so that it faces `front`.
  void triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vec3& front);

  /// Planar quad with corners p0 p1 p2 p3 in order around its edge, flat
  /// normal towards `front`, texture coordinates given per corner. Two-sided
  /// quads (reeds, thin plates seen from both sides) get a back copy.
  void quad(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, const Vec3& front,
            const Eigen::Vector2d& t0, const Eigen::Vector2d& t1, const Eigen::Vector2d& t2,
            const Eigen::Vector2d& t3, bool two_sided = false);
  /// Quad textured in metres: u along p0 -> p1, v along p0 -> p3, one repeat
  /// every repeat_u_m / repeat_v_m.
  void quad_m(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3, const Vec3& front,
              double repeat_u_m, double repeat_v_m, bool two_sided = false);

  /// Faces of an axis-aligned box, as bits.
  enum Face : unsigned {
    kNorth = 1,    // +x
    kSouth = 2,    // -x
    kEast = 4,     // +y
    kWest = 8,     // -y
    kBottom = 16,  // +z (down)
    kTop = 32,     // -z (up)
    kAllFaces = 63,
    kNoBottom = 47,
  };
  /// Axis-aligned box [lo, hi] (NED: lo.z is the top). Texture projected from
  /// world coordinates (one repeat per repeat_m), so adjacent boxes line up.
  void box(const Vec3& lo, const Vec3& hi, double repeat_m, unsigned faces = kAllFaces);

  /// Prism with a polygonal cross-section of `sides` around the segment a -> b
  /// (radius [m]), smooth radial normals, no caps. u wraps around the prism
  /// (one repeat per repeat_m of circumference, rounded to whole repeats so the
  /// texture seam is invisible), v runs along it.
  void prism(const Vec3& a, const Vec3& b, double radius, int sides, double repeat_m);

  /// Tube along the polyline `points` (>= 2) with one radius per point [m]: a ring of `sides`
  /// vertices at every point, oriented by parallel-transport (rotation-minimising) frames (the
  /// double reflection method of Wang et al. 2008) so the tube does not twist, smooth radial
  /// normals, no caps. When the last radius is 0 (or tiny) the tube ends in a point (a cone fan).
  /// u wraps around (whole repeats of repeat_m of circumference at the first ring, at least 1), v
  /// runs along it in metres / repeat_m. Triangles: sides x 2 per segment, sides on a tip segment.
  void tube(const std::vector<Vec3>& points, const std::vector<double>& radii, int sides,
            double repeat_m);

  /// One quad with corners centre -/+ axis_u -/+ axis_v, uv over [0, 1]^2 (u along axis_u, v
  /// along axis_v), all four normals normal_hint (normalised), two triangles wound to face
  /// normal_hint; no back copy (for double-sided materials such as leaf cards).
  void card(const Vec3& centre, const Vec3& axis_u, const Vec3& axis_v, const Vec3& normal_hint);

  std::size_t vertex_count() const { return mesh_.vertices.size(); }
  std::size_t triangle_count() const { return mesh_.indices.size() / 3; }
  /// Position of vertex i.
  Vec3 position(std::uint32_t i) const;
  /// Replaces the normal of vertex i (normalised here).
  void set_normal(std::uint32_t i, const Vec3& n);

  /// The mesh built so far (the builder is empty afterwards).
  sim::Mesh take();

 private:
  sim::Mesh mesh_;
};

/// Appends `src` to `dst` (vertices, triangles, sway weights: a mesh without them is rigid),
/// translated by `offset`.
void append_mesh(sim::Mesh* dst, const sim::Mesh& src, const Vec3& offset);

/// Adds a mesh to the scene unless it is empty.
void add_mesh(sim::SceneGeometry* scene, sim::Mesh mesh);

}  // namespace driftlab::scenes
