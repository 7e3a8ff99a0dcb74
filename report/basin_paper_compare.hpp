// The basin paper's Tables 2 and 3 next to the twin's (`driftlab paper` on basin runs):
// Kucic and Valcic (2020), Section 4, the Kalman and particle filters' RMSE (std) of N, E,
// u, v and heading in each of the seven experiments of its Table 1, beside the same filters
// on the twin, measured against the exact truth and against the simulated overhead camera
// (the paper's reference, `sensors.overhead`).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "record/run_record.hpp"

namespace driftlab::report {

/// The experiment (1-7) a basin scenario reproduces, by its name (basin_expN); nullopt for
/// others.
std::optional<int> basin_paper_experiment_of(const std::string& scenario_name);

/// Markdown: Tables 2 (Kalman filter, algorithm *_ned_kf) and 3 (particle filter, *_ned_pf),
/// a row per experiment and source (paper; twin against the exact truth; twin against the
/// overhead camera, when the run has it), and which experiment each source finds hardest.
/// `runs` are metrics.json of basin runs. Throws UserError when one is not a basin twin or
/// has neither filter.
std::string basin_paper_side_by_side(const std::vector<record::RunRecord>& runs);

}  // namespace driftlab::report
