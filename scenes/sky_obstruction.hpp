// What the scene's meshes mean for the other sensors: the sky the GPS antenna sees (a
// SkyObstruction ray-cast against every mesh) and the magnetic disturbances of its steel
// structures (the river paper names steel sheet piling as a source of compass bias).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "sim/render/scene_geometry.hpp"
#include "sim/sensors/sensor_options.hpp"
#include "sim/sensors/sky.hpp"

namespace driftlab::scenes {

/// Every triangle of a scene as a sky obstruction, found through a uniform grid over north and
/// east: a ray towards a satellite only visits the cells under it until it climbs above the
/// highest vertex of the scene (a 3D digital differential analyser, Amanatides & Woo 1987, in
/// the horizontal plane), so a query costs tens of triangle tests, not the scene's ~60 000.
class MeshSkyObstruction final : public sim::SkyObstruction {
 public:
  /// `cell_m`: grid cell side [m] (> 0). Throws UserError for a non-finite vertex.
  explicit MeshSkyObstruction(const sim::SceneGeometry& scene, double cell_m = 2.0);

  bool blocked(const Vec3& from_W, const Vec3& direction_W) const override;

  std::size_t triangle_count() const { return triangles_.size(); }

 private:
  std::vector<sim::Triangle> triangles_;
  double cell_ = 2.0;
  double n0_ = 0.0, e0_ = 0.0;             // grid origin (north, east) [m]
  int nx_ = 0, ny_ = 0;                    // cells along north, east
  double top_z_ = 0.0;                     // smallest z (highest point) of the scene, NED [m]
  std::vector<std::uint32_t> cell_begin_;  // CSR: triangles of cell (i, j) at i * ny_ + j
  std::vector<std::uint32_t> cell_items_;
};

/// Magnetic anomalies for the scene's steel structures: one segment along the longer
/// horizontal side of the bounding box of each mesh whose name ends in one of `suffixes`
/// (".quay_piling", ".bridge" by default), at mid-height, with the perturbation `field_ned_nt`,
/// decaying as MagneticAnomalyOptions describes. Meshes are taken in scene order: the result is
/// deterministic.
std::vector<sim::MagneticAnomalyOptions> steel_anomalies(
    const sim::SceneGeometry& scene, const std::array<double, 3>& field_ned_nt,
    double decay_length_m, double decay_exponent,
    const std::vector<std::string>& suffixes = {".quay_piling", ".bridge"});

}  // namespace driftlab::scenes
