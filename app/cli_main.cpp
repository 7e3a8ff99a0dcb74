#include "app/cli_main.hpp"

#include <iostream>

#include "core/error.hpp"

namespace driftlab::app {

int run_cli_main(CLI::App& app, int argc, char** argv, const std::function<int()>& dispatch) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int rc = app.exit(e);
    return rc == 0 ? kExitOk : kExitUsage;
  }
  try {
    return dispatch();
  } catch (const UsageError& e) {
    std::cerr << "error: " << e.what() << "\nRun with --help for more information.\n";
    return kExitUsage;
  } catch (const Unavailable& e) {
    std::cerr << "driftlab: not available in this build yet: " << e.what() << "\n";
    return kExitUnavailable;
  } catch (const UserError& e) {
    std::cerr << "error: " << e.what() << "\n";
    return kExitUserError;
  } catch (const std::exception& e) {
    std::cerr << "driftlab: internal error: " << e.what() << "\n";
    return kExitInternal;
  }
}

}  // namespace driftlab::app
