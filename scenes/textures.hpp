// Procedural grayscale textures (no downloaded assets): natural surfaces from
// multi-octave noise, man-made ones from structured patterns. Every texture
// wraps (its left and right, top and bottom edges continue each other), so the
// renderer can repeat it; the bytes depend only on the Rng's state.
#pragma once

#include <string_view>

#include "core/rng.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes {

enum class TextureKind {
  kGrass,        // meadow seen from above: clumps, blades, dry patches
  kSoil,         // bank face: earth with pebbles and grass tufts
  kBark,         // vertical ridges and fissures
  kFoliage,      // leaf clusters with dark gaps (high contrast)
  kReeds,        // vertical blades, darker towards the base
  kStone,        // cobbles / rip-rap with mortar
  kBrick,        // stretcher bond, 8 courses x 4 bricks, light mortar lines
  kConcrete,     // mottled cast concrete with pits and formwork joints
  kSheetPiling,  // steel sheet piles: vertical corrugation, faint rust (low contrast)
  kPaintedWall,  // nearly uniform paint (very low contrast)
  kPoster,       // high-contrast structured print with a white margin; `variant` picks the layout
  kWindow,       // framed window with 2 x 2 panes reflecting the sky
  kLabFloor,     // 4 x 4 square tiles with grout
  kRoof,         // overlapping roof tiles, 8 rows
  kFacade,       // one 3 m x 3 m bay of a brick facade with a window
  kMetalPanel,   // painted steel panel with seams and bolts
};

/// Lower-case name, e.g. "sheet_piling"; used as the sim::Texture name.
std::string_view texture_kind_name(TextureKind kind);

/// Default edge length [px] of a kind (256 or 512).
int default_texture_size(TextureKind kind);

/// Number of distinct poster layouts (valid `variant`s of kPoster).
constexpr int kPosterVariants = 4;

/// Generates a texture of `kind` from `rng` (which it advances).
///   contrast: deviations from the image mean are multiplied by it, then
///             clamped to [0, 255] (1 = natural, 0 = flat grey), >= 0;
///   variant:  layout of a poster (0 .. kPosterVariants - 1), ignored otherwise;
///   size_px:  edge length (square), 16 .. 4096; 0 = default_texture_size.
sim::Texture make_texture(TextureKind kind, Rng& rng, double contrast = 1.0, int variant = 0,
                          int size_px = 0);

/// Adds a texture of `kind` to the scene, drawn from its own stream
/// "scene.texture.KIND" (posters: "scene.texture.posterVARIANT"), so that changing one
/// texture's code leaves the others' bytes alone; returns its index in g->textures.
int add_scene_texture(sim::SceneGeometry* g, const RngStreams& streams, TextureKind kind,
                      double contrast = 1.0, int variant = 0);

}  // namespace driftlab::scenes
