#include "sim/sensors/sky.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace driftlab::sim {
namespace {

// Hits closer than this are taken as the ray's own origin grazing a surface it
// starts on (an antenna exactly on a bank top), not as an obstruction.
constexpr double kMinHitDistance_m = 1e-9;

std::string vec_text(const Vec3& v) { return fmt::format("({}, {}, {})", v.x(), v.y(), v.z()); }

}  // namespace

std::optional<double> ray_box_distance(const Vec3& o, const Vec3& d, const AxisAlignedBox& box) {
  double t_near = -std::numeric_limits<double>::infinity();
  double t_far = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    if (d[i] == 0.0) {
      // Parallel to this pair of faces: inside the slab or never.
      if (o[i] < box.min_W[i] || o[i] > box.max_W[i]) return std::nullopt;
      continue;
    }
    double t0 = (box.min_W[i] - o[i]) / d[i];
    double t1 = (box.max_W[i] - o[i]) / d[i];
    if (t0 > t1) std::swap(t0, t1);
    t_near = std::max(t_near, t0);
    t_far = std::min(t_far, t1);
    if (t_near > t_far) return std::nullopt;
  }
  if (t_far < kMinHitDistance_m) return std::nullopt;  // behind the origin
  return std::max(t_near, 0.0);
}

std::optional<double> ray_triangle_distance(const Vec3& o, const Vec3& d, const Triangle& tri) {
  const Vec3 e1 = tri.b - tri.a, e2 = tri.c - tri.a;
  const Vec3 p = d.cross(e2);
  const double det = e1.dot(p);
  // Relative threshold: the ray is parallel to the plane (or the triangle degenerate).
  if (std::abs(det) <= 1e-12 * e1.norm() * e2.norm()) return std::nullopt;
  const double inv = 1.0 / det;
  const Vec3 s = o - tri.a;
  const double u = s.dot(p) * inv;
  if (u < 0.0 || u > 1.0) return std::nullopt;
  const Vec3 q = s.cross(e1);
  const double v = d.dot(q) * inv;
  if (v < 0.0 || u + v > 1.0) return std::nullopt;
  const double t = e2.dot(q) * inv;
  if (t < kMinHitDistance_m) return std::nullopt;
  return t;
}

void PrimitiveObstruction::add_box(const Vec3& min_W, const Vec3& max_W) {
  if (!min_W.allFinite() || !max_W.allFinite() || (min_W.array() > max_W.array()).any())
    throw UserError(
        fmt::format("sky obstruction box: got min {} and max {}, expected finite "
                    "corners with min <= max on every axis",
                    vec_text(min_W), vec_text(max_W)));
  boxes_.push_back({min_W, max_W});
}

void PrimitiveObstruction::add_triangle(const Vec3& a, const Vec3& b, const Vec3& c) {
  if (!a.allFinite() || !b.allFinite() || !c.allFinite())
    throw UserError(
        fmt::format("sky obstruction triangle: got {}, {}, {}, expected finite vertices",
                    vec_text(a), vec_text(b), vec_text(c)));
  triangles_.push_back({a, b, c});
}

bool PrimitiveObstruction::blocked(const Vec3& from_W, const Vec3& direction_W) const {
  for (const auto& box : boxes_)
    if (ray_box_distance(from_W, direction_W, box)) return true;
  for (const auto& tri : triangles_)
    if (ray_triangle_distance(from_W, direction_W, tri)) return true;
  return false;
}

}  // namespace driftlab::sim
