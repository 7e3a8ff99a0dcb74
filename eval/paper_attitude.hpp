// The river paper's attitude errors as the paper computed them (Kriechbaumer et al. 2015,
// Section 2.4, Eq. (11)): eps_n = n_IMU - n_VO for each Euler angle n, where n_IMU are the
// angles an AHRS (the x-IMU) reported in its own frame and n_VO the VO's angles in its first
// camera's frame, with no alignment between the two frames. Over each 6.5 m section the change
// of eps, divided by the section's length, is Table 1's e'_roll, e'_pitch and e'_yaw; along the
// whole track, eps's largest excursion from its start is Section 3.1's maximum error.
//
// The exact errors (sections.hpp) compare the VO's relative rotation with the true one in the
// same camera axes. These do not: a camera tilted against the AHRS's level turns part of every
// yaw change into apparent pitch and roll, and the AHRS's own errors enter as they are.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "core/rotation.hpp"
#include "core/se3.hpp"
#include "core/time.hpp"
#include "eval/sections.hpp"
#include "eval/stats.hpp"

namespace driftlab::eval {

/// An attitude reference: stamped ZYX Euler angles of its own frame (ahrs.csv of a run).
struct AttitudeReference {
  std::vector<TimeNs> t_ns;  // strictly increasing
  std::vector<EulerZYX> euler;
};

/// An AHRS's angles from a CSV with a header (read_frame_table()): a time column and columns
/// roll_deg, pitch_deg and yaw_deg (a run's ahrs.csv). Throws UserError naming the file and the
/// missing column, or the row and column of a missing or non-finite angle.
AttitudeReference read_attitude_reference(const std::string& path);

struct PaperAttitude {
  Summary roll_deg_per_m, pitch_deg_per_m, yaw_deg_per_m;  // over the sections with both ends
  EulerZYX max_abs_rad;   // largest |eps(t) - eps(t_0)| along the track, each angle on its own
  std::size_t pairs = 0;  // estimate poses with a reference sample within the tolerance
};

/// Eq. (11) against `reference`, its nearest sample to each estimate stamp within
/// `tolerance_ns`. n_VO: ZYX angles of the estimate's pose relative to its first pose, in
/// camera FRD axes (x optical, y right, z down), as in the exact errors. `sections` index into
/// `t_ns` / `T_W_C_est` (compute_sections()). Angles wrap into (-180, 180] deg.
PaperAttitude paper_attitude(const std::vector<TimeNs>& t_ns, const std::vector<SE3>& T_W_C_est,
                             const std::vector<Section>& sections,
                             const AttitudeReference& reference, TimeNs tolerance_ns);

}  // namespace driftlab::eval
