// The overcast sky's cloud deck (the river-bank issue, item 3): a tiling texture of the
// deck's luminance fluctuations, read by the renderer's sky shader where each viewing ray
// meets a plane at the deck's height (sim::Lighting's cloud fields). Not the GPS sky
// (scenes/sky_obstruction.hpp).
#pragma once

#include <cstdint>

#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes {

/// The deck's texture, `size` x `size`, tiling: fractal gradient noise with octave gain
/// 2^(-1/3), whose 2D power falls as f^(-8/3), the 2D form of the k^(-5/3) spectrum of
/// stratocumulus liquid water path (Cahalan and Snider 1989), from 4 cells a tile (2 km at
/// the river reach's 8 km tile) down to 64; normalised to zero mean and unit variance in
/// double, stored as 128 + 32 n (+-4 sigma). A pure function of the seed (the stream
/// "scene.sky.clouds").
sim::Texture bake_cloud_layer(std::uint64_t seed, int size = 512);

}  // namespace driftlab::scenes
