// The towed ship model as the basin's overhead camera sees it (basin paper Section 3.2): its
// hull and the red and green markers on its deck, in the body frame (FRD), drawn at the
// model's pose (sim::Mesh::on_body).
#pragma once

#include <vector>

#include "sim/physics/vessel/vessel_options.hpp"
#include "sim/render/scene_geometry.hpp"
#include "sim/sensors/overhead_options.hpp"

namespace driftlab::scenes {

/// Height of the markers' faces in the body frame (z, down positive) [m]: 1 mm above the deck.
double marker_face_z_B(const sim::HullOptions& hull);

/// The hull (a box keel to deck, as sim::HullOptions gives it) and the two round markers on
/// the centreline of its deck: red forward, green aft, `markers.separation_m` apart around
/// `markers.centre_forward_m`.
std::vector<sim::Mesh> ship_model_meshes(const sim::HullOptions& hull,
                                         const sim::MarkerOptions& markers);

}  // namespace driftlab::scenes
