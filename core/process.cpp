#include "core/process.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <system_error>

#include "core/error.hpp"

namespace driftlab {

std::string ExitStatus::describe() const {
  if (exited) return fmt::format("exit code {}", code);
  const char* name = ::strsignal(signal);
  return fmt::format("killed by signal {} ({})", signal, name ? name : "unknown");
}

pid_t spawn_process(const ProcessSpec& spec) {
  // Everything the child needs is prepared before fork(): between fork and
  // exec only async-signal-safe calls are allowed.
  std::vector<std::string> argv_storage;
  argv_storage.push_back(spec.executable.string());
  argv_storage.insert(argv_storage.end(), spec.args.begin(), spec.args.end());
  std::vector<char*> argv;
  for (auto& a : argv_storage) argv.push_back(a.data());
  argv.push_back(nullptr);
  const std::string exe = spec.executable.string();
  const std::string out = spec.output_file.string();
  const std::string cwd = spec.working_directory.string();

  int report[2];  // the child writes errno here when exec (or setup) fails
  if (::pipe2(report, O_CLOEXEC) != 0)
    throw UserError(fmt::format("{}: cannot start: pipe: {}", exe, std::strerror(errno)));
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int e = errno;
    ::close(report[0]);
    ::close(report[1]);
    throw UserError(fmt::format("{}: cannot start: fork: {}", exe, std::strerror(e)));
  }
  if (pid == 0) {
    int stage = 0;  // 0 setup, 1 output file, 2 working directory, 3 exec
    auto fail = [&](int e) {
      const int msg[2] = {stage, e};
      [[maybe_unused]] ssize_t n = ::write(report[1], msg, sizeof msg);
      ::_exit(127);
    };
    if (spec.die_with_parent) {
      if (::prctl(PR_SET_PDEATHSIG, SIGTERM) != 0) fail(errno);
      if (::getppid() != parent) ::_exit(127);  // the parent died before prctl
    }
    if (!out.empty()) {
      stage = 1;
      const int fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd < 0) fail(errno);
      if (::dup2(fd, STDOUT_FILENO) < 0 || ::dup2(fd, STDERR_FILENO) < 0) fail(errno);
    }
    if (!cwd.empty()) {
      stage = 2;
      if (::chdir(cwd.c_str()) != 0) fail(errno);
    }
    stage = 3;
    ::execv(exe.c_str(), argv.data());
    fail(errno);
  }
  ::close(report[1]);
  int msg[2] = {0, 0};
  ssize_t n;
  do {
    n = ::read(report[0], msg, sizeof msg);
  } while (n < 0 && errno == EINTR);
  ::close(report[0]);
  if (n == static_cast<ssize_t>(sizeof msg)) {
    int status = 0;
    ::waitpid(pid, &status, 0);
    const char* what = msg[0] == 1   ? "cannot write its output file "
                       : msg[0] == 2 ? "cannot enter the working directory "
                                     : "";
    const std::string where = msg[0] == 1 ? out : msg[0] == 2 ? cwd : "";
    throw UserError(fmt::format("{}: cannot start: {}{}{}{}", exe, what, where,
                                where.empty() ? "" : ": ", std::strerror(msg[1])));
  }
  return pid;
}

namespace {
ExitStatus decode(int status) {
  ExitStatus s;
  if (WIFEXITED(status)) {
    s.exited = true;
    s.code = WEXITSTATUS(status);
  } else if (WIFSIGNALED(status)) {
    s.signal = WTERMSIG(status);
  }
  return s;
}
}  // namespace

std::optional<ExitStatus> try_wait_process(pid_t pid) {
  int status = 0;
  pid_t r;
  do {
    r = ::waitpid(pid, &status, WNOHANG);
  } while (r < 0 && errno == EINTR);
  if (r == 0) return std::nullopt;
  DRIFTLAB_DEMAND_MSG(r == pid, "waitpid on a process that is not our child");
  return decode(status);
}

ExitStatus wait_process(pid_t pid) {
  int status = 0;
  pid_t r;
  do {
    r = ::waitpid(pid, &status, 0);
  } while (r < 0 && errno == EINTR);
  DRIFTLAB_DEMAND_MSG(r == pid, "waitpid on a process that is not our child");
  return decode(status);
}

std::optional<std::filesystem::path> find_on_path(const std::string& name) {
  const char* path = std::getenv("PATH");
  if (!path) return std::nullopt;
  std::string all = path;
  std::size_t start = 0;
  while (start <= all.size()) {
    const auto colon = all.find(':', start);
    std::string dir = all.substr(start, colon == std::string::npos ? colon : colon - start);
    if (dir.empty()) dir = ".";
    const std::filesystem::path candidate = std::filesystem::path(dir) / name;
    std::error_code ec;
    if (std::filesystem::is_regular_file(candidate, ec) && ::access(candidate.c_str(), X_OK) == 0)
      return candidate;
    if (colon == std::string::npos) break;
    start = colon + 1;
  }
  return std::nullopt;
}

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

bool process_alive(pid_t pid) { return pid > 0 && (::kill(pid, 0) == 0 || errno == EPERM); }

}  // namespace driftlab
