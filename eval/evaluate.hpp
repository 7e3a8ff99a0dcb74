// One evaluation of an estimated trajectory against ground truth: association,
// alignment, APE/RPE, KITTI segments, the river paper's Tables 1-4 and the
// basin paper's table. Returns everything in one Evaluation (a summary object
// in the style of Ceres' Solver::Summary); writers turn it into
// metrics.json, sections.csv and tables.md.
#pragma once

#include <nlohmann/json.hpp>

#include <optional>
#include <string>
#include <vector>

#include "core/trajectory_io.hpp"
#include "eval/align.hpp"
#include "eval/ape_rpe.hpp"
#include "eval/association.hpp"
#include "eval/eval_options.hpp"
#include "eval/evaluation_record.hpp"
#include "eval/kitti_segments.hpp"
#include "eval/paper_attitude.hpp"
#include "eval/regression.hpp"
#include "eval/sections.hpp"
#include "eval/track.hpp"

namespace driftlab::eval {

struct EvaluationInput {
  Trajectory gt;
  Trajectory est;
  std::string gt_label = "ground truth";
  std::string est_label = "estimate";
  std::string algorithm = "estimate";  // name in tables and sections.csv
  std::optional<FrameTable> frames;    // per-frame covariates (frames.csv)
  EvalOptions options;
  /// A second reference for the basin paper's table (the basin's overhead camera), with the
  /// name its table goes by.
  std::optional<PlanarReference> basin_reference;
  std::string basin_reference_name = "overhead camera";
  /// The attitude reference the river paper compared the VO's angles with (its x-IMU), for
  /// Table 1's angle rows as the paper computed them.
  std::optional<AttitudeReference> attitude_reference;
};

struct SubtrackEvaluation {
  std::string name;
  TrackErrors track;
};

struct Evaluation {
  std::string algorithm;
  Association association;
  std::size_t gt_poses = 0, est_poses = 0;
  SimilarityTransform alignment;
  ApeResult ape;
  RpeResult rpe;
  TrackErrors track;
  std::vector<SubtrackEvaluation> subtracks;
  std::vector<Section> sections;
  SectionSummary section_summary;
  // Sections holding frames where the VO lost track (a `lost` column in the frame table,
  // section mean > 0), and Table 1 over the other sections; both empty without the column.
  std::vector<std::size_t> lost_track_sections;  // Section::index of each
  std::optional<SectionSummary> tracked_summary;
  std::vector<std::pair<std::string, Summary>> covariates;  // Table 4
  std::optional<OlsResult> regression;                      // Table 3
  std::string regression_skipped;                           // why, when not run
  BasinTable basin;
  /// The basin paper's table against `EvaluationInput::basin_reference`, when given.
  std::optional<BasinTable> basin_reference;
  std::string basin_reference_name;
  std::size_t basin_reference_pairs = 0;
  std::vector<KittiSegmentResult> kitti;
  /// Table 1's angle rows and Section 3.1's maxima against `EvaluationInput::attitude_reference`.
  std::optional<PaperAttitude> paper_attitude;
  std::vector<std::string> warnings;

  /// One paragraph: pairs, APE RMSE, sections, regression R^2.
  std::string brief() const;
};

/// Runs every metric. Throws UserError for input that cannot be evaluated
/// (unsorted stamps, no overlap, too few poses to align); conditions that
/// only invalidate one table (too few sections for the regression, collinear
/// covariates) are recorded in `regression_skipped` / `warnings` instead.
Evaluation evaluate(const EvaluationInput& input);

/// The evaluation as metrics.json reports it; its warnings name each number that is not
/// finite (written as null).
EvaluationRecord evaluation_record(const Evaluation& e, const EvalOptions& options);

/// metrics.json content: evaluation_record() written. Never contains NaN or Inf (such a value
/// becomes null and a warning names it).
nlohmann::json to_json(const Evaluation& e, const EvalOptions& options);

/// sections.csv: one row per section with errors, per-metre errors and covariates.
std::string sections_csv(const Evaluation& e);

/// tables.md: the papers' tables formatted like the papers.
std::string tables_markdown(const Evaluation& e, const EvalOptions& options);

}  // namespace driftlab::eval
