// Section errors and covariates of the river paper (Kriechbaumer et al. 2015,
// Section 2.4, Eqs. (10)-(13)): the ground-truth path is cut into consecutive
// sections of `section_length_m`; at each section start the estimate is
// re-anchored to the truth, and at its end the translation, Euler-angle and 3D
// position errors are divided by the section length.
//
// Axes of the errors: the paper uses the sensor frame. We express them in the
// camera's frame at the section start with FRD axes (x along the optical axis,
// y right, z down), so that Euler ZYX gives roll about the optical axis, pitch
// about the right axis and yaw about the down axis.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "core/rotation.hpp"
#include "core/se3.hpp"
#include "core/time.hpp"
#include "eval/stats.hpp"

namespace driftlab::eval {

/// Per-frame covariates: a time column and named numeric columns (frames.csv
/// of a run, or any CSV a user provides).
struct FrameTable {
  std::vector<TimeNs> t_ns;
  std::vector<std::string> names;
  std::vector<std::vector<double>> columns;  // columns[k][i] is row i of names[k]

  /// The column called `name`, or nullptr.
  const std::vector<double>* column(std::string_view name) const;
};

/// Reads a CSV with a header line. The time column is `t_ns` (integer
/// nanoseconds) or `t` / `t_s` (decimal seconds); every other column must be
/// numeric (empty cells and `nan` are read as missing). Throws UserError
/// naming file, line and column on bad input.
FrameTable read_frame_table(const std::string& path);

/// The VOs whose per-frame columns a run's frames.csv holds (`driftlab run`, `driftlab vo`):
/// NAME for each `NAME_valid` column, in order. Empty for a table that is not a run's, i.e.
/// one with a plain `inliers`, `valid_depth_px` or `mean_depth_m` column.
std::vector<std::string> run_vo_names(const FrameTable& table);

/// Which of a run's VOs the estimate called `algorithm` came from: the VO of that name, else
/// the longest VO name that `algorithm` starts with, followed by '_' (a filter on that VO:
/// `sparse_kf_ca` is `sparse_kf`'s). Empty when none.
std::string run_vo_of(const std::vector<std::string>& vos, const std::string& algorithm);

/// From a run's frames.csv, the covariates the run's own evaluation of VO `vo` used: the
/// platform's `yaw_deg`, `pitch_deg`, `roll_deg`; the VO's `NAME_features` as `inliers`
/// (covariate f), `NAME_mean_depth_m` as `mean_depth_m` (d), both missing where the VO gave no
/// motion (`NAME_valid` 0), `NAME_lost` as `lost`, and the scene's `moving_px` (the share of
/// the image showing moving things, a covariate of every VO). The run's other columns (render and
/// camera timings, the other VOs) are left out, as in the run's evaluation. For a frames.csv
/// written before `NAME_features` existed, f is `NAME_valid_depth_px` where that
/// is positive (the dense VO), else `NAME_inliers`. Throws UserError naming `path` and the VOs
/// present when `vo` is not one of them.
FrameTable run_vo_covariates(const FrameTable& run_frames, const std::string& vo,
                             const std::string& path);

struct SectionOptions {
  double section_length_m = 6.5;
};

/// One section: where it is, its errors (Eqs. 10-12) and its covariates (Eq. 13).
struct Section {
  std::size_t index = 0;
  std::size_t first = 0;  // index of the first pose (the anchor) in the pose lists
  std::size_t last = 0;   // index of the end pose
  TimeNs t_start_ns = 0;
  TimeNs t_end_ns = 0;
  double length_m = 0;        // ground-truth path length of the section
  Vec3 err_m = Vec3::Zero();  // Eq. (10): truth minus estimate, start-camera FRD axes [m]
  double err_p_m = 0;         // Eq. (12)
  EulerZYX err_rad;           // Eq. (11): truth minus estimate, wrapped [rad]
  // Covariates, in this order: v, h, then the others. Missing values are NaN
  // internally and never reach a report (sections lacking a covariate are
  // left out of a regression that uses it).
  std::vector<std::string> covariate_names;
  std::vector<double> covariates;

  double per_m(double e) const { return e / length_m; }
  /// The covariate called `name`, or NaN when absent.
  double covariate(std::string_view name) const;
};

/// Cuts the associated poses (same length, same times) into sections and
/// computes errors and covariates. `frames` may be null. Covariates:
///   v [m/s]  section mean speed (ground-truth path length over time)
///   h [deg]  sample SD of the unwrapped platform yaw: the `yaw_deg` column of
///            `frames` if present, else the yaw of the ground-truth camera
///   pitch_sd_deg, roll_sd_deg   likewise (`pitch_deg`, `roll_deg` columns)
///   f        section mean of `inliers` (sparse VO), else of `valid_depth_px` (dense VO)
///   d [m]    section mean of `mean_depth_m`
///   every other numeric column of `frames`: its section mean, under its own name
/// A trailing part shorter than a section is not a section.
std::vector<Section> compute_sections(const std::vector<TimeNs>& t_ns,
                                      const std::vector<SE3>& T_W_C_gt,
                                      const std::vector<SE3>& T_W_C_est,
                                      const SectionOptions& options,
                                      const FrameTable* frames = nullptr);

/// Table 1 of the river paper: summaries of the per-metre errors.
struct SectionSummary {
  Summary p_m_per_m, x_m_per_m, y_m_per_m, z_m_per_m;
  Summary roll_deg_per_m, pitch_deg_per_m, yaw_deg_per_m;
};
SectionSummary summarize_sections(const std::vector<Section>& sections);

/// Table 4 of the river paper: the distribution of one covariate over the
/// sections that have it.
Summary summarize_covariate(const std::vector<Section>& sections, std::string_view name);

/// Rotation taking vectors in the camera's FRD axes (x optical axis, y right,
/// z down) into the OpenCV optical frame.
Mat3 R_optical_frd();

}  // namespace driftlab::eval
