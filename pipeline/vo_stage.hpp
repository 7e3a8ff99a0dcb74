// The VO stage's pieces that a scenario run and a run on a dataset share: the VOs by name
// and their per-frame record in frames.csv.
#pragma once

#include <memory>
#include <string>

#include "core/camera.hpp"
#include "core/rng.hpp"
#include "pipeline/scenario.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::pipeline {

/// The VO `name` (built-in, or registered: vo/registry.hpp) on `rig`, a built-in one with its
/// options from `pipeline`, each with its own random stream ("vo.<name>") of `rng`. UserError
/// for an unknown name.
std::unique_ptr<vo::StereoOdometry> make_vo(const std::string& name, const StereoRig& rig,
                                            const PipelineOptions& pipeline, const RngStreams& rng);

/// frames.csv columns of one VO: ",NAME_valid,NAME_inliers,NAME_valid_depth_px,
/// NAME_mean_depth_m,NAME_ref_frames,NAME_ms".
std::string vo_csv_header(const std::string& name);
/// The cells of one result under those columns (each with its leading comma).
std::string vo_csv_cells(const vo::VoResult& result);

}  // namespace driftlab::pipeline
