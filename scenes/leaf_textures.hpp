// Procedural leaf-cluster textures with alpha for the trees' leaf cards (docs: trees design,
// section 2): a dark twig with side twigs carrying leaves of the species' shape, drawn until a
// chosen share of the texels is opaque. Unlike make_texture's kinds these do not wrap; they
// carry alpha (sim::Texture::alpha) and a transparent border.
#pragma once

#include "core/rng.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes {

enum class LeafShape {
  kBroad,   // ovate leaves (alder, poplar)
  kNarrow,  // lanceolate leaves (willows)
};

/// The share of opaque texels (alpha >= sim::kAlphaOpaqueFrom) a cluster of `shape` is drawn to:
/// broad 0.60, narrow 0.50. make_leaf_cluster ends within [target, target + 0.03].
double leaf_target_coverage(LeafShape shape);

/// A square leaf-cluster card texture with alpha: a dark twig (2-3 px) with 4-7 side twigs
/// carrying leaves (broad: ovate 18-24 x 14-18 px; narrow: lanceolate 26-36 x 4-6 px, at 256 px),
/// each leaf's grey varied and its midrib darker, leaves added until the opaque share reaches
/// leaf_target_coverage(shape). Alpha is 255 x the share of 4 x 4 subsamples inside; a 2 px
/// border is fully transparent; transparent texels take the grey of the nearest opaque texel
/// (breadth-first from the opaque texels in raster order, 8 neighbours), so filtering never
/// pulls in black. Deterministic in `rng` (which it advances).
///   mean_grey: the mean grey of the opaque texels (0-255; exact to rounding unless clamped);
///   contrast:  relative spread (sd) of the per-leaf grey, like texture_contrast (~0.25-0.5);
///   size_px:   edge length, 64 .. 4096 (leaf sizes scale with size_px / 256).
/// Named "leaves_broad" or "leaves_narrow".
sim::Texture make_leaf_cluster(LeafShape shape, Rng* rng, double mean_grey, double contrast,
                               int size_px = 256);

/// The share of opaque texels a reed clump is drawn to: 0.30 (make_reed_clump ends within
/// [target, target + 0.03]).
double reed_target_coverage();

/// A square reed-clump card texture with alpha, for reed_model: cards: blades from a narrow foot
/// at the bottom edge (the middle 40 %), fanning out up to 28 deg from the vertical, 45-95 % of
/// the texture tall and 5-9 px wide at the foot (at 256 px), tapering to a point, each blade's
/// grey varied and its midrib darker, added until reed_target_coverage(). Alpha, border and
/// dilation as make_leaf_cluster's. Deterministic in `rng`. Named "reeds_clump".
sim::Texture make_reed_clump(Rng* rng, double mean_grey, double contrast, int size_px = 256);

/// The share of opaque texels a far tree's billboard is drawn to: 0.35.
double billboard_target_coverage();

/// A square far-tree billboard texture with alpha, for far_trees_per_m: a trunk from the middle
/// of the bottom edge into a crown of broad leaf clusters (twice a near cluster's leaves)
/// scattered normally about a centre at about 40 % of the height, lighter above, until
/// billboard_target_coverage(). Alpha, border and dilation as make_leaf_cluster's.
/// Deterministic in `rng`. Named "tree_billboard".
sim::Texture make_tree_billboard(Rng* rng, double mean_grey, double contrast, int size_px = 256);

}  // namespace driftlab::scenes
