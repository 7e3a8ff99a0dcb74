// The river reach of the river paper (Kriechbaumer et al. 2015, Section 2.1):
// a straight river running north-south along x, banks of heightfield terrain,
// reeds, a tree line, a road bridge with piers, a sheet-piled quay wall,
// buildings and far-field woods and hills, in tiles of reach_length_m laid end
// to end so a survey track of any length (663 m in the paper) is covered.
//
// Frame: world NED, still water at z = 0 (above the water z < 0). The water
// lies between y = -bank_distance_m and +bank_distance_m; the renderer draws
// the water surface itself, the scene only what stands in and around it.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "scenes/scene_options.hpp"
#include "scenes/trees.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes {

/// Tree heights are drawn uniformly in [kTreeHeightMin, kTreeHeightMax] x tree_height_m.
constexpr double kTreeHeightMin = 0.75;
constexpr double kTreeHeightMax = 1.25;
/// Distance beyond the water's edge [m] at which the near terrain ends and the
/// far-field wood begins; hills rise behind it out to kFarFieldEnd_m.
constexpr double kFarFieldStart_m = 60.0;
constexpr double kFarFieldEnd_m = 150.0;

/// One tree: base on the ground (NED), height above the base, crown radius; for skeleton trees
/// (scenes/trees.hpp) its species, level of detail, the lean asked for (build_river_reach takes
/// less where the tree would come nearer the boats' water than the bank allows) and the seed of
/// its form.
struct TreeSpec {
  Eigen::Vector3d base_W;
  double height_m = 0;
  double crown_radius_m = 0;
  double trunk_radius_m = 0;
  TreeSpecies species = TreeSpecies::kAlder;
  int lod = 0;  // 0 near (twigs, all cards), 1 mid
  Eigen::Vector3d lean_dir_W = Eigen::Vector3d::UnitX();
  double lean_rad = 0;
  std::uint64_t form_seed = 0;
};

/// A building: footprint [x0, x1] x [y0, y1], ground (lowest wall foot) and eave heights (NED z).
struct BuildingSpec {
  double x0_m = 0, x1_m = 0, y0_m = 0, y1_m = 0;
  double ground_z_m = 0;
  double eave_z_m = 0;
  double ridge_z_m = 0;
};

/// What one reach tile holds (positions in the world frame). The pipeline can
/// use it for occlusion of the GPS sky view, the tests for expectations.
struct RiverTileLayout {
  int index = 0;  // tile k covers x in [k L, (k + 1) L)
  double x0_m = 0, x1_m = 0;
  std::vector<TreeSpec> trees;
  std::vector<TreeSpec> bushes;  // crown only (no trunk), resting on the ground
  bool bridge = false;
  double bridge_x_m = 0;           // deck centre line (north)
  double bridge_half_width_m = 0;  // half the deck width along x
  double bridge_deck_bottom_z_m = 0;
  std::vector<double> pier_y_m;  // pier centre lines (east)
  bool quay = false;
  double quay_x0_m = 0, quay_x1_m = 0;  // on the east bank (y = +bank_distance_m)
  std::vector<BuildingSpec> buildings;
  std::vector<Eigen::Vector3d> bollards_W;  // base of each bollard (shipped asset)
};

/// The layout of tile `index` (deterministic in seed and index; independent
/// of which other tiles are built).
RiverTileLayout plan_river_tile(const RiverReachOptions& options, std::uint64_t seed, int index);

/// Height of the bank terrain (NED z, negative above the water) at (x, y):
/// below the water for |y| < bank_distance_m, the bank slope up to
/// bank_height_m, then a gently rising, undulating plain.
double river_terrain_z(const RiverReachOptions& options, std::uint64_t seed, double x_m,
                       double y_m);

/// Daylight of the river scene: overcast (diffuse sky, no sun) or sun.
sim::Lighting outdoor_lighting(Sky sky);

/// -ln(0.02): the visibility V at which a dark object's contrast has fallen to 2 %
/// (Koschmieder's law), so the extinction length is V / 3.912.
inline constexpr double kKoschmiederContrast = 3.912;

/// Builds the tiles covering [north_min_m - view_margin_m, north_max_m +
/// view_margin_m] (north_min_m <= north_max_m: the cameras' north range; at
/// least one tile), closed at both ends by a wooded river bend across the
/// valley. Meshes are per tile ("tile<k>.<part>"), so a renderer can cull them
/// by their bounds. Throws UserError if the options are invalid.
sim::SceneGeometry build_river_reach(const RiverReachOptions& options, Sky sky, std::uint64_t seed,
                                     double north_min_m, double north_max_m);

}  // namespace driftlab::scenes
