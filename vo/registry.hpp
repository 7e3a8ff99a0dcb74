// VOs of a user's own, registered by name in their program, so that scenarios select them as
// `pipeline.vo: [my_vo]` beside the built-in ones (in-process plug-ins; docs/datasets.md,
// "Your VO in-process: the installed package"):
//
//   driftlab::vo::register_vo("my_vo", [](const driftlab::StereoRig& rig, driftlab::Rng rng) {
//     return std::make_unique<MyVo>(rig, rng);
//   });
//   return driftlab::app::driftlab_main(argc, argv);  // the driftlab command line, with my_vo
//
// Register before scenarios are read (their reader checks the names). The factory gets the
// scenario's rectified rig and the random stream "vo.<name>" of the run's seed.
//
// A VO with options of its own registers with its options struct (a visit() list, as every
// driftlab options struct has); the scenario sets them under pipeline.plugins.<name>, read by
// the same strict reader, overridable with --set and sweepable:
//
//   driftlab::vo::register_vo<MyVoOptions>(
//       "my_vo", [](const driftlab::StereoRig& rig, driftlab::Rng rng, const MyVoOptions& o) {
//         return std::make_unique<MyVo>(rig, rng, o);
//       });
#pragma once

#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "core/camera.hpp"
#include "core/error.hpp"
#include "core/rng.hpp"
#include "core/yaml_io.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::vo {

using VoFactory = std::function<std::unique_ptr<StereoOdometry>(const StereoRig& rig, Rng rng)>;
template <yaml::Visitable Options>
using VoFactoryWithOptions = std::function<std::unique_ptr<StereoOdometry>(
    const StereoRig& rig, Rng rng, const Options& options)>;

namespace detail {
using ErasedFactory = std::function<std::unique_ptr<StereoOdometry>(
    const StereoRig& rig, Rng rng, const yaml::NamedOptions::Holder* options)>;
using OptionsMaker = std::function<std::unique_ptr<yaml::NamedOptions::Holder>()>;
void register_erased(const std::string& name, ErasedFactory factory, OptionsMaker options);
}  // namespace detail

/// The built-in VOs' names, which a plug-in cannot take: sparse, sparse_kf, pnp, dense.
const std::vector<std::string>& built_in_vo_names();

/// Adds a VO. UserError when `name` is empty, not made of letters, digits, '_' and '-', a
/// built-in's or already registered. Thread-safe.
void register_vo(const std::string& name, VoFactory factory);

/// Adds a VO with options: `Options{}` unless the scenario sets pipeline.plugins.<name>.
/// The same errors as register_vo() without options.
template <yaml::Visitable Options>
void register_vo(const std::string& name, VoFactoryWithOptions<Options> factory) {
  if (!factory) throw UserError("register_vo: '" + name + "': no factory");
  detail::register_erased(
      name,
      [f = std::move(factory)](const StereoRig& rig, Rng rng,
                               const yaml::NamedOptions::Holder* given) {
        const Options* o = yaml::options_of<Options>(given);
        return f(rig, std::move(rng), o ? *o : Options{});
      },
      [] { return yaml::make_options<Options>(); });
}

/// pipeline.plugins of a scenario: the options of the registered VOs that have some.
yaml::NamedOptions plugin_options();

/// The registered names, in registration order.
std::vector<std::string> registered_vo_names();

/// The built-in names followed by the registered ones: what `pipeline.vo` accepts.
std::vector<std::string> available_vo_names();

/// A new instance of a registered VO, or null when `name` is not registered; with its options
/// from `plugins` (pipeline.plugins) when they are there, else its defaults.
std::unique_ptr<StereoOdometry> make_registered_vo(const std::string& name, const StereoRig& rig,
                                                   Rng rng, const yaml::NamedOptions& plugins = {});

}  // namespace driftlab::vo
