#include "pipeline/tracking.hpp"

#include <fmt/format.h>

#include <algorithm>

namespace driftlab::pipeline {
namespace {
constexpr const char* kFirstFrame = "first frame";

double seconds(TimeNs ns) { return static_cast<double>(ns) * 1e-9; }
}  // namespace

bool lost_track(const vo::VoResult& r) {
  return !r.valid && r.reason != kFirstFrame && !dropped_frame(r);
}

const LostStretch* TrackingSummary::longest() const {
  const auto it = std::max_element(
      stretches.begin(), stretches.end(),
      [](const LostStretch& a, const LostStretch& b) { return a.frames() < b.frames(); });
  return it == stretches.end() ? nullptr : &*it;
}

TrackingSummary summarize_tracking(const std::vector<vo::VoResult>& results,
                                   const Trajectory& camera_gt) {
  TrackingSummary s;
  double track_m = 0;
  bool started = false;
  for (std::size_t k = 0; k < results.size() && k < camera_gt.size(); ++k) {
    if (k > 0)
      track_m += (camera_gt[k].T_W_C.translation() - camera_gt[k - 1].T_W_C.translation()).norm();
    const vo::VoResult& r = results[k];
    if (dropped_frame(r)) {
      ++s.dropped;
      continue;
    }
    if (!started) {  // the VO's first frame: nothing to match yet
      started = true;
      continue;
    }
    ++s.frames;
    if (!lost_track(r)) continue;
    ++s.lost;
    ++s.reasons[r.reason];
    if (!s.stretches.empty() && s.stretches.back().last + 1 == k) {
      s.stretches.back().last = k;
      s.stretches.back().t_end_ns = camera_gt[k].t_ns;
    } else {
      s.stretches.push_back({k, k, camera_gt[k].t_ns, camera_gt[k].t_ns, track_m, r.reason});
    }
  }
  return s;
}

record::TrackingRecord TrackingSummary::tracking_record() const {
  record::TrackingRecord r;
  r.frames = frames;
  r.lost_frames = lost;
  r.lost_fraction = frames ? static_cast<double>(lost) / static_cast<double>(frames) : 0.0;
  r.dropped_frames = dropped;
  r.reasons = reasons;
  for (const LostStretch& l : stretches)
    r.stretches.push_back(
        {l.first, l.frames(), seconds(l.t_start_ns), seconds(l.t_end_ns), l.track_m, l.reason});
  const LostStretch* worst = longest();
  r.longest_stretch_frames = worst ? worst->frames() : 0;
  return r;
}

std::string tracking_warning(const std::string& vo_name, const TrackingSummary& s, double min_s) {
  const LostStretch* worst = s.longest();
  if (!worst || seconds(worst->t_end_ns - worst->t_start_ns) < min_s) return "";
  return fmt::format(
      "{} lost track for {} frames ({:.1f} s) from t = {:.1f} s, {:.1f} m along the track: {} "
      "(each such frame adds no motion; {} frames lost in {} stretches, see tracking in "
      "metrics.json and the sections' `lost` column)",
      vo_name, worst->frames(), seconds(worst->t_end_ns - worst->t_start_ns),
      seconds(worst->t_start_ns), worst->track_m, worst->reason, s.lost, s.stretches.size());
}

std::string tracking_table_markdown(const std::vector<std::string>& names,
                                    const std::vector<TrackingSummary>& summaries) {
  std::string out =
      "### Tracking\n\nFrames on which each VO gave no motion (the estimate stands still), "
      "and why.\n\n| VO | frames | lost | stretches | longest | where | main reason |\n"
      "|---|---|---|---|---|---|---|\n";
  for (std::size_t i = 0; i < names.size(); ++i) {
    const TrackingSummary& s = summaries[i];
    const LostStretch* worst = s.longest();
    std::string main_reason = "-";
    std::size_t most = 0;
    for (const auto& [reason, n] : s.reasons)
      if (n > most) {
        most = n;
        main_reason = fmt::format("{} ({})", reason, n);
      }
    out += fmt::format(
        "| {} | {} | {} ({:.1f} %) | {} | {} | {} | {} |\n", names[i], s.frames, s.lost,
        s.frames ? 100.0 * static_cast<double>(s.lost) / static_cast<double>(s.frames) : 0.0,
        s.stretches.size(), worst ? std::to_string(worst->frames()) : "-",
        worst ? fmt::format("t {:.1f} s, {:.1f} m", seconds(worst->t_start_ns), worst->track_m)
              : "-",
        main_reason);
  }
  return out + "\n";
}

}  // namespace driftlab::pipeline
