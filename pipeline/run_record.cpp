#include "pipeline/run_record.hpp"

namespace driftlab::pipeline {

std::optional<double> AlgorithmRecord::ape_trans_rmse_m() const {
  const nlohmann::json::json_pointer at("/ape/trans_m/rmse");
  if (!evaluation.contains(at) || !evaluation.at(at).is_number()) return std::nullopt;
  return evaluation.at(at).get<double>();
}

void TrackRecords::add_to(nlohmann::json* metrics) const {
  nlohmann::json& m = *metrics;
  for (const auto& [name, a] : algorithms) {
    nlohmann::json j = a.evaluation;
    if (a.tracking) j["tracking"] = *a.tracking;
    if (a.filter) j["filter"] = *a.filter;
    if (a.vs_raw_vo) {
      const VsRawVo& v = *a.vs_raw_vo;
      j["vs_raw_vo"] = {{"raw_vo", v.raw_vo},     {"metric", "ape.trans_m.rmse"},
                        {"filtered", v.filtered}, {"raw", v.raw},
                        {"ratio", v.ratio()},     {"better", v.better()}};
    }
    m["algorithms"][name] = std::move(j);
  }
  for (const auto& [name, t] : vo_timing) {
    m["timing"]["vo_ms_per_frame"][name] = t.ms_per_frame;
    if (t.sparse_pairs)
      m["timing"]["sparse_pairs"][name] = {{"detected", t.sparse_pairs->detected},
                                           {"shared", t.sparse_pairs->shared}};
  }
}

void OverheadRecord::add_to(nlohmann::json* metrics) const {
  nlohmann::json& m = *metrics;
  m["overhead"] = {{"frames", frames},
                   {"tracked", tracked},
                   {"plane_z_m", plane_z_m},
                   {"reference", reference_file},
                   {"frame", frame_file}};
  // Wall-clock figures live under timing, the one block that differs between two runs.
  m["timing"]["overhead_render_s"] = render_s;
  m["timing"]["overhead_track_s"] = track_s;
}

void VisionRecord::add_to(nlohmann::json* metrics) const {
  nlohmann::json& m = *metrics;
  m["timing"]["threads"] = threads;
  m["timing"]["render_s"] = render_s;
  m["timing"]["render_pairs_per_s"] = render_pairs_per_s;
  m["camera"] = {{"frames_delivered", camera.frames_delivered},
                 {"frames_dropped", camera.frames_dropped},
                 {"noise", camera.noise},
                 {"vignetting_strength", camera.vignetting_strength},
                 {"motion_blur_samples", camera.motion_blur_samples},
                 {"motion_blur_step_px", camera.motion_blur_step_px},
                 {"lens_distortion", camera.lens_distortion},
                 {"clock_offset_ms", camera.clock_offset_ms},
                 {"shutter", camera.shutter},
                 {"line_delay_us", camera.line_delay_us},
                 {"right_offset_ms", camera.right_offset_ms},
                 {"right_offset_jitter_ms", camera.right_offset_jitter_ms}};
  m["frame_cache"] = {
      {"state", frame_cache.state}, {"entry", frame_cache.entry}, {"note", frame_cache.note}};
  m["render"] = {{"context", render_context}, {"assets", assets}, {"triangles", triangles}};
  tracks.add_to(metrics);
  for (const auto& [name, record] : external_vo) m["external_vo"][name] = record;
  if (overhead) overhead->add_to(metrics);
  m["warnings"] = warnings;
}

}  // namespace driftlab::pipeline
