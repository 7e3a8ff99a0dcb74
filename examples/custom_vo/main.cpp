// my-driftlab: driftlab's command line with one more VO, "lk_pnp", registered with its options
// (pipeline.plugins.lk_pnp.*) before the command line reads any scenario.
#include <memory>

#include "app/driftlab_main.hpp"
#include "lk_pnp_vo.hpp"
#include "vo/registry.hpp"

int main(int argc, char** argv) {
  driftlab::vo::register_vo<LkPnpOptions>(
      "lk_pnp", [](const driftlab::StereoRig& rig, driftlab::Rng rng, const LkPnpOptions& o) {
        return std::make_unique<LkPnpVo>(rig, rng, o);
      });
  return driftlab::app::driftlab_main(argc, argv);
}
