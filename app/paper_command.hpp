// `driftlab paper`: the papers' tables next to the twin's. The river paper's Tables 1-4
// beside a run of river_crossing or river_survey, the twin measured at its camera (exact)
// and at the paper's prism (report/paper_compare.hpp); the basin paper's Tables 2-3 beside
// runs of its seven experiments (report/basin_paper_compare.hpp).
#pragma once

#include <string>
#include <vector>

namespace driftlab::app {

/// The prism the river twins assume (docs/twin-vs-paper.md, "The paper's truth was a prism"):
/// 1 m above the centre of gravity on the centre line, from the camera in its optical frame.
inline constexpr const char* kRiverPrism = "-0.35,-0.55,0.606";

/// `runs`: run folders or their metrics.json. `track`: discharge|total or empty (from the
/// scenario's name). `prism`: X,Y,Z from the camera, or "none". `out`: a file, or empty for
/// stdout.
int paper_command(const std::vector<std::string>& runs, const std::string& track,
                  const std::string& prism, const std::string& out);

}  // namespace driftlab::app
