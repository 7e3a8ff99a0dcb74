#include "report/gnuplot.hpp"

#include <system_error>

#include "core/error.hpp"
#include "core/process.hpp"

namespace driftlab::report {

namespace fs = std::filesystem;

GnuplotLookup find_gnuplot(const fs::path& executable) {
  GnuplotLookup out;
  const std::optional<fs::path> exe =
      executable.empty() ? find_on_path("gnuplot") : std::optional<fs::path>(executable);
  if (!exe) {
    out.warning = "gnuplot not found on PATH (install gnuplot-nox)";
    return out;
  }
  try {
    // pngcairo draws nicer; the libgd `png` terminal is the fallback.
    const ProcessSpec probe{*exe, {"-e", "set terminal pngcairo"}, "/dev/null", {}, true};
    const bool cairo = wait_process(spawn_process(probe)).ok();
    out.gnuplot = Gnuplot{*exe, cairo ? "pngcairo" : "png"};
  } catch (const UserError& e) {
    out.warning = std::string("gnuplot cannot run: ") + e.what();
  }
  return out;
}

GnuplotRun run_gnuplot(const Gnuplot& gnuplot, const fs::path& dir, const std::string& script,
                       const std::string& log) {
  const ProcessSpec spec{gnuplot.executable, {script}, dir / log, dir, true};
  GnuplotRun out;
  try {
    const ExitStatus st = wait_process(spawn_process(spec));
    out.ok = st.ok();
    if (!out.ok) out.failure = st.describe();
  } catch (const UserError& e) {
    out.failure = e.what();
  }
  std::error_code ec;
  if (out.ok) fs::remove(dir / log, ec);
  return out;
}

}  // namespace driftlab::report
