// A merged sweep's plots (summary/plots/): for every axis and run metric, each algorithm's
// mean over the runs at each axis value with its 95 % interval, drawn by the one gnuplot
// runner (report/gnuplot.hpp), with the .dat and .gp that made them.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "study/sweep_merge.hpp"
#include "study/sweep_pool.hpp"

namespace driftlab::study {

/// Draws the plots into `plots`; returns the summary's image lines and adds each PNG to
/// `out->plots`. A missing or failing gnuplot (`gnuplot_executable`, empty: on PATH) is a
/// warning in `out`, never an error.
std::vector<std::string> draw_sweep_plots(const SweepManifest& m, const Pool& pool,
                                          const std::filesystem::path& gnuplot_executable,
                                          const std::filesystem::path& plots, MergeSummary* out);

}  // namespace driftlab::study
