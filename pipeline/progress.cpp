#include "pipeline/progress.hpp"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace driftlab::pipeline {

namespace {
std::string clock_text(double s) {
  if (!std::isfinite(s) || s < 0) return "--:--";
  const auto t = static_cast<long long>(std::llround(s));
  if (t >= 3600) return fmt::format("{}:{:02}:{:02}", t / 3600, (t / 60) % 60, t % 60);
  return fmt::format("{}:{:02}", t / 60, t % 60);
}
}  // namespace

Progress::Progress(std::FILE* out, std::string what, std::size_t total, bool tty,
                   double line_every_s)
    : out_(out),
      what_(std::move(what)),
      total_(total),
      tty_(tty),
      every_s_(line_every_s),
      start_(Clock::now()),
      last_(start_) {}

std::string Progress::line(const std::string& what, std::size_t done, std::size_t total,
                           double elapsed_s, bool bar) {
  const double rate = elapsed_s > 0 ? static_cast<double>(done) / elapsed_s : 0.0;
  const double eta = rate > 0 ? static_cast<double>(total - std::min(done, total)) / rate : NAN;
  std::string s = what + "  ";
  if (bar) {
    constexpr int kWidth = 24;
    const int filled = total > 0
                           ? static_cast<int>(kWidth * static_cast<double>(std::min(done, total)) /
                                              static_cast<double>(total))
                           : kWidth;
    s += "[" + std::string(static_cast<std::size_t>(filled), '#') +
         std::string(static_cast<std::size_t>(kWidth - filled), ' ') + "]  ";
  }
  s += fmt::format("{}/{} frames  {:.1f}/s  elapsed {}  ETA {}", done, total, rate,
                   clock_text(elapsed_s), done >= total ? "0:00" : clock_text(eta));
  return s;
}

void Progress::update(std::size_t done) {
  done_ = done;
  if (out_ == nullptr) return;
  const auto now = Clock::now();
  const double since = std::chrono::duration<double>(now - last_).count();
  if (printed_ && since < (tty_ ? 0.2 : every_s_)) return;  // the first update always shows
  printed_ = true;
  last_ = now;
  const double elapsed = std::chrono::duration<double>(now - start_).count();
  if (tty_)
    std::fprintf(out_, "\r%s\033[K", line(what_, done, total_, elapsed, true).c_str());
  else
    std::fprintf(out_, "%s\n", line(what_, done, total_, elapsed, false).c_str());
  std::fflush(out_);
}

void Progress::finish() {
  if (out_ == nullptr || finished_) return;
  finished_ = true;
  const double elapsed = std::chrono::duration<double>(Clock::now() - start_).count();
  if (tty_)
    std::fprintf(out_, "\r%s\033[K\n", line(what_, done_, total_, elapsed, true).c_str());
  else
    std::fprintf(out_, "%s\n", line(what_, done_, total_, elapsed, false).c_str());
  std::fflush(out_);
}

}  // namespace driftlab::pipeline
