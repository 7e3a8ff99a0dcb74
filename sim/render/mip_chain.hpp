// The mip levels of the water's mirror image, drawn by the GL pipeline: each level the 2x2 box
// average of the level above. The wind ripples' blur samples them (shaders::kWaterFs).
// glGenerateMipmap does the same job, but Mesa's llvmpipe runs it on the calling thread: 21 ms of
// that thread for a 1024x768 stereo pair, where drawing the levels keeps the work on llvmpipe's
// raster threads.
#pragma once

#include <vector>

#include "sim/render/render_options.hpp"
#include "sim/render/renderer.hpp"

namespace driftlab::sim {

/// Level sizes as OpenGL makes them: each max(1, floor(half the level above)), down to 1x1.
int mip_level_count(int width, int height);

/// The levels 1.. of `base` as the renderer draws them, on a context of its own: level k + 1
/// texel (i, j) is the mean of level k texels (2i, 2j), (2i + 1, 2j), (2i, 2j + 1) and
/// (2i + 1, 2j + 1), a last odd row or column of level k left out, rounded to the nearest 8-bit
/// level. For tests and tools; the renderer builds them in place.
std::vector<GrayImage> draw_mip_levels(const GrayImage& base, RenderBackend backend);

}  // namespace driftlab::sim
