// VOs of a user's own, registered by name in their program, so that scenarios select them as
// `pipeline.vo: [my_vo]` beside the built-in ones (issue 17, in-process plug-ins):
//
//   driftlab::vo::register_vo("my_vo", [](const driftlab::StereoRig& rig, driftlab::Rng rng) {
//     return std::make_unique<MyVo>(rig, rng);
//   });
//   return driftlab::app::driftlab_main(argc, argv);  // the driftlab command line, with my_vo
//
// Register before scenarios are read (their reader checks the names). The factory gets the
// scenario's rectified rig and the random stream "vo.<name>" of the run's seed.
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::vo {

using VoFactory = std::function<std::unique_ptr<StereoOdometry>(const StereoRig& rig, Rng rng)>;

/// The built-in VOs' names, which a plug-in cannot take: sparse, sparse_kf, pnp, dense.
const std::vector<std::string>& built_in_vo_names();

/// Adds a VO. UserError when `name` is empty, not made of letters, digits, '_' and '-', a
/// built-in's or already registered. Thread-safe.
void register_vo(const std::string& name, VoFactory factory);

/// The registered names, in registration order.
std::vector<std::string> registered_vo_names();

/// The built-in names followed by the registered ones: what `pipeline.vo` accepts.
std::vector<std::string> available_vo_names();

/// A new instance of a registered VO, or null when `name` is not registered.
std::unique_ptr<StereoOdometry> make_registered_vo(const std::string& name, const StereoRig& rig,
                                                   Rng rng);

}  // namespace driftlab::vo
