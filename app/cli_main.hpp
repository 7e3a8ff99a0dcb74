// What every driftlab executable does around its commands: parse the command
// line, run, and turn exceptions into the documented exit codes. Library code
// throws; only this file maps errors to exit codes.
#pragma once

#include <CLI/CLI.hpp>

#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "core/error.hpp"

namespace driftlab::app {

constexpr int kExitOk = 0;
constexpr int kExitUserError = 1;    // bad input: the message names file, line, key, value
constexpr int kExitUsage = 2;        // bad command line
constexpr int kExitUnavailable = 3;  // a stage this build does not have
constexpr int kExitInternal = 4;     // a bug
constexpr int kExitRegressed = 5;    // `regress`: a metric regressed or is missing
constexpr int kExitJobsFailed = 6;   // `sweep run`, `run --manifest`: some jobs failed

/// A subcommand whose stage this build does not have.
struct Unavailable : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// A command line that parsed but does not make sense (e.g. a missing option that is required
/// only without a subcommand): exit kExitUsage.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Runs `f`, turning a UserError into a UsageError ("FLAG: " and its message): for the values
/// of command-line options that library code checks (a format's name, an eval option), which
/// are a bad command line, not bad input.
template <class F>
auto as_usage_error(std::string_view flag, F&& f) -> decltype(f()) {
  try {
    return f();
  } catch (const UserError& e) {
    throw UsageError(flag.empty() ? std::string(e.what())
                                  : std::string(flag) + ": " + std::string(e.what()));
  }
}

/// `text` into the file `out` (written atomically), or to stdout when `out` is empty.
void write_or_print(const std::string& text, const std::string& out);

/// CLI11 check of a seed option: a non-negative integer (as the scenario's `seed`).
inline CLI::Validator seed_check() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        std::uint64_t value = 0;
        const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
        if (text.empty() || error != std::errc() || end != text.data() + text.size())
          return "got '" + text + "', expected a non-negative integer";
        return "";
      },
      "SEED");
}

/// `--frame-cache DIR`, the option of every command that renders frames: it sets
/// DRIFTLAB_FRAME_CACHE for the command and every job it starts (pipeline/frame_cache.hpp reads
/// it), so that a flag and the environment are one rule.
inline void add_frame_cache_option(CLI::App* cmd) {
  cmd->add_option_function<std::string>(
      "--frame-cache",
      [](const std::string& dir) { ::setenv("DRIFTLAB_FRAME_CACHE", dir.c_str(), 1); },
      "Keep the rendered frames in DIR and replay them when nothing that decides them changed "
      "(default: $DRIFTLAB_FRAME_CACHE; none when unset; size: $DRIFTLAB_FRAME_CACHE_GIB, "
      "default 20)");
}

/// Parses argv into `app` and runs `dispatch`, mapping a bad command line to kExitUsage (after
/// CLI11 printed why; --help and --version exit 0), UsageError to kExitUsage, UserError to
/// kExitUserError, Unavailable to kExitUnavailable and any other exception to kExitInternal.
int run_cli_main(CLI::App& app, int argc, char** argv, const std::function<int()>& dispatch);

/// A generated key reference (`driftlab scenario|sweep|regress schema`): "# TITLE", a line
/// saying which command generated it and `intro`, then the table; written to `out`
/// (atomically) or, when `out` is empty, to standard output. Returns kExitOk.
int print_reference(const std::string& title, const std::string& command, const std::string& intro,
                    const std::string& table, const std::string& out);

}  // namespace driftlab::app
