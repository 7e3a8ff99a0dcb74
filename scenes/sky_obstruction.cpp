#include "scenes/sky_obstruction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/error.hpp"

namespace driftlab::scenes {

MeshSkyObstruction::MeshSkyObstruction(const sim::SceneGeometry& scene, double cell_m)
    : cell_(cell_m) {
  if (!(cell_m > 0.0 && std::isfinite(cell_m)))
    throw UserError("MeshSkyObstruction: cell_m: got " + std::to_string(cell_m) + ", expected > 0");
  double n_min = std::numeric_limits<double>::infinity(), n_max = -n_min;
  double e_min = n_min, e_max = -n_min;
  top_z_ = std::numeric_limits<double>::infinity();
  for (const sim::Mesh& m : scene.meshes) {
    if (m.mover >= 0) continue;  // a vessel passing by: not a fixed obstruction of the sky
    auto at = [&m](std::uint32_t i) {
      const sim::Vertex& v = m.vertices[i];
      return Vec3(v.x, v.y, v.z);
    };
    for (std::size_t k = 0; k + 2 < m.indices.size(); k += 3) {
      const sim::Triangle t{at(m.indices[k]), at(m.indices[k + 1]), at(m.indices[k + 2])};
      if (!t.a.allFinite() || !t.b.allFinite() || !t.c.allFinite())
        throw UserError("MeshSkyObstruction: mesh '" + m.name + "' has a non-finite vertex");
      for (const Vec3* p : {&t.a, &t.b, &t.c}) {
        n_min = std::min(n_min, p->x());
        n_max = std::max(n_max, p->x());
        e_min = std::min(e_min, p->y());
        e_max = std::max(e_max, p->y());
        top_z_ = std::min(top_z_, p->z());
      }
      triangles_.push_back(t);
    }
  }
  if (triangles_.empty()) return;
  n0_ = n_min;
  e0_ = e_min;
  nx_ = std::max(1, static_cast<int>(std::ceil((n_max - n_min) / cell_)) + 1);
  ny_ = std::max(1, static_cast<int>(std::ceil((e_max - e_min) / cell_)) + 1);
  // Counting sort of the triangles into every cell their horizontal bounding box touches.
  const auto cells = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  cell_begin_.assign(cells + 1, 0);
  auto range = [this](const sim::Triangle& t, int* i0, int* i1, int* j0, int* j1) {
    const double a = std::min({t.a.x(), t.b.x(), t.c.x()}),
                 b = std::max({t.a.x(), t.b.x(), t.c.x()});
    const double c = std::min({t.a.y(), t.b.y(), t.c.y()}),
                 d = std::max({t.a.y(), t.b.y(), t.c.y()});
    *i0 = std::clamp(static_cast<int>((a - n0_) / cell_), 0, nx_ - 1);
    *i1 = std::clamp(static_cast<int>((b - n0_) / cell_), 0, nx_ - 1);
    *j0 = std::clamp(static_cast<int>((c - e0_) / cell_), 0, ny_ - 1);
    *j1 = std::clamp(static_cast<int>((d - e0_) / cell_), 0, ny_ - 1);
  };
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::uint32_t> fill;
    if (pass == 1) {
      for (std::size_t c = 0; c < cells; ++c) cell_begin_[c + 1] += cell_begin_[c];
      cell_items_.resize(cell_begin_[cells]);
      fill.assign(cell_begin_.begin(), cell_begin_.end() - 1);
    }
    for (std::size_t k = 0; k < triangles_.size(); ++k) {
      int i0, i1, j0, j1;
      range(triangles_[k], &i0, &i1, &j0, &j1);
      for (int i = i0; i <= i1; ++i)
        for (int j = j0; j <= j1; ++j) {
          const auto c = static_cast<std::size_t>(i) * static_cast<std::size_t>(ny_) +
                         static_cast<std::size_t>(j);
          if (pass == 0)
            ++cell_begin_[c + 1];
          else
            cell_items_[fill[c]++] = static_cast<std::uint32_t>(k);
        }
    }
  }
}

bool MeshSkyObstruction::blocked(const Vec3& from_W, const Vec3& direction_W) const {
  if (triangles_.empty()) return false;
  // Only the part of the ray below the scene's highest point can hit anything.
  double t_end = 0.0;
  if (direction_W.z() < 0.0) {
    if (from_W.z() <= top_z_) return false;  // already above everything
    t_end = (from_W.z() - top_z_) / -direction_W.z();
  } else {
    t_end = 1e5;  // horizontal or downwards: bounded by the grid below
  }
  // Walk the cells under the segment [0, t_end] of the ray (Amanatides & Woo).
  const double px = (from_W.x() - n0_) / cell_, py = (from_W.y() - e0_) / cell_;
  const double dx = direction_W.x() / cell_, dy = direction_W.y() / cell_;
  int i = static_cast<int>(std::floor(px)), j = static_cast<int>(std::floor(py));
  const int step_i = dx > 0 ? 1 : -1, step_j = dy > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  double t_next_i = dx != 0.0 ? ((dx > 0 ? i + 1 : i) - px) / dx : inf;
  double t_next_j = dy != 0.0 ? ((dy > 0 ? j + 1 : j) - py) / dy : inf;
  const double t_di = dx != 0.0 ? std::abs(1.0 / dx) : inf;
  const double t_dj = dy != 0.0 ? std::abs(1.0 / dy) : inf;
  double t = 0.0;
  while (t <= t_end) {
    const bool inside = i >= 0 && i < nx_ && j >= 0 && j < ny_;
    if (inside) {
      const auto c =
          static_cast<std::size_t>(i) * static_cast<std::size_t>(ny_) + static_cast<std::size_t>(j);
      for (std::uint32_t k = cell_begin_[c]; k < cell_begin_[c + 1]; ++k) {
        const auto hit =
            sim::ray_triangle_distance(from_W, direction_W, triangles_[cell_items_[k]]);
        if (hit && *hit > 1e-6) return true;
      }
    } else if ((i < 0 && step_i < 0) || (i >= nx_ && step_i > 0) || (j < 0 && step_j < 0) ||
               (j >= ny_ && step_j > 0) || (i < 0 && dx == 0.0) || (i >= nx_ && dx == 0.0) ||
               (j < 0 && dy == 0.0) || (j >= ny_ && dy == 0.0)) {
      return false;  // leaving the grid for good
    }
    if (t_next_i < t_next_j) {
      t = t_next_i;
      t_next_i += t_di;
      i += step_i;
    } else {
      t = t_next_j;
      t_next_j += t_dj;
      j += step_j;
    }
  }
  return false;
}

std::vector<sim::MagneticAnomalyOptions> steel_anomalies(const sim::SceneGeometry& scene,
                                                         const std::array<double, 3>& field_ned_nt,
                                                         double decay_length_m,
                                                         double decay_exponent,
                                                         const std::vector<std::string>& suffixes) {
  std::vector<sim::MagneticAnomalyOptions> out;
  for (const sim::Mesh& m : scene.meshes) {
    const bool steel = std::any_of(suffixes.begin(), suffixes.end(), [&m](const std::string& s) {
      return m.name.size() >= s.size() &&
             m.name.compare(m.name.size() - s.size(), s.size(), s) == 0;
    });
    if (!steel || m.vertices.empty() || m.mover >= 0) continue;
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const sim::Vertex& v : m.vertices) {
      const Vec3 p(v.x, v.y, v.z);
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    const Vec3 mid = 0.5 * (lo + hi);
    sim::MagneticAnomalyOptions a;
    a.name = m.name;
    if (hi.x() - lo.x() >= hi.y() - lo.y()) {
      a.from_ned_m = {lo.x(), mid.y(), mid.z()};
      a.to_ned_m = {hi.x(), mid.y(), mid.z()};
    } else {
      a.from_ned_m = {mid.x(), lo.y(), mid.z()};
      a.to_ned_m = {mid.x(), hi.y(), mid.z()};
    }
    a.field_ned_nt = field_ned_nt;
    a.decay_length_m = decay_length_m;
    a.decay_exponent = decay_exponent;
    out.push_back(a);
  }
  return out;
}

}  // namespace driftlab::scenes
