#include "app/paper_command.hpp"

#include <fmt/format.h>

#include <array>
#include <filesystem>
#include <iostream>
#include <optional>

#include "app/cli_main.hpp"
#include "core/atomic_file.hpp"
#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "eval/evaluate.hpp"
#include "gate/gate.hpp"
#include "pipeline/run.hpp"
#include "pipeline/scenario.hpp"
#include "record/run_record.hpp"
#include "report/basin_paper_compare.hpp"
#include "report/paper_compare.hpp"

namespace driftlab::app {
namespace {

namespace fs = std::filesystem;

// --prism X,Y,Z as the scenario's eval.reference_point_m reads it (its checks, its message).
std::array<double, 3> prism_point(const std::string& text) {
  eval::EvalOptions o;
  as_usage_error("", [&] {
    yaml::read_into(yaml::override_document("reference_point_m=[" + text + "]"),
                    {"--prism " + text, false}, &o);
  });
  return o.reference_point_m;
}

// The run's river-paper VOs evaluated again with the truth at `prism`, as the run evaluated
// them (its eval options and its frames.csv covariates), added to `metrics` as
// algorithms."NAME (prism)".
void add_prism_columns(const fs::path& run_dir, const std::array<double, 3>& prism,
                       record::RunRecord* metrics) {
  const pipeline::Scenario sc = pipeline::load_scenario(run_dir / "scenario.resolved.yaml");
  const Trajectory gt = read_trajectory(run_dir / "groundtruth.tum", TrajectoryFormat::kTum);
  const fs::path frames_path = run_dir / "frames.csv";
  const eval::FrameTable frames = eval::read_frame_table(frames_path.string());
  for (const char* a : {"sparse", "sparse_kf", "dense"}) {
    if (!metrics->algorithms.count(a)) continue;
    eval::EvaluationInput in;
    in.gt = gt;
    in.est =
        read_trajectory(run_dir / "estimates" / (std::string(a) + ".tum"), TrajectoryFormat::kTum);
    in.algorithm = a;
    in.options = sc.eval;
    in.options.reference_point_m = prism;
    in.frames = eval::run_vo_covariates(frames, a, frames_path.string());
    metrics->algorithms[std::string(a) + " (prism)"].evaluation =
        eval::evaluation_record(eval::evaluate(in), in.options);
  }
}

// kRiverPrismFrd in the optical frame of the run's left camera, through its mount.
std::array<double, 3> river_prism_from_camera(const fs::path& run_dir) {
  const pipeline::Scenario sc = pipeline::load_scenario(run_dir / "scenario.resolved.yaml");
  const Vec3 p_B(kRiverPrismFrd[0], kRiverPrismFrd[1], kRiverPrismFrd[2]);
  const Vec3 p_C = pipeline::camera_mount_T_B_C(sc.sensors.camera.mount).inverse() * p_B;
  return {p_C.x(), p_C.y(), p_C.z()};
}

}  // namespace

int paper_command(const std::vector<std::string>& runs, const std::string& track_name,
                  const std::string& prism, const std::string& out) {
  std::vector<record::RunRecord> all;
  std::vector<fs::path> files;
  for (const std::string& r : runs) {
    files.push_back(gate::find_results_metrics(r));
    all.push_back(record::read_run_record(files.back()));
  }
  if (report::basin_paper_experiment_of(all.front().scenario.value_or(""))) {
    if (!track_name.empty()) throw UsageError("--track: the basin paper has no tracks to choose");
    write_or_print(report::basin_paper_side_by_side(all), out);
    return kExitOk;
  }
  if (runs.size() != 1)
    throw UsageError(fmt::format(
        "got {} runs: the river paper's tables take one run (several only for basin runs)",
        runs.size()));
  std::optional<report::RiverPaperTrack> track;
  if (track_name == "discharge") track = report::RiverPaperTrack::kDischarge;
  if (track_name == "total") track = report::RiverPaperTrack::kTotal;
  if (!track_name.empty() && !track)
    throw UsageError(fmt::format("--track: got '{}', expected discharge or total", track_name));
  record::RunRecord& metrics = all.front();
  const std::string scenario = metrics.scenario.value_or("");
  if (!track) track = report::river_paper_track_of(scenario);
  if (!track)
    throw UsageError(fmt::format(
        "{}: scenario '{}' is not a twin of the river paper (river_crossing, river_survey); "
        "say which row of its Table 2 to compare with: --track discharge|total",
        runs.front(), scenario));
  // A run already measured at a prism (eval.reference_point_m) has no camera columns to add to.
  const auto sparse = metrics.algorithms.find("sparse");
  const bool at_camera =
      sparse == metrics.algorithms.end() ||
      sparse->second.evaluation.association.reference_point_m == std::array<double, 3>{0, 0, 0};
  const fs::path dir = files.front().parent_path();
  if (prism != "none" && at_camera) {
    const std::optional<std::array<double, 3>> given =
        prism.empty() ? std::nullopt : std::optional(prism_point(prism));
    std::string missing;
    for (const char* f : {"scenario.resolved.yaml", "groundtruth.tum", "frames.csv"})
      if (!fs::exists(dir / f)) missing += (missing.empty() ? "" : ", ") + std::string(f);
    if (missing.empty())
      add_prism_columns(dir, given ? *given : river_prism_from_camera(dir), &metrics);
    else
      std::cerr << fmt::format(
          "warning: no columns at the prism: {} lacks {} (the run's files that the twin is "
          "measured again from); --prism none leaves them out without this warning\n",
          dir.string(), missing);
  }
  write_or_print(report::river_paper_side_by_side(metrics, *track), out);
  return kExitOk;
}

}  // namespace driftlab::app
