// Writing results so that a failure never leaves a half-written file or run
// directory behind (docs/design.md "Errors"): write under a temporary name in the
// same directory, then rename into place, which POSIX makes atomic.
#pragma once

#include <filesystem>
#include <fstream>
#include <string_view>

namespace driftlab {

/// A file written as `PATH.tmp.<pid>.<counter>` and renamed onto PATH by commit().
/// Without commit() (an exception, an early return) the temporary is removed and
/// PATH is left as it was. Throws UserError "PATH: cannot write: <reason>".
class AtomicFile {
 public:
  /// Opens the temporary file (binary mode: bytes are written as given).
  explicit AtomicFile(std::filesystem::path path);
  ~AtomicFile();

  AtomicFile(AtomicFile&& other) noexcept;
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;
  AtomicFile& operator=(AtomicFile&&) = delete;

  /// The stream to write the content into.
  std::ofstream& stream() { return out_; }
  /// Writes bytes to stream(); if that fails, commit() can name the system
  /// error (a failed `stream() <<` is reported without one, its errno being lost).
  void write(std::string_view bytes);
  /// The final path and the temporary one (for messages and tests).
  const std::filesystem::path& path() const { return path_; }
  const std::filesystem::path& temp_path() const { return temp_path_; }

  /// Flushes, checks that every write succeeded and renames onto path().
  /// On failure removes the temporary and throws UserError. Call at most once.
  void commit();

 private:
  [[noreturn]] void fail(int error_number);

  std::filesystem::path path_;
  std::filesystem::path temp_path_;
  std::ofstream out_;
  bool active_ = true;   // false once committed, failed or moved from
  int write_error_ = 0;  // errno of the first failed write()
};

/// Writes `content` to `path` through an AtomicFile.
void write_file_atomic(const std::filesystem::path& path, std::string_view content);

/// A run-output directory built as `DIR.tmp.<pid>` and renamed onto DIR by commit().
/// Without commit() the temporary directory and everything in it is removed.
class AtomicDirectory {
 public:
  /// Creates DIR's parent directories if needed and a fresh `DIR.tmp.<pid>` (a
  /// stale one left by a crashed process with the same pid is removed first).
  /// When DIR already exists and `replace` is false this throws UserError at once,
  /// so that a long run does not fail only at its end; commit() checks again.
  explicit AtomicDirectory(std::filesystem::path dir, bool replace = false);
  ~AtomicDirectory();

  AtomicDirectory(const AtomicDirectory&) = delete;
  AtomicDirectory& operator=(const AtomicDirectory&) = delete;

  /// Where to write the outputs until commit().
  const std::filesystem::path& path() const { return temp_path_; }
  /// The final directory.
  const std::filesystem::path& final_path() const { return dir_; }

  /// Renames the temporary directory onto DIR. An existing DIR is replaced only
  /// when `replace` was passed, else UserError "DIR: already exists ...".
  void commit();

 private:
  std::filesystem::path dir_;
  std::filesystem::path temp_path_;
  bool replace_;
  bool active_ = true;
};

}  // namespace driftlab
