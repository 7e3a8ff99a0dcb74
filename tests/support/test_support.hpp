// Helpers shared by the test files: reading files, temporary folders, and
// running the `driftlab` executable or a shell command as a user would.
#pragma once

#include <filesystem>
#include <functional>
#include <limits>
#include <numbers>
#include <string>
#include <vector>

// DRIFTLAB_TEST_ASAN: this build has AddressSanitizer (GCC defines __SANITIZE_ADDRESS__, clang
// answers __has_feature).
#if defined(__SANITIZE_ADDRESS__)
#define DRIFTLAB_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define DRIFTLAB_TEST_ASAN 1
#endif
#endif

namespace driftlab::test {

/// Constants that many test files use (brought in with `using test::kPi;` and so on, so that the
/// files of one test executable can be compiled as one unit).
inline constexpr double kPi = std::numbers::pi;
inline constexpr double kDeg = std::numbers::pi / 180.0;  ///< one degree [rad]
inline constexpr double kEps = std::numeric_limits<double>::epsilon();

/// The source tree (scenarios, tests/data) and the build tree (bin/driftlab).
std::filesystem::path source_dir();
std::filesystem::path binary_dir();
/// build/bin/driftlab.
std::filesystem::path cli_path();

/// The whole file as bytes; "" when it cannot be read.
std::string slurp(const std::filesystem::path& path);

/// The "# expect: TEXT" comment lines of a bad input file: what its error message must contain.
std::vector<std::string> expected_messages(const std::filesystem::path& file);

/// What the UserError thrown by `f` says, or "(no UserError)" when it throws none.
std::string user_error_of(const std::function<void()>& f);
/// Expects `f` to throw a UserError whose message contains `part`.
void expect_user_error(const std::function<void()>& f, const std::string& part);

/// A path under the temporary folder, unique to this process and `name`, that does not exist;
/// removed, with what is under it, when the process exits.
std::filesystem::path unused_temp_path(const std::string& name);
/// The same path, created as an empty folder.
std::filesystem::path fresh_temp_dir(const std::string& name);

/// 'text' quoted for /bin/sh.
std::string shell_quote(const std::string& text);

struct CommandResult {
  int exit_code = -1;  // -1: killed by a signal
  std::string out;     // standard output
  std::string err;     // standard error
  std::string output;  // both, for searching messages
};

/// Runs build/bin/driftlab with `args`; `env` ("A=1 B=2") is put before the command.
CommandResult run_cli(const std::vector<std::string>& args, const std::string& env = "");

/// Runs a /bin/sh command line.
CommandResult run_shell(const std::string& command);

}  // namespace driftlab::test
