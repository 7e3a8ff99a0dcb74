// The sensor CSV writers' shared parts (internal to sim/sensors): number
// formatting and the rows of a stamped file. Numbers:
// integers exactly, doubles as the shortest text that reads back to the same
// value (std::to_chars), so that files are exact and byte-reproducible.
#pragma once

#include <charconv>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

#include "core/atomic_file.hpp"
#include "core/time.hpp"

namespace driftlab::sim::csv_detail {

inline void append_int(std::string* out, std::int64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out->append(buf, r.ptr);
}

/// ",VALUE"; a non-finite value is written "nan" (a missing fix, say), which
/// NumPy and pandas read as NaN.
inline void append_double(std::string* out, double v) {
  *out += ',';
  if (!std::isfinite(v)) {
    *out += "nan";
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  out->append(buf, r.ptr);
}

/// The rows of one sensor's CSV file: a header, then one row per sample with
/// strictly increasing stamps (InternalError otherwise, naming `sensor`).
/// Nothing appears at the path unless commit() is called (AtomicFile).
class StampedRows {
 public:
  StampedRows(const std::filesystem::path& path, std::string_view header, std::string sensor);
  /// Checks the stamp and starts a row with it; append the columns to the
  /// returned string, then call end_row().
  std::string* begin_row(TimeNs t_ns);
  void end_row();
  void commit() { file_.commit(); }

 private:
  AtomicFile file_;
  std::string sensor_;
  std::string line_;
  TimeNs last_ns_ = 0;
  bool any_ = false;
};

}  // namespace driftlab::sim::csv_detail
