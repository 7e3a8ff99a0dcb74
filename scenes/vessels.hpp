// Other vessels on the river (docs/renderer-and-scenes.md, "Other vessels: a moving world"): motor
// boats under way or moored, each a mover of the scene (sim::MoverMotion): a hull, a deck and a
// wheelhouse in the vessel's own frame (FRD, origin on the waterline at mid-length), drawn at its
// pose at every instant.
#pragma once

#include <cstdint>
#include <vector>

#include "scenes/scene_options.hpp"
#include "sim/render/scene_geometry.hpp"

namespace driftlab::scenes {

/// How vessel `index` of these options moves: from (north_m, east_m) at t = 0 along the river
/// at speed_mps (heading north, or south when the speed is negative), rocking with the
/// amplitudes and periods asked for and phases drawn from stream "scene.vessels.INDEX".
sim::MoverMotion vessel_motion(const OtherVesselOptions& options, std::uint64_t seed, int index);

/// Half the hull's width at x along its length [m] (x from -length/2 at the transom to
/// +length/2 at the stem): the full half-beam aft of a quarter length forward of mid-length,
/// then narrowing as sqrt(1 - s) to a tenth of it at the stem (s in [0, 1] over that span).
double vessel_half_beam(const OtherVesselOptions& options, double x_m);

/// The vessels' meshes and motions, added to `scene` (nothing when there are none; their
/// textures are added only then, so a scene without vessels keeps its bytes).
void add_other_vessels(sim::SceneGeometry* scene, const std::vector<OtherVesselOptions>& vessels,
                       std::uint64_t seed, double texture_contrast);

}  // namespace driftlab::scenes
