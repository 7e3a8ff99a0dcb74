// The river paper's Tables 1-4 next to a run's (`driftlab paper`):
// Kriechbaumer et al. (2015), Section 3, for the twin scenarios
// river_crossing (Table 2's discharge-measurement rows) and river_survey
// (Table 2's total trajectory), so that a reader sees at once where the twin
// agrees with the real river and where it does not.
#pragma once

#include <optional>
#include <string>

#include "record/run_record.hpp"

namespace driftlab::report {

/// Which row of the paper's Table 2 a run is set against.
enum class RiverPaperTrack {
  kDischarge,  ///< four river crossings, 54 m (river_crossing)
  kTotal,      ///< the whole 663 m survey (river_survey)
};

/// The track a twin scenario reproduces, by its name; nullopt for others.
std::optional<RiverPaperTrack> river_paper_track_of(const std::string& scenario_name);

/// Markdown: for each of Tables 1-4 the paper's sparse and dense columns and
/// the run's sparse, sparse_kf and dense columns (those the run has), then
/// the comparisons the twin-fidelity work asks for (does sparse beat dense,
/// are h and d significant). `metrics` is a run's metrics.json. Throws
/// UserError when the run has none of sparse, sparse_kf and dense.
std::string river_paper_side_by_side(const record::RunRecord& metrics, RiverPaperTrack track);

}  // namespace driftlab::report
