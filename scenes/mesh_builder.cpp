#include "scenes/mesh_builder.hpp"

#include <cmath>
#include <numbers>

#include <Eigen/Geometry>

#include "core/error.hpp"

namespace driftlab::scenes {

MeshBuilder::MeshBuilder(std::string name, sim::Material material) {
  mesh_.name = std::move(name);
  mesh_.material = material;
}

std::uint32_t MeshBuilder::vertex(const Vec3& p, const Vec3& n, double u, double v) {
  const double len = n.norm();
  DRIFTLAB_DEMAND_MSG(len > 0 && std::isfinite(len), "vertex normal must be non-zero");
  DRIFTLAB_DEMAND_MSG(p.allFinite(), "vertex position must be finite");
  const Vec3 un = n / len;
  mesh_.vertices.push_back({static_cast<float>(p.x()), static_cast<float>(p.y()),
                            static_cast<float>(p.z()), static_cast<float>(un.x()),
                            static_cast<float>(un.y()), static_cast<float>(un.z()),
                            static_cast<float>(u), static_cast<float>(v)});
  return static_cast<std::uint32_t>(mesh_.vertices.size() - 1);
}

Vec3 MeshBuilder::position(std::uint32_t i) const {
  const auto& v = mesh_.vertices[i];
  return {v.x, v.y, v.z};
}

void MeshBuilder::set_normal(std::uint32_t i, const Vec3& n) {
  const Vec3 un = n.normalized();
  auto& v = mesh_.vertices[i];
  v.nx = static_cast<float>(un.x());
  v.ny = static_cast<float>(un.y());
  v.nz = static_cast<float>(un.z());
}

void MeshBuilder::triangle(std::uint32_t a, std::uint32_t b, std::uint32_t c, const Vec3& front) {
  const Vec3 pa = position(a), pb = position(b), pc = position(c);
  if ((pb - pa).cross(pc - pa).dot(front) < 0) std::swap(b, c);
  mesh_.indices.insert(mesh_.indices.end(), {a, b, c});
}

void MeshBuilder::quad(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                       const Vec3& front, const Eigen::Vector2d& t0, const Eigen::Vector2d& t1,
                       const Eigen::Vector2d& t2, const Eigen::Vector2d& t3, bool two_sided) {
  // The flat normal comes from the geometry (oriented by `front`), so a quad
  // given a rough hint still shades correctly.
  Vec3 n = (p2 - p0).cross(p3 - p1);
  if (n.squaredNorm() == 0) return;  // degenerate: nothing to draw
  if (n.dot(front) < 0) n = -n;
  for (int side = 0; side < (two_sided ? 2 : 1); ++side) {
    const Vec3 ns = side == 0 ? n : Vec3(-n);
    const std::uint32_t a = vertex(p0, ns, t0.x(), t0.y());
    const std::uint32_t b = vertex(p1, ns, t1.x(), t1.y());
    const std::uint32_t c = vertex(p2, ns, t2.x(), t2.y());
    const std::uint32_t d = vertex(p3, ns, t3.x(), t3.y());
    triangle(a, b, c, ns);
    triangle(a, c, d, ns);
  }
}

void MeshBuilder::quad_m(const Vec3& p0, const Vec3& p1, const Vec3& p2, const Vec3& p3,
                         const Vec3& front, double repeat_u_m, double repeat_v_m, bool two_sided) {
  const double lu = (p1 - p0).norm() / repeat_u_m, lv = (p3 - p0).norm() / repeat_v_m;
  const double lu2 = (p2 - p3).norm() / repeat_u_m;
  quad(p0, p1, p2, p3, front, {0, 0}, {lu, 0}, {lu2, lv}, {0, lv}, two_sided);
}

void MeshBuilder::box(const Vec3& lo, const Vec3& hi, double repeat_m, unsigned faces) {
  const double r = repeat_m;
  auto p = [&](int ix, int iy, int iz) {
    return Vec3(ix ? hi.x() : lo.x(), iy ? hi.y() : lo.y(), iz ? hi.z() : lo.z());
  };
  // Texture: vertical faces use (horizontal coordinate, z); v grows downwards
  // in the world, so the texture's top row is up. Horizontal faces use (x, y).
  auto vert = [&](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& n,
                  bool along_x) {
    auto uv = [&](const Vec3& q) {
      return Eigen::Vector2d((along_x ? q.x() : q.y()) / r, q.z() / r);
    };
    quad(a, b, c, d, n, uv(a), uv(b), uv(c), uv(d));
  };
  auto horiz = [&](const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d, const Vec3& n) {
    auto uv = [&](const Vec3& q) { return Eigen::Vector2d(q.y() / r, q.x() / r); };
    quad(a, b, c, d, n, uv(a), uv(b), uv(c), uv(d));
  };
  if (faces & kNorth) vert(p(1, 0, 0), p(1, 1, 0), p(1, 1, 1), p(1, 0, 1), Vec3::UnitX(), false);
  if (faces & kSouth) vert(p(0, 0, 0), p(0, 1, 0), p(0, 1, 1), p(0, 0, 1), -Vec3::UnitX(), false);
  if (faces & kEast) vert(p(0, 1, 0), p(1, 1, 0), p(1, 1, 1), p(0, 1, 1), Vec3::UnitY(), true);
  if (faces & kWest) vert(p(0, 0, 0), p(1, 0, 0), p(1, 0, 1), p(0, 0, 1), -Vec3::UnitY(), true);
  if (faces & kBottom) horiz(p(0, 0, 1), p(1, 0, 1), p(1, 1, 1), p(0, 1, 1), Vec3::UnitZ());
  if (faces & kTop) horiz(p(0, 0, 0), p(1, 0, 0), p(1, 1, 0), p(0, 1, 0), -Vec3::UnitZ());
}

void MeshBuilder::prism(const Vec3& a, const Vec3& b, double radius, int sides, double repeat_m) {
  const Vec3 axis = b - a;
  const double len = axis.norm();
  if (len == 0 || radius <= 0) return;
  const Vec3 w = axis / len;
  // Any unit vector perpendicular to the axis starts the cross-section.
  const Vec3 e1 =
      (std::abs(w.z()) < 0.9 ? w.cross(Vec3::UnitZ()) : w.cross(Vec3::UnitX())).normalized();
  const Vec3 e2 = w.cross(e1);
  const double repeats = std::max(1.0, std::round(2 * std::numbers::pi * radius / repeat_m));
  std::vector<std::uint32_t> ring_a, ring_b;
  for (int i = 0; i <= sides; ++i) {  // i == sides duplicates i == 0 with u = repeats
    const double ang = 2 * std::numbers::pi * (i % sides) / sides;
    const Vec3 n = std::cos(ang) * e1 + std::sin(ang) * e2;
    const double u = repeats * i / sides;
    ring_a.push_back(vertex(a + radius * n, n, u, 0));
    ring_b.push_back(vertex(b + radius * n, n, u, len / repeat_m));
  }
  for (int i = 0; i < sides; ++i) {
    const double mid = 2 * std::numbers::pi * (i + 0.5) / sides;
    const Vec3 out = std::cos(mid) * e1 + std::sin(mid) * e2;
    triangle(ring_a[i], ring_a[i + 1], ring_b[i + 1], out);
    triangle(ring_a[i], ring_b[i + 1], ring_b[i], out);
  }
}

sim::Mesh MeshBuilder::take() {
  sim::Mesh out = std::move(mesh_);
  mesh_ = sim::Mesh{};
  mesh_.name = out.name;
  mesh_.material = out.material;
  return out;
}

void append_mesh(sim::Mesh* dst, const sim::Mesh& src, const Vec3& offset) {
  const auto base = static_cast<std::uint32_t>(dst->vertices.size());
  for (sim::Vertex v : src.vertices) {
    v.x = static_cast<float>(v.x + offset.x());
    v.y = static_cast<float>(v.y + offset.y());
    v.z = static_cast<float>(v.z + offset.z());
    dst->vertices.push_back(v);
  }
  for (std::uint32_t i : src.indices) dst->indices.push_back(base + i);
  sim::append_sway(dst, base, src);
}

void add_mesh(sim::SceneGeometry* scene, sim::Mesh mesh) {
  if (!mesh.indices.empty()) scene->meshes.push_back(std::move(mesh));
}

}  // namespace driftlab::scenes

namespace driftlab::scenes {

namespace {

// A unit vector perpendicular to the unit vector w.
Vec3 any_perpendicular(const Vec3& w) {
  return (std::abs(w.z()) < 0.9 ? w.cross(Vec3::UnitZ()) : w.cross(Vec3::UnitX())).normalized();
}

// Unit tangents at the polyline's points: the mean of the adjacent segments' directions
// (one-sided at the ends); a zero-length segment takes its neighbour's direction.
std::vector<Vec3> polyline_tangents(const std::vector<Vec3>& p) {
  const std::size_t n = p.size();
  std::vector<Vec3> seg(n - 1);
  Vec3 last = Vec3::Zero();
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const Vec3 d = p[i + 1] - p[i];
    seg[i] = d.norm() > 1e-12 ? Vec3(d.normalized()) : last;
    if (seg[i].squaredNorm() > 0) last = seg[i];
  }
  for (std::size_t i = n - 1; i-- > 0;)  // leading zero segments take the next direction
    if (seg[i].squaredNorm() == 0) seg[i] = i + 1 < n - 1 ? seg[i + 1] : Vec3(-Vec3::UnitZ());
  std::vector<Vec3> t(n);
  for (std::size_t i = 0; i < n; ++i) {
    const Vec3 a = seg[i == 0 ? 0 : i - 1], b = seg[i + 1 == n ? n - 2 : i];
    const Vec3 m = a + b;
    t[i] = m.norm() > 1e-9 ? Vec3(m.normalized()) : b;
  }
  return t;
}

}  // namespace

void MeshBuilder::tube(const std::vector<Vec3>& points, const std::vector<double>& radii, int sides,
                       double repeat_m) {
  DRIFTLAB_DEMAND_MSG(points.size() >= 2 && radii.size() == points.size() && sides >= 3,
                      "tube needs >= 2 points, one radius per point and >= 3 sides");
  const std::size_t n = points.size();
  const std::vector<Vec3> t = polyline_tangents(points);
  // Frames by double reflection (Wang, Juettler, Zheng and Liu 2008, "Computation of rotation
  // minimizing frames", algorithm 1): e1 is carried from ring to ring without twisting.
  std::vector<Vec3> e1(n);
  e1[0] = any_perpendicular(t[0]);
  for (std::size_t i = 0; i + 1 < n; ++i) {
    const Vec3 v1 = points[i + 1] - points[i];
    const double c1 = v1.squaredNorm();
    Vec3 r = e1[i], tl = t[i];
    if (c1 > 1e-24) {
      r -= (2 / c1) * v1.dot(r) * v1;
      tl -= (2 / c1) * v1.dot(tl) * v1;
    }
    const Vec3 v2 = t[i + 1] - tl;
    const double c2 = v2.squaredNorm();
    if (c2 > 1e-24) r -= (2 / c2) * v2.dot(r) * v2;
    r -= r.dot(t[i + 1]) * t[i + 1];  // remove rounding drift
    e1[i + 1] = r.norm() > 1e-9 ? Vec3(r.normalized()) : any_perpendicular(t[i + 1]);
  }
  const double r_max = *std::max_element(radii.begin(), radii.end());
  const bool tip = radii.back() <= 1e-6 * r_max || radii.back() < 1e-9;
  const double repeats = std::max(1.0, std::round(2 * std::numbers::pi * radii[0] / repeat_m));
  auto radial = [&](std::size_t i, double ang) {
    return Vec3(std::cos(ang) * e1[i] + std::sin(ang) * t[i].cross(e1[i]));
  };
  const std::size_t rings = tip ? n - 1 : n;
  std::vector<std::vector<std::uint32_t>> ring(rings);
  double along_m = 0;
  for (std::size_t i = 0; i < rings; ++i) {
    if (i > 0) along_m += (points[i] - points[i - 1]).norm();
    for (int k = 0; k <= sides; ++k) {  // k == sides duplicates k == 0 with u = repeats
      const Vec3 nr = radial(i, 2 * std::numbers::pi * (k % sides) / sides);
      ring[i].push_back(
          vertex(points[i] + radii[i] * nr, nr, repeats * k / sides, along_m / repeat_m));
    }
  }
  for (std::size_t i = 0; i + 1 < rings; ++i) {
    for (int k = 0; k < sides; ++k) {
      const Vec3 out = radial(i, 2 * std::numbers::pi * (k + 0.5) / sides);
      triangle(ring[i][k], ring[i][k + 1], ring[i + 1][k + 1], out);
      triangle(ring[i][k], ring[i + 1][k + 1], ring[i + 1][k], out);
    }
  }
  if (!tip) return;
  // Cone fan to the point: one apex vertex per side, its normal the side's mid radial.
  const std::size_t last = rings - 1;
  const double v_tip = (along_m + (points[n - 1] - points[n - 2]).norm()) / repeat_m;
  for (int k = 0; k < sides; ++k) {
    const Vec3 out = radial(last, 2 * std::numbers::pi * (k + 0.5) / sides);
    const std::uint32_t apex = vertex(points[n - 1], out, repeats * (k + 0.5) / sides, v_tip);
    triangle(ring[last][k], ring[last][k + 1], apex, out);
  }
}

void MeshBuilder::card(const Vec3& centre, const Vec3& axis_u, const Vec3& axis_v,
                       const Vec3& normal_hint) {
  if (axis_u.cross(axis_v).squaredNorm() == 0) return;  // degenerate: nothing to draw
  const std::uint32_t a = vertex(centre - axis_u - axis_v, normal_hint, 0, 0);
  const std::uint32_t b = vertex(centre + axis_u - axis_v, normal_hint, 1, 0);
  const std::uint32_t c = vertex(centre + axis_u + axis_v, normal_hint, 1, 1);
  const std::uint32_t d = vertex(centre - axis_u + axis_v, normal_hint, 0, 1);
  triangle(a, b, c, normal_hint);
  triangle(a, c, d, normal_hint);
}

}  // namespace driftlab::scenes
