// `driftlab-gate`: the CI baseline gate alone, the same command as `driftlab regress`.
#include "app/cli_main.hpp"
#include "app/gate_command.hpp"

#ifndef DRIFTLAB_VERSION
#define DRIFTLAB_VERSION "unknown"
#endif

int main(int argc, char** argv) {
  CLI::App app{
      "driftlab-gate: compare metrics with a baseline (CI regression gate); exit 5 on a "
      "regression. The same command as `driftlab regress`."};
  app.set_version_flag("--version", std::string(DRIFTLAB_VERSION));
  driftlab::app::GateCommand gate(&app);
  return driftlab::app::run_cli_main(app, argc, argv, [&] { return gate.run(); });
}
