#include "tests/support/test_support.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <fstream>
#include <mutex>
#include <sstream>

namespace driftlab::test {

namespace fs = std::filesystem;

fs::path source_dir() { return DRIFTLAB_SOURCE_DIR; }
fs::path binary_dir() { return DRIFTLAB_BINARY_DIR; }
fs::path cli_path() { return binary_dir() / "bin" / "driftlab"; }

std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::vector<std::string> expected_messages(const fs::path& file) {
  std::vector<std::string> out;
  std::ifstream in(file);
  const std::string tag = "# expect: ";
  for (std::string line; std::getline(in, line);)
    if (line.rfind(tag, 0) == 0) out.push_back(line.substr(tag.size()));
  return out;
}

namespace {

// The temporary paths this process handed out, removed when it exits (never by a forked
// child), so that the tests leave nothing behind in the temporary folder.
class TempPaths {
 public:
  void add(const fs::path& p) {
    const std::lock_guard<std::mutex> lock(mutex_);
    paths_.push_back(p);
  }
  ~TempPaths() {
    if (::getpid() != owner_) return;
    std::error_code ignored;
    for (const fs::path& p : paths_) fs::remove_all(p, ignored);
  }

 private:
  std::mutex mutex_;
  std::vector<fs::path> paths_;
  const pid_t owner_ = ::getpid();
};

TempPaths& temp_paths() {
  static TempPaths paths;
  return paths;
}

}  // namespace

fs::path unused_temp_path(const std::string& name) {
  const fs::path p =
      fs::temp_directory_path() / ("driftlab_" + name + "_" + std::to_string(::getpid()));
  fs::remove_all(p);
  temp_paths().add(p);
  return p;
}

fs::path fresh_temp_dir(const std::string& name) {
  const fs::path p = unused_temp_path(name);
  fs::create_directories(p);
  return p;
}

std::string user_error_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const UserError& e) {
    return e.what();
  }
  return "(no UserError)";
}

void expect_user_error(const std::function<void()>& f, const std::string& part) {
  const std::string msg = user_error_of(f);
  EXPECT_NE(msg.find(part), std::string::npos) << "message: " << msg << "\nexpected part: " << part;
}

std::string shell_quote(const std::string& text) {
  std::string out = "'";
  for (char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

namespace {

// Runs `command` with its output in two temporary files, read back and removed.
CommandResult run_with_logs(const std::string& command) {
  static int counter = 0;
  const std::string stem =
      "driftlab_cmd_" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
  const fs::path out_log = fs::temp_directory_path() / (stem + ".out");
  const fs::path err_log = fs::temp_directory_path() / (stem + ".err");
  const std::string line =
      command + " > " + shell_quote(out_log.string()) + " 2> " + shell_quote(err_log.string());
  const int status = std::system(line.c_str());
  CommandResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out_log);
  r.err = slurp(err_log);
  r.output = r.out + r.err;
  fs::remove(out_log);
  fs::remove(err_log);
  return r;
}

}  // namespace

CommandResult run_cli(const std::vector<std::string>& args, const std::string& env) {
  std::string cmd = env + (env.empty() ? "" : " ") + shell_quote(cli_path().string());
  for (const auto& a : args) cmd += " " + shell_quote(a);
  return run_with_logs(cmd);
}

CommandResult run_shell(const std::string& command) { return run_with_logs("( " + command + " )"); }

}  // namespace driftlab::test
