#include "pipeline/run_record.hpp"

#include <cmath>

namespace driftlab::pipeline {

std::optional<double> ape_trans_rmse_m(const AlgorithmRecord& a) {
  const double v = a.evaluation.ape.trans_m.rmse;
  if (a.evaluation.association.pairs == 0 || !std::isfinite(v)) return std::nullopt;
  return v;
}

record::VsRawVoRecord vs_raw_vo(const std::string& raw_vo, double filtered, double raw) {
  record::VsRawVoRecord v;
  v.raw_vo = raw_vo;
  v.filtered = filtered;
  v.raw = raw;
  v.ratio = raw > 0 ? filtered / raw : 0.0;
  v.better = filtered < raw;
  return v;
}

void TrackRecords::add_to(record::RunRecord* out) const {
  for (const auto& [name, a] : algorithms) out->algorithms[name] = a;
  record::TimingRecord& t = out->timing;
  for (const auto& [name, v] : vo_timing) {
    if (!t.vo_ms_per_frame) t.vo_ms_per_frame.emplace();
    (*t.vo_ms_per_frame)[name] = v.ms_per_frame;
    if (!v.sparse_pairs) continue;
    if (!t.sparse_pairs) t.sparse_pairs.emplace();
    (*t.sparse_pairs)[name] = *v.sparse_pairs;
  }
}

void OverheadRecord::add_to(record::RunRecord* out) const {
  out->overhead = record::OverheadRecord{frames, tracked, plane_z_m, reference_file, frame_file};
  // Wall-clock figures live under timing, the one block that differs between two runs.
  out->timing.overhead_render_s = render_s;
  out->timing.overhead_track_s = track_s;
}

void VisionRecord::add_to(record::RunRecord* out) const {
  out->timing.threads = threads;
  out->timing.render_s = render_s;
  out->timing.render_pairs_per_s = render_pairs_per_s;
  out->camera = camera;
  out->frame_cache =
      record::FrameCacheRecord{frame_cache.state, frame_cache.entry, frame_cache.note};
  out->render = record::RenderRecord{render_context, assets, triangles};
  tracks.add_to(out);
  if (!external_vo.empty()) out->external_vo = external_vo;
  if (overhead) overhead->add_to(out);
  out->warnings = warnings;
}

}  // namespace driftlab::pipeline
