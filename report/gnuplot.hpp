// The one gnuplot runner of runs and studies: finds gnuplot and the PNG
// terminal it can draw with, and runs a script in its folder. Plots are an
// extra: a missing or failing gnuplot is a warning, never an error.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

namespace driftlab::report {

struct Gnuplot {
  std::filesystem::path executable;
  std::string terminal;  ///< "pngcairo" where gnuplot has it, else the libgd "png"
};

struct GnuplotLookup {
  std::optional<Gnuplot> gnuplot;
  std::string
      warning;  ///< why there is none, e.g. "gnuplot not found on PATH (install gnuplot-nox)"
};

/// gnuplot from PATH, or `executable` when given; probes for the pngcairo terminal.
GnuplotLookup find_gnuplot(const std::filesystem::path& executable = {});

struct GnuplotRun {
  bool ok = false;
  std::string failure;  ///< how it failed ("exit code 1", "killed by signal 9 (Killed)")
};

/// Runs `script` (a file in `dir`) with `dir` as working directory, its output in `dir/log`.
/// The log is removed when gnuplot succeeds, kept when it fails.
GnuplotRun run_gnuplot(const Gnuplot& gnuplot, const std::filesystem::path& dir,
                       const std::string& script, const std::string& log);

}  // namespace driftlab::report
