// The river reach's parts (scenes/river_reach.hpp), shared by its three files:
// river_reach.cpp (the bank's cross-section, the terrain, the textures and the tile's
// assembly), river_structures.cpp (bridge, quay, buildings, far field) and
// river_vegetation.cpp (trees, bushes, reeds, stones, roots, undercut banks). Not for use
// outside scenes.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <numbers>
#include <string>
#include <tuple>

#include <fmt/format.h>
#include <Eigen/Geometry>

#include "core/error.hpp"
#include "core/rng.hpp"
#include "scenes/assets.hpp"
#include "scenes/mesh_builder.hpp"
#include "scenes/noise.hpp"
#include "scenes/photographs.hpp"
#include "scenes/river_reach.hpp"
#include "scenes/sky_clouds.hpp"
#include "scenes/textures.hpp"
#include "scenes/trees.hpp"
#include "scenes/vessels.hpp"

namespace driftlab::scenes::river {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kToeDepth_m = 0.8;    // the bank slope continues this far under water
inline constexpr double kPlainGrade = 0.01;   // rise of the plain behind the bank top
inline constexpr double kRowSpacing_m = 1.5;  // terrain grid spacing along the river
inline constexpr double kTreeSpacingAtFull_m = 4.0;  // tree spacing per row at vegetation_density 1
inline constexpr double kTreeRowGap_m = 6.0;         // second tree row behind the tree line
inline constexpr double kCrownAxisFrac = 0.38;       // crown's vertical semi-axis / tree height
inline constexpr double kFarFieldWoodTop_m = 95.0;   // the far wood's canopy reaches back to here
inline constexpr double kBridgeClearance_m = 3.5;    // deck underside above the bank top
inline constexpr double kDeckDepth_m = 0.9;
inline constexpr double kBridgeLandSpan_m = 12.0;  // abutment length behind the water's edge
inline constexpr double kRampGrade = 0.15;
inline constexpr double kQuayLength_m = 30.0;
inline constexpr int kReedBlades = 14;        // blades per reed clump
inline constexpr double kQuayPaving_m = 8.0;  // depth of the paved quay behind the wall
inline constexpr double kLeafGreyContrast =
    0.3;  // relative spread of the leaves' grey in a cluster

// Cross-section of one bank, from the options.
struct Bank {
  double b = 0;  // water's edge |y| [m]
  double H = 0;  // bank top above the water [m]
  double tan_slope = 0;
  double run = 0;    // horizontal extent of the slope [m]
  double toe_s = 0;  // s (distance beyond the water's edge) of the underwater toe, < 0
};

struct Textures {
  int grass, soil, bark, foliage, reeds, concrete, sheet, facade, roof, brick, stone;
  int leaves_broad, leaves_narrow;  // leaf-cluster cards (alpha), at the foliage's mean grey
  int reed_clump = -1;              // reed_model cards (alpha), at the reeds' mean grey
  int tree_billboard = -1;          // far_trees_per_m (alpha), at the foliage's mean grey
};

// What a lumpy ellipsoid looks like: its grid (sides around, bands pole to pole), the range of
// the random scale of its vertices off the poles, and one texture repeat every repeat_m.
struct Lumps {
  int sides = 9, bands = 6;
  double lo = 0.85, hi = 1.15;
  double repeat_m = 3.0;
};

// river_reach.cpp
Bank bank_of(const RiverReachOptions& o);
Noise terrain_noise(std::uint64_t seed);
double terrain_z(const Bank& k, const Noise& n, double x, double s, int side);
double far_top_z(const Bank& k, const Noise& n, double x, double s, int side);
std::string tile_name(int index, const char* what);
sim::Material solid(int texture, float albedo);
Textures add_textures(sim::SceneGeometry* g, std::uint64_t seed, const RiverReachOptions& o);

// river_vegetation.cpp
void add_lumpy_ellipsoid(MeshBuilder* mb, const Vec3& c, double r, double a, const Lumps& form,
                         Rng* lumps);
void add_crown(MeshBuilder* mb, const TreeSpec& t, double a_frac, Rng* lumps);
void choose_form(TreeSpec* t, const RngStreams& streams, const RiverTileLayout& L, int side,
                 int row, int i);
std::vector<TreeSpec> plan_trees(const RiverReachOptions& o, const Bank& k, const Noise& n,
                                 const RiverTileLayout& L, std::uint64_t seed, Rng* rng);
void add_reeds(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
               const Textures& tex, const RiverReachOptions& options, std::uint64_t seed,
               int index);
void add_waterline_stones(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k,
                          const Noise& n, const Textures& tex, const RiverReachOptions& options,
                          std::uint64_t seed, int index);
void add_bank_roots(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                    const Textures& tex, const RiverReachOptions& options, std::uint64_t seed);
std::vector<std::pair<double, double>> plan_undercuts(const RiverTileLayout& L, double share,
                                                      int side, Rng* rng);
void add_undercut(MeshBuilder* lip, MeshBuilder* hollow, const Bank& k, double x0, double x1,
                  int side, Rng* rng);
void add_bank_undercuts(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k,
                        const Textures& tex, const RiverReachOptions& options, std::uint64_t seed);
std::vector<TreeSpec> plan_bushes(const RiverReachOptions& o, const Bank& k, const Noise& n,
                                  const RiverTileLayout& L, Rng* rng);
void add_ellipsoid_trees(sim::SceneGeometry* g, const RiverTileLayout& L, const Textures& tex,
                         Rng* lumps);
bool clear_of_the_water(const sim::Mesh& m, const Bank& k);
std::pair<sim::Mesh, sim::Mesh> grow_and_dress(const TreeSpec& t, const Bank& k,
                                               const Textures& tex, int cards);
TreeSpec scrub(const TreeSpec& bush, std::uint64_t seed, int tile, std::size_t i);
void add_skeleton_trees(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k,
                        const Textures& tex, const RiverReachOptions& o, std::uint64_t seed);

// river_structures.cpp
void add_bridge(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                const Textures& tex);
void add_quay_ladders(sim::SceneGeometry* g, const RiverTileLayout& L, double b, double z_cap_top,
                      const std::vector<double>& xs);
void add_quay(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Textures& tex,
              const RiverReachOptions& o);
void add_buildings(sim::SceneGeometry* g, const RiverTileLayout& L, const Textures& tex);
void add_far_field(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                   const Textures& tex, int side);
void add_far_trees(sim::SceneGeometry* g, const RiverTileLayout& L, const Bank& k, const Noise& n,
                   const Textures& tex, const RiverReachOptions& options, std::uint64_t seed,
                   int side);
void add_river_bend(sim::SceneGeometry* g, double x_end, int facing, const Bank& k, const Noise& n,
                    const Textures& tex);
bool inside(const BuildingSpec& b, double x, double y, double margin);
bool inside_any(const std::vector<BuildingSpec>& buildings, double x, double y, double margin);
RiverTileLayout plan_structures(const RiverReachOptions& o, const Bank& k, int index);
std::vector<Eigen::Vector3d> plan_bollards(const RiverTileLayout& L, const Bank& k, const Noise& n);
std::vector<BuildingSpec> plan_buildings(const RiverReachOptions& o, const Bank& k, const Noise& n,
                                         const RiverTileLayout& L, Rng* rng);

}  // namespace driftlab::scenes::river
