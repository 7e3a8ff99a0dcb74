// Combinations of scenario values that each look fine on their own but cannot run: a wave
// longer than the basin, a hull that sinks, a camera under the water line, a mission that
// starts or goes outside the scene. Checked before any work starts (validate_scenario), each
// problem naming every key involved. And values that run but that nature would not give.
#pragma once

#include <string>
#include <vector>

#include "core/yaml_io.hpp"
#include "pipeline/scenario.hpp"

namespace driftlab::pipeline {

/// One problem per impossible combination (its path the first key the message names);
/// empty when the scenario can run.
std::vector<yaml::Problem> impossible_combinations(const Scenario& scenario);

/// Values that run but that nature would not give, as warnings (`scenario check` prints them,
/// a run records them in metrics.json "warnings" and the report): a regular wave steeper than
/// Miche's breaking limit, which linear wave theory still computes. The basin paper's
/// experiments 4 and 7 (11 mm on a 59 mm wavelength, Table 1) are such waves.
std::vector<std::string> implausible_values(const Scenario& scenario);

}  // namespace driftlab::pipeline
