// Child processes for the sweep runner and the plot step: fork + exec with
// standard output and error sent to a file, an optional working directory,
// and (Linux) the child terminated when the process that started it dies, so
// that a killed `driftlab sweep run` does not leave jobs running unsupervised.
#pragma once

#include <sys/types.h>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace driftlab {

/// What to start. `executable` is run as given (no PATH search; see find_on_path).
struct ProcessSpec {
  std::filesystem::path executable;
  std::vector<std::string> args;            // argv[1...]; argv[0] is the executable
  std::filesystem::path output_file;        // stdout and stderr, truncated; empty: inherit
  std::filesystem::path working_directory;  // empty: the caller's
  /// SIGTERM to the child when the parent dies (PR_SET_PDEATHSIG). Linux ties this to the
  /// thread that forks: spawn from a thread that outlives the child (the main thread).
  bool die_with_parent = true;
};

/// How a child ended.
struct ExitStatus {
  bool exited = false;  // true: returned `code`; false: killed by `signal`
  int code = 0;
  int signal = 0;
  bool ok() const { return exited && code == 0; }
  /// "exit code 1", "killed by signal 9 (Killed)".
  std::string describe() const;
};

/// Starts the child; returns its pid. Throws UserError naming the executable when it cannot be
/// started (missing, not executable, output file not writable): the exec failure is reported
/// back through a close-on-exec pipe rather than as a mysterious exit code 127.
pid_t spawn_process(const ProcessSpec& spec);

/// Non-blocking: the status once the child has ended (and is reaped), else nullopt.
std::optional<ExitStatus> try_wait_process(pid_t pid);

/// Blocks until the child ends.
ExitStatus wait_process(pid_t pid);

/// The first executable file called `name` in $PATH, or nullopt.
std::optional<std::filesystem::path> find_on_path(const std::string& name);

/// `text` quoted for /bin/sh: 'text', with each ' written as '\''.
std::string shell_quote(const std::string& text);

/// True when a process with this pid exists on this machine (kill(pid, 0)).
bool process_alive(pid_t pid);

}  // namespace driftlab
