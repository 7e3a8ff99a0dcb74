// Progress of a long stage on stderr: a bar redrawn in place on a terminal, plain periodic
// lines otherwise (CI logs, files), with frames, rate and estimated time left.
#pragma once

#include <chrono>
#include <cstddef>
#include <cstdio>
#include <string>

namespace driftlab::pipeline {

class Progress {
 public:
  /// `out` null: silent. `tty`: redraw in place at most 5 times a second; else a line every
  /// `line_every_s` seconds and at the end.
  Progress(std::FILE* out, std::string what, std::size_t total, bool tty,
           double line_every_s = 10.0);
  /// `done` items of `total` finished.
  void update(std::size_t done);
  /// Final line (the bar's last state, newline-terminated).
  void finish();

  /// The text of one update, e.g. "render+vo  [#####     ]  50/100 frames  12.3/s  ETA 0:04".
  static std::string line(const std::string& what, std::size_t done, std::size_t total,
                          double elapsed_s, bool bar);

 private:
  using Clock = std::chrono::steady_clock;
  std::FILE* out_;
  std::string what_;
  std::size_t total_;
  bool tty_;
  double every_s_;
  Clock::time_point start_, last_;
  std::size_t done_ = 0;
  bool finished_ = false;
  bool printed_ = false;
};

}  // namespace driftlab::pipeline
