// The estimate streams of a run, shared by a scenario run (run.cpp) and a run on a dataset
// (dataset_run.cpp): a VO, a filter following one (fusion::Filter through FilterTrack), the
// constant-acceleration smoother's backward pass, or an external VO; how each advances frame
// by frame, and what is reported about the filters.
#pragma once

#include <cstddef>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/time.hpp"
#include "core/trajectory_io.hpp"
#include "fusion/ca_smoother.hpp"
#include "pipeline/filter_stage.hpp"
#include "pipeline/run_record.hpp"
#include "pipeline/scenario.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::pipeline {

/// One estimate stream: a VO, or a filter following one, or an external VO.
struct Track {
  std::string name;
  std::unique_ptr<vo::StereoOdometry> vo;
  std::unique_ptr<FilterTrack> filter;  // NAME_ca, NAME_ned_kf, NAME_ned_pf, NAME_eskf streams
  std::size_t source = 0;               // for a filter or smoother: the VO track it follows
  bool external = false;                // an external VO's estimate (pipeline.external_vo)
  Trajectory estimate;
  std::vector<vo::VoResult> results;  // per frame; a dropped frame's is invalid
  double vo_ms = 0;
};

/// The name of filter `kind`'s stream following VO `vo`: NAME_ca for the smoother, else
/// NAME_<fusion name> (sparse_eskf).
std::string filter_track_name(const std::string& vo, FusionAlgorithm kind);

/// For each fusion algorithm in `fusion`, one track per VO track among the first `n_vo` of
/// `tracks`, following it; `make` builds the filter of one algorithm.
void add_filter_tracks(const std::vector<FusionAlgorithm>& fusion, std::size_t n_vo,
                       const std::function<std::unique_ptr<FilterTrack>(FusionAlgorithm)>& make,
                       std::vector<Track>* tracks);

/// Every VO track's result on `frame`, by track index (other tracks' entries are left
/// default). With `threads` >= 2 the VOs run side by side on up to `threads` workers, the
/// calling thread one of them, the slowest so far (`vo_ms`) first and each worker taking the
/// next when its VO is done: a VO's result depends only on its own state and the frame, so the
/// results are the same as in turn. After a VO throws no worker takes another; its exception
/// reaches the caller after those running are done.
std::vector<vo::VoResult> process_vos(std::vector<Track>* tracks, const vo::StereoFrame& frame,
                                      int threads);

/// One frame of a track (frame index `k`): a VO's result is kept; a smoother or filter starts
/// at the first delivered frame and then adds a pose (a filter's absolute pose; otherwise the
/// increment, river paper Eq. (3)).
void advance_track(Track* track, std::size_t k, bool first, TimeNs t, const vo::VoResult& r);

/// Whether pipeline.fusion has the constant-acceleration smoother with its backward pass on.
bool runs_backward_pass(const PipelineOptions& pipeline);

/// The constant-acceleration smoother with its backward pass (NAME_ca_rts) over VO track
/// `track` (index `source`), anchored where the VO's estimate starts. `delivered[k]`: the stamp
/// of frame k when the VO saw it (from the first delivered frame on), nullopt otherwise.
Track rts_smoothed(const Track& track, std::size_t source,
                   const std::vector<std::optional<TimeNs>>& delivered,
                   const fusion::CaSmootherOptions& options);

/// estimates/NAME.tum for every track, and estimates/NAME.csv for the NED filters' states.
void write_estimates(const std::vector<Track>& tracks, const std::filesystem::path& dir);

/// What each filter and smoother did (algorithms.NAME.filter: measurements fused, skipped,
/// gated; non-finite guards), and a warning for every guard that fired.
void report_filter_counts(const std::vector<Track>& tracks, TrackRecords* records,
                          std::vector<std::string>* warnings);

/// Each filter's estimate against its raw VO's, by APE translation RMSE (the same evaluation,
/// the same frames): `vs_raw_vo` in the filter's metrics, a report table, and a warning for each
/// filter that is worse than the VO it filters, so that a filter that does not help says so.
std::string compare_filters_with_raw_vo(const std::vector<Track>& tracks, TrackRecords* records,
                                        std::vector<std::string>* warnings);

}  // namespace driftlab::pipeline
