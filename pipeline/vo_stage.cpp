#include "pipeline/vo_stage.hpp"

#include <fmt/format.h>

#include <algorithm>

#include "core/error.hpp"
#include "core/yaml_io.hpp"
#include "pipeline/tracking.hpp"
#include "vo/dense/dense_vo.hpp"
#include "vo/pnp/pnp_vo.hpp"
#include "vo/registry.hpp"
#include "vo/sparse/shared_detection.hpp"
#include "vo/sparse/sparse_vo.hpp"

namespace driftlab::pipeline {

namespace {

std::unique_ptr<vo::StereoOdometry> make_vo(
    const std::string& name, const StereoRig& rig, const PipelineOptions& p, const RngStreams& rng,
    const std::shared_ptr<vo::sparse::SharedDetection>& sparse_detection) {
  Rng stream = rng.stream("vo." + name);
  if (name == "sparse")
    return std::make_unique<vo::SparseStereoOdometry>(rig, p.sparse, stream, sparse_detection);
  if (name == "sparse_kf")
    return std::make_unique<vo::SparseStereoOdometry>(rig, p.sparse_kf, stream, sparse_detection);
  if (name == "pnp") return std::make_unique<vo::PnpStereoOdometry>(rig, p.pnp, stream);
  if (name == "dense") return std::make_unique<vo::DenseStereoOdometry>(rig, p.dense, stream);
  if (auto v = vo::make_registered_vo(name, rig, stream, p.plugins)) return v;
  std::string names;
  for (const auto& n : vo::available_vo_names()) names += (names.empty() ? "" : ", ") + n;
  throw UserError(fmt::format("pipeline.vo: got '{}', expected one of: {}", name, names));
}

}  // namespace

std::vector<std::unique_ptr<vo::StereoOdometry>> make_vos(const std::vector<std::string>& names,
                                                          const StereoRig& rig,
                                                          const PipelineOptions& p,
                                                          const RngStreams& rng) {
  std::shared_ptr<vo::sparse::SharedDetection> sparse_detection;
  const auto settings = vo::sparse::detection_settings(p.sparse);
  if (std::ranges::count(names, "sparse") > 0 && std::ranges::count(names, "sparse_kf") > 0 &&
      settings == vo::sparse::detection_settings(p.sparse_kf))
    sparse_detection = std::make_shared<vo::sparse::SharedDetection>(settings);
  std::vector<std::unique_ptr<vo::StereoOdometry>> vos;
  for (const std::string& name : names) vos.push_back(make_vo(name, rig, p, rng, sparse_detection));
  return vos;
}

VoTiming vo_timing(const vo::StereoOdometry& vo, double ms_per_frame) {
  VoTiming t;
  t.ms_per_frame = ms_per_frame;
  if (const auto* sparse = dynamic_cast<const vo::SparseStereoOdometry*>(&vo)) {
    const auto counts = sparse->detection_counts();
    t.sparse_pairs = record::SparsePairsRecord{counts.detected, counts.shared};
  }
  return t;
}

std::string vo_csv_header(const std::string& name) {
  return fmt::format(
      ",{0}_valid,{0}_inliers,{0}_valid_depth_px,{0}_mean_depth_m,{0}_ref_frames,{0}_features,"
      "{0}_lost,{0}_ms",
      name);
}

std::string vo_csv_cells(const vo::VoResult& r) {
  return fmt::format(
      ",{},{},{},{},{},{},{},{:.3f}", r.valid ? 1 : 0, r.inliers, r.valid_depth_pixels,
      r.valid ? yaml::format_double(r.mean_inlier_depth_m) : "", r.reference_frames_back,
      r.valid ? std::to_string(r.feature_count()) : "", lost_track(r) ? 1 : 0, r.times.total_ms);
}

}  // namespace driftlab::pipeline
