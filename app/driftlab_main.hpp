// The driftlab command line as a function: `driftlab` itself is a one-line main() around it,
// and a user's program can register its own VOs (vo/registry.hpp) and then call it to get the
// whole command line with those VOs selectable in `pipeline.vo` (examples/custom_vo/).
#pragma once

namespace driftlab::app {

/// Parses argv as `driftlab` does and runs the command; returns the documented exit code.
int driftlab_main(int argc, char** argv);

}  // namespace driftlab::app
