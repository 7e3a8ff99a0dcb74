// Whole-track errors: the river paper's Table 2 (RMSE, Eq. (14), and maximum
// of the 3D and 2D position error, in metres and % of track length, with N,
// and the track-length over/under-estimate) and the basin paper's table
// (RMSE and SD of N, E, surge u, sway v and heading against the reference).
#pragma once

#include <string>
#include <vector>

#include "core/se3.hpp"
#include "core/time.hpp"
#include "eval/stats.hpp"

namespace driftlab::eval {

/// Path length of a sequence of positions [m].
double path_length_m(const std::vector<SE3>& poses);

/// Indices of the poses where the ground truth has moved at least `spacing_m` along its path
/// since the previous index; the first and the last pose are always in. spacing_m = 0 takes
/// every pose.
std::vector<std::size_t> length_sample_indices(const std::vector<SE3>& gt, double spacing_m);

/// Path length through the poses at `indices` only [m].
double path_length_m(const std::vector<SE3>& poses, const std::vector<std::size_t>& indices);

struct TrackErrors {
  std::size_t n = 0;
  double length_gt_m = 0;
  double length_est_m = 0;
  double length_error_pct = 0;  // (estimate - truth) / truth * 100: > 0 over-estimates
  double rmse_3d_m = 0, max_3d_m = 0, rmse_2d_m = 0, max_2d_m = 0;
  double rmse_3d_pct = 0, max_3d_pct = 0, rmse_2d_pct = 0, max_2d_pct = 0;
  std::vector<double> err_3d_m;  // per pose, Eq. (12) on absolute positions
};

/// Errors of aligned estimate positions against truth (same length, associated).
/// 2D is the horizontal (north, east) part in the world NED frame. Both lengths are taken
/// through the same poses, one every `length_sample_m` of ground-truth travel
/// (length_sample_indices): summed frame by frame, an estimate's pose noise adds length that
/// grows with the frame rate, not with any error of the track's shape or scale.
TrackErrors track_errors(const std::vector<SE3>& gt, const std::vector<SE3>& est_aligned,
                         double length_sample_m);

/// Basin paper table (Kucic and Valcic 2020, Tables 2-3): per quantity, the
/// summary of the error (estimate minus reference; heading wrapped), whose
/// `rmse` and `sd_sample` are the paper's RMSE and std.
struct BasinTable {
  Summary north_m, east_m, surge_m_s, sway_m_s, heading_deg;
};

/// Planar navigation states (N, E, u, v, psi) from a trajectory of body (FRD)
/// or camera (optical) poses. Heading is the direction of the frame's forward
/// axis (body x, or the optical axis) projected on the horizontal plane; u
/// and v are the horizontal velocity, by central differences (one-sided at the
/// ends), along and across that heading.
struct PlanarStates {
  std::vector<double> north_m, east_m, surge_m_s, sway_m_s, heading_rad;
};
PlanarStates planar_states(const std::vector<TimeNs>& t_ns, const std::vector<SE3>& T_W_X,
                           bool x_is_camera_optical);

BasinTable basin_table(const PlanarStates& reference, const PlanarStates& estimate);

/// A reference of planar states at times of its own (the basin's overhead camera): a quantity
/// it could not measure at a time is NaN there.
struct PlanarReference {
  std::vector<TimeNs> t_ns;  ///< sorted
  PlanarStates states;
};

/// The basin table of `estimate` (at the sorted times `t_ns`) against `reference`: each
/// reference time is paired with the nearest estimate within `tolerance_ns`, and each quantity
/// counts the pairs where the reference has it. `pairs`: the paired times.
BasinTable basin_table(const PlanarReference& reference, const std::vector<TimeNs>& t_ns,
                       const PlanarStates& estimate, TimeNs tolerance_ns, std::size_t* pairs);

}  // namespace driftlab::eval
