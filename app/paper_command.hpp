// `driftlab paper`: the papers' tables next to the twin's. The river paper's Tables 1-4
// beside a run of river_crossing or river_survey, the twin measured at its camera (exact)
// and at the paper's prism (report/paper_compare.hpp); the basin paper's Tables 2-3 beside
// runs of its seven experiments (report/basin_paper_compare.hpp).
#pragma once

#include <array>
#include <string>
#include <vector>

namespace driftlab::app {

/// The prism the river twins assume (docs/twin-vs-paper.md, "The paper's truth was a prism"):
/// 1 m above the centre of gravity on the centre line, in the body's FRD frame [m]. The paper's
/// columns at the prism place it in the camera's frame through the run's camera mount.
inline constexpr std::array<double, 3> kRiverPrismFrd{0.0, 0.0, -1.0};

/// `runs`: run folders or their metrics.json. `track`: discharge|total or empty (from the
/// scenario's name). `prism`: X,Y,Z from the camera, "none", or empty for kRiverPrismFrd seen
/// from the run's camera. `out`: a file, or empty for stdout.
int paper_command(const std::vector<std::string>& runs, const std::string& track,
                  const std::string& prism, const std::string& out);

}  // namespace driftlab::app
