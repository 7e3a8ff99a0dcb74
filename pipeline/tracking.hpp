// Where a VO lost track (guard counters reported, not just counted): every frame on which a
// VO gave no motion, by reason ("too few PnP inliers", "motion estimate not finite", ...),
// and the stretches of consecutive such frames with their time and place on the true track.
// metrics.json algorithms.VO.tracking, the report's "Tracking" table, a warning for long
// stretches, and a per-frame `lost` column whose section mean marks the sections affected.
#pragma once

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "record/run_record.hpp"

#include "core/time.hpp"
#include "core/trajectory_io.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::pipeline {

/// Consecutive frames without a motion estimate.
struct LostStretch {
  std::size_t first = 0, last = 0;  ///< frame indices, inclusive
  TimeNs t_start_ns = 0, t_end_ns = 0;
  double track_m = 0;  ///< distance along the true camera track where it starts
  std::string reason;  ///< the first frame's reason
  std::size_t frames() const { return last - first + 1; }
};

struct TrackingSummary {
  std::size_t frames = 0;   ///< frames the camera delivered after the VO's first
  std::size_t lost = 0;     ///< of those, frames without a motion estimate
  std::size_t dropped = 0;  ///< frames the camera dropped (no image: not the VO's doing)
  std::map<std::string, std::size_t> reasons;  ///< lost frames by reason
  std::vector<LostStretch> stretches;          ///< in time order
  record::TrackingRecord tracking_record() const;
  /// The longest stretch, or nullptr when the VO never lost track.
  const LostStretch* longest() const;
};

/// The reason of a frame the camera dropped (no image: the VO never saw it).
inline constexpr const char* kFrameDropped = "frame dropped";
inline bool dropped_frame(const vo::VoResult& r) { return r.reason == kFrameDropped; }

/// Whether frame `r` counts as lost: invalid for a reason of the VO's, not the camera's
/// (a dropped frame) nor the start (the first frame has nothing to match).
bool lost_track(const vo::VoResult& r);

/// The summary of a VO's per-frame results (one per true camera pose, `camera_gt`).
TrackingSummary summarize_tracking(const std::vector<vo::VoResult>& results,
                                   const Trajectory& camera_gt);

/// A warning when a stretch lasted `min_s` seconds or more; empty otherwise.
std::string tracking_warning(const std::string& vo_name, const TrackingSummary& s,
                             double min_s = 1.0);

/// The report's table: one row per VO, frames lost, the longest stretch, the top reasons.
std::string tracking_table_markdown(const std::vector<std::string>& names,
                                    const std::vector<TrackingSummary>& summaries);

}  // namespace driftlab::pipeline
