#include "pipeline/dataset_run.hpp"

#include <fmt/format.h>

#include <limits>
#include <nlohmann/json.hpp>

#include "core/atomic_file.hpp"
#include "core/rng.hpp"
#include "core/stopwatch.hpp"
#include "eval/evaluate.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/vo_stage.hpp"

#ifndef DRIFTLAB_VERSION
#define DRIFTLAB_VERSION "unknown"
#endif

namespace driftlab::pipeline {
namespace fs = std::filesystem;

namespace {

struct VoTrack {
  std::string name;
  std::unique_ptr<vo::StereoOdometry> vo;
  Trajectory estimate;
  std::vector<vo::VoResult> results;
  double vo_ms = 0;
};

// The first frame with a true pose (all of them start there), and that pose.
std::pair<std::size_t, SE3> first_anchored(const dataset::StereoDataset& d) {
  if (d.camera_gt.empty()) return {0, SE3()};
  for (std::size_t i = 0; i < d.frames.size(); ++i)
    if (const auto T = dataset::pose_at(d.camera_gt, d.frames[i].t_ns)) return {i, *T};
  throw UserError(
      fmt::format("{}: no frame lies within the ground truth's time span", d.root.string()));
}

eval::FrameTable covariates(const VoTrack& t, const std::vector<dataset::DatasetFrame>& frames) {
  eval::FrameTable ft;
  ft.names = {"inliers", "mean_depth_m"};
  ft.columns.resize(2);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t k = 0; k < t.results.size(); ++k) {
    const vo::VoResult& r = t.results[k];
    ft.t_ns.push_back(frames[k].t_ns);
    // Covariate f as the VO counts its features (river paper Table 4).
    ft.columns[0].push_back(r.valid ? r.feature_count() : nan);
    ft.columns[1].push_back(r.valid ? r.mean_inlier_depth_m : nan);
  }
  return ft;
}

}  // namespace

std::string DatasetRunSummary::brief() const {
  std::string s = fmt::format("{} stereo frames in {:.2f} s", frames, total_s);
  for (const auto& a : algorithms) s += "\n  " + a;
  return s;
}

DatasetRunSummary run_on_dataset(const dataset::StereoDataset& d, const Scenario& settings,
                                 const fs::path& out_dir, const DatasetRunOptions& options) {
  const auto t0 = SteadyClock::now();
  AtomicDirectory dir(out_dir, options.replace_existing);
  write_file_atomic(dir.path() / "scenario.resolved.yaml", resolved_yaml(settings));
  const RngStreams rng(settings.seed);
  std::vector<VoTrack> tracks;
  for (const std::string& a :
       options.algorithms.empty() ? settings.pipeline.vo : options.algorithms)
    tracks.push_back({a, make_vo(a, d.rig, settings.pipeline, rng), {}, {}, 0});
  if (tracks.empty()) throw UserError("driftlab vo: no VO to run (--algo or pipeline.vo)");
  const auto [first, T_W_C0] = first_anchored(d);
  std::size_t end = d.frames.size();
  if (options.max_frames > 0) end = std::min(end, first + options.max_frames);

  AtomicFile frames_csv(dir.path() / "frames.csv");
  std::string header = "t_ns";
  for (const auto& t : tracks) header += vo_csv_header(t.name);
  frames_csv.write(header + "\n");
  std::vector<dataset::DatasetFrame> used(d.frames.begin() + first, d.frames.begin() + end);
  Progress progress(options.progress, "vo", used.size(), options.progress_tty);
  for (std::size_t k = 0; k < used.size(); ++k) {
    progress.update(k);
    auto [left, right] = dataset::read_pair(d, used[k]);  // rectified when raw
    vo::StereoFrame frame{used[k].t_ns, left, right};
    std::string row = std::to_string(frame.t_ns);
    for (auto& t : tracks) {
      const vo::VoResult r = t.vo->process(frame);
      row += vo_csv_cells(r);
      t.vo_ms += r.times.total_ms;
      t.results.push_back(r);
      if (k == 0) {
        t.estimate.push_back({frame.t_ns, T_W_C0});
        continue;
      }
      const SE3 step = r.valid ? r.T_prev_curr : SE3();
      t.estimate.push_back({frame.t_ns, t.estimate.back().T_W_C * step});  // river paper Eq. (3)
    }
    frames_csv.write(row + "\n");
  }
  progress.update(used.size());
  progress.finish();
  frames_csv.commit();

  fs::create_directories(dir.path() / "estimates");
  if (!d.camera_gt.empty()) write_tum(dir.path() / "groundtruth.tum", d.camera_gt);
  nlohmann::json metrics;
  metrics["version"] = DRIFTLAB_VERSION;
  metrics["seed"] = settings.seed;
  metrics["dataset"] = {{"root", d.root.string()},
                        {"format", dataset::format_name(d.format)},
                        {"frames_used", used.size()},
                        {"first_frame", first},
                        {"ground_truth", !d.camera_gt.empty()},
                        {"fx_px", d.rig.camera.fx},
                        {"baseline_m", d.rig.baseline_m},
                        {"width_px", d.rig.camera.width},
                        {"height_px", d.rig.camera.height}};
  std::string tables, sections;
  DatasetRunSummary summary;
  summary.frames = used.size();
  for (const auto& t : tracks) {
    write_tum(dir.path() / "estimates" / (t.name + ".tum"), t.estimate);
    metrics["timing"]["vo_ms_per_frame"][t.name] =
        used.empty() ? 0.0 : t.vo_ms / static_cast<double>(used.size());
    if (d.camera_gt.empty()) {
      summary.algorithms.push_back(t.name + ": no ground truth, estimate only");
      continue;
    }
    eval::EvaluationInput in;
    in.gt = d.camera_gt;
    in.est = t.estimate;
    in.gt_label = "groundtruth.tum";
    in.est_label = "estimates/" + t.name + ".tum";
    in.algorithm = t.name;
    in.options = settings.eval;
    in.frames = covariates(t, used);
    const eval::Evaluation e = eval::evaluate(in);
    metrics["algorithms"][t.name] = eval::to_json(e, settings.eval);
    tables += eval::tables_markdown(e, settings.eval) + "\n";
    const std::string csv = eval::sections_csv(e);
    sections += sections.empty() ? csv : csv.substr(csv.find('\n') + 1);
    summary.algorithms.push_back(e.brief());
  }
  if (!sections.empty()) write_file_atomic(dir.path() / "sections.csv", sections);
  write_file_atomic(dir.path() / "tables.md",
                    fmt::format("# driftlab vo: {}\n\n{}", d.root.string(), tables));
  summary.total_s = seconds_since(t0);
  metrics["timing"]["total_s"] = summary.total_s;
  write_file_atomic(dir.path() / "metrics.json", metrics.dump(2) + "\n");
  dir.commit();
  return summary;
}

}  // namespace driftlab::pipeline
