#include "pipeline/vo_stage.hpp"

#include <fmt/format.h>

#include "core/error.hpp"
#include "core/yaml_io.hpp"
#include "vo/dense/dense_vo.hpp"
#include "vo/pnp/pnp_vo.hpp"
#include "vo/registry.hpp"
#include "vo/sparse/sparse_vo.hpp"

namespace driftlab::pipeline {

std::unique_ptr<vo::StereoOdometry> make_vo(const std::string& name, const StereoRig& rig,
                                            const PipelineOptions& p, const RngStreams& rng) {
  Rng stream = rng.stream("vo." + name);
  if (name == "sparse") return std::make_unique<vo::SparseStereoOdometry>(rig, p.sparse, stream);
  if (name == "sparse_kf")
    return std::make_unique<vo::SparseStereoOdometry>(rig, p.sparse_kf, stream);
  if (name == "pnp") return std::make_unique<vo::PnpStereoOdometry>(rig, p.pnp, stream);
  if (name == "dense") return std::make_unique<vo::DenseStereoOdometry>(rig, p.dense, stream);
  if (auto v = vo::make_registered_vo(name, rig, stream, p.plugins)) return v;
  std::string names;
  for (const auto& n : vo::available_vo_names()) names += (names.empty() ? "" : ", ") + n;
  throw UserError(fmt::format("pipeline.vo: got '{}', expected one of: {}", name, names));
}

std::string vo_csv_header(const std::string& name) {
  return fmt::format(
      ",{0}_valid,{0}_inliers,{0}_valid_depth_px,{0}_mean_depth_m,{0}_ref_frames,{0}_ms", name);
}

std::string vo_csv_cells(const vo::VoResult& r) {
  return fmt::format(",{},{},{},{},{},{:.3f}", r.valid ? 1 : 0, r.inliers, r.valid_depth_pixels,
                     r.valid ? yaml::format_double(r.mean_inlier_depth_m) : "",
                     r.reference_frames_back, r.times.total_ms);
}

}  // namespace driftlab::pipeline
