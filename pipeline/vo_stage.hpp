// The VO stage's pieces that a scenario run and a run on a dataset share: the VOs by name
// and their per-frame record in frames.csv.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "pipeline/run_record.hpp"
#include "pipeline/scenario.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::pipeline {

/// The VOs `names` (built-in, or registered: vo/registry.hpp) on `rig`, in that order, the
/// built-in ones with their options from `pipeline`, each with its own random stream
/// ("vo.<name>") of `rng`. `sparse` and `sparse_kf` share their feature detection when their
/// detection options agree (the shipped ones do): the same results, one detection a frame.
/// UserError for an unknown name.
std::vector<std::unique_ptr<vo::StereoOdometry>> make_vos(const std::vector<std::string>& names,
                                                          const StereoRig& rig,
                                                          const PipelineOptions& pipeline,
                                                          const RngStreams& rng);

/// The cost of one VO (metrics.json timing.vo_ms_per_frame.NAME) and, for a sparse VO, the
/// pairs it detected itself and those it took from the VO it shares detection with
/// (timing.sparse_pairs.NAME; which of the two detects a pair depends on the threads' timing;
/// the two add up to the frames it processed).
VoTiming vo_timing(const vo::StereoOdometry& vo, double ms_per_frame);

/// frames.csv columns of one VO: ",NAME_valid,NAME_inliers,NAME_valid_depth_px,
/// NAME_mean_depth_m,NAME_ref_frames,NAME_features,NAME_lost,NAME_ms". `_features` is the
/// river paper's covariate f as the VO counts it (VoResult::feature_count(), empty where the VO
/// gave no motion), `_lost` 1 where it lost track (lost_track()): with `_mean_depth_m` the
/// columns that `driftlab eval --covariates` reads back (eval::run_vo_covariates()).
std::string vo_csv_header(const std::string& name);
/// The cells of one result under those columns (each with its leading comma).
std::string vo_csv_cells(const vo::VoResult& result);

}  // namespace driftlab::pipeline
