// Trees with limbs, twigs and leaf cards: a simplified Weber & Penn (1995) generator ("Creation
// and rendering of realistic trees", SIGGRAPH 95) with three levels (trunk, limbs, twigs), the
// bark as tubes and the foliage as alpha-tested leaf-cluster cards (scenes/leaf_textures.hpp).
// World frame NED: z points down, a tree's top has z = base.z - height.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "core/rng.hpp"
#include "scenes/leaf_textures.hpp"
#include "scenes/mesh_builder.hpp"

namespace driftlab::scenes {

enum class TreeSpecies { kAlder, kWillow, kWeepingWillow, kPoplar };

/// One tree to grow.
struct TreeForm {
  Vec3 base_W;          // trunk foot on the ground (NED) [m]
  double height_m = 0;  // the top lies exactly height_m above the base: top_W.z = base_W.z - h
  double crown_radius_m = 0;  // horizontal spread of the crown (radius) to aim for [m]
  double trunk_radius_m = 0;  // at the foot [m]
  TreeSpecies species = TreeSpecies::kAlder;
  int lod = 0;                      // 0 near, 1 mid
  Vec3 lean_dir_W = Vec3::UnitX();  // horizontal unit vector the trunk leans toward
  double lean_rad = 0;              // trunk lean from vertical [rad]
};

/// One stem: a polyline with a radius per point (non-increasing, 0 at the tip).
struct Stem {
  std::vector<Vec3> points;
  std::vector<double> radii;
  int level = 0;        // 0 trunk, 1 limb, 2 twig
  int parent = -1;      // index of the parent stem (-1: the trunk)
  double fork_t = 0;    // where it leaves the parent: fraction of the parent's polyline (by point
                        // index, so point i of n is at t = i / (n - 1))
  double length_m = 0;  // the stem's length as grown (before clamping under the top)
};

struct TreeSkeleton {
  std::vector<Stem> stems;  // stems[0] the trunk, then the limbs, then the twigs
  Vec3 top_W;               // the trunk's top (the highest point of the tree)
  double spread_m = 0;      // max horizontal distance of any stem point from the trunk axis
  double length_scale = 1;  // factor applied to every limb's W&P length to reach the spread
};

/// Species parameters (Weber & Penn's names; angles in degrees). Starting values in the spirit of
/// the paper's tables; see trees.cpp.
struct SpeciesParams {
  const char* name;
  int shape;                // Weber & Penn's shape index (shape_ratio)
  double base_size;         // share of the trunk without limbs
  int n1[2];                // number of limbs, near / mid LOD
  double n_length1;         // limb length / trunk length (times ShapeRatio)
  double length_v1;         // relative spread of the limb length (U(1 +- V))
  double down1, down_v1;    // limb angle from the trunk
  double rotate, rotate_v;  // azimuth step between successive limbs
  double curve1, curve_v1;  // total bend along a limb (+ up, - down)
  double attraction_up;     // bend towards up (+) or down (-) per segment
  int n2;                   // twigs per limb at most (near LOD only)
  double n_length2;         // twig length / (limb length - 0.6 x offset)
  double length_v2;
  double down2, down_v2;  // twig angle from its limb
  double curve2;          // twig bend (weeping: hanging twigs)
  LeafShape leaf;
  double card_edge_over_height;  // leaf-card edge / tree height
};
const SpeciesParams& species_params(TreeSpecies species);
LeafShape leaf_shape_of(TreeSpecies species);

/// Weber & Penn's ShapeRatio(shape, r): 0 conical 0.2 + 0.8r, 1 spherical 0.2 + 0.8 sin(pi r),
/// 2 hemispherical 0.2 + 0.8 sin(pi r / 2), 3 cylindrical 1, 4 tapered cylindrical 0.5 + 0.5r,
/// 5 flame r / 0.7 (r <= 0.7) else (1 - r) / 0.3, 6 inverse conical 1 - 0.8r, 7 tend flame
/// 0.5 + 0.5 r / 0.7 (r <= 0.7) else 0.5 + 0.5 (1 - r) / 0.3. r: the fork's distance from the
/// trunk's top over the crown's length.
double shape_ratio(int shape, double r);

/// Number of limbs of `species` at `lod`, and of twigs on a limb whose length is `length_ratio`
/// of the tree's longest limb: round(n2 (0.2 + 0.8 length_ratio)) (Weber & Penn's count for
/// level 2); 0 at lod 1.
int limb_count(TreeSpecies species, int lod);
int twig_count(TreeSpecies species, int lod, double length_ratio);

/// Grows the skeleton: the trunk straight from base_W to top_W (lod 0: 5 segments, lod 1: 3);
/// limbs (lod 0: 3 segments, lod 1: 2) forking above base_size x L0 with length
/// ShapeRatio x n_length1 x L0 x U(1 +- length_v1) x length_scale, where L0 = h / cos(lean) and
/// length_scale makes the spread equal crown_radius_m; twigs (lod 0 only, one segment). No stem
/// point lies above top_W. Draws from `rng` in a fixed order.
TreeSkeleton grow_tree(const TreeForm& f, Rng* rng);

/// The number of leaf cards dress_tree gives a tree at `lod` for `cards` per near tree.
inline int card_count(int cards, int lod) { return lod == 0 ? cards : cards / 2; }

/// Triangles dress_tree adds for a skeleton: wood (trunk 6 sides x 5 segments = 54 at lod 0,
/// 5 x 3 = 25 at lod 1; limbs 4 x 3 = 20 / 3 x 2 = 9; twigs none: the card texture draws them) plus
/// 2 per card.
int tree_triangle_count(const TreeSkeleton& s, int lod, int cards);

/// Bark tubes (one repeat of the bark texture per 1.5 m of circumference) into `wood`; leaf cards
/// into `leaves`: card_count(cards, lod) cards, about 10 % around the leader's top and the rest
/// split over the limbs by length (largest remainders), each on a twig or limb end at t in
/// [0.3, 1] with a radial jitter up to half a card, edge card_edge_over_height x h x
/// U(0.85, 1.15) (x sqrt 2 at lod 1), facing normalize(r + 0.6 N(0, 1)) with r radial from the
/// crown's centre, rolled at random (willows: the texture's v axis within 20 deg of down). All four
/// normals of a card are normalize(r + 0.5 f), f the face normal turned towards r. Cards are stored
/// outermost first; none rises above top_W.
void dress_tree(const TreeForm& f, const TreeSkeleton& s, int cards, Rng* rng, MeshBuilder* wood,
                MeshBuilder* leaves);

/// The sway weights of a plant's mesh (sim::Mesh::sway): the first bending mode of a cantilever,
/// psi(h) = h^2 with h the vertex's height over the plant's (0 at the foot, 1 at the top), scaled
/// by height_m / sim::kReferenceTreeHeight_m (a taller tree's top moves further); `flutter` for
/// each vertex (1: leaf cards).
void set_plant_sway(sim::Mesh* mesh, const Vec3& base_W, double height_m, float flutter);

}  // namespace driftlab::scenes
