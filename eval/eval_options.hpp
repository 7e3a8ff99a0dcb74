// Options of the evaluation (scenario section `eval`).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/yaml_io.hpp"

namespace driftlab::eval {

enum class Alignment { kHorn, kSe3, kSim3, kPosYaw, kNone };
constexpr auto enum_table(Alignment) {
  return std::array{std::pair{Alignment::kHorn, "horn"}, std::pair{Alignment::kSe3, "se3"},
                    std::pair{Alignment::kSim3, "sim3"}, std::pair{Alignment::kPosYaw, "posyaw"},
                    std::pair{Alignment::kNone, "none"}};
}

enum class RpeUnit { kFrames, kMeters };
constexpr auto enum_table(RpeUnit) {
  return std::array{std::pair{RpeUnit::kFrames, "frames"}, std::pair{RpeUnit::kMeters, "meters"}};
}

/// A named time window evaluated as a track of its own (e.g. the river
/// paper's discharge measurement within the survey).
struct SubtrackOptions {
  std::string name = "subtrack";
  double start_s = 0.0;
  double end_s = 0.0;

  template <class A>
  void visit(A& a) {
    a("name", name, "Name of the sub-track in tables", yaml::non_empty());
    a("start_s", start_s, "Start time [s]", yaml::non_negative());
    a("end_s", end_s, "End time [s]", yaml::non_negative());
    a.require(end_s > start_s, "end_s", "end_s > start_s");
  }
};

struct EvalOptions {
  double section_length_m = 6.5;
  double length_sample_m = 0.5;
  Alignment align = Alignment::kNone;
  int align_first_n = 0;
  double association_tolerance_s = 0.02;
  std::vector<std::string> regression_covariates{"v", "h", "f", "d"};
  double rpe_delta = 1.0;
  RpeUnit rpe_unit = RpeUnit::kFrames;
  std::vector<double> kitti_lengths_m{100, 200, 300, 400, 500, 600, 700, 800};
  std::vector<SubtrackOptions> subtracks;
  std::array<double, 3> reference_point_m{0.0, 0.0, 0.0};

  template <class A>
  void visit(A& a) {
    a("section_length_m", section_length_m, "Length of the sections of river paper Section 2.4 [m]",
      yaml::positive());
    a("length_sample_m", length_sample_m,
      "Track lengths (truth and estimate) are measured through the poses one every this many "
      "metres of true travel; 0 sums every frame, which counts an estimate's pose noise as "
      "length (ours: 0.5 m, well above the per-frame noise, well below a turn) [m]",
      yaml::in_range(0.0, 1000.0));
    a("align", align,
      "Alignment of estimate to ground truth before ATE. none: every estimate of driftlab run "
      "starts at the true first pose, so there is nothing to align; a rigid fit never turns "
      "the estimate about a nearly straight track's axis (see docs/evaluation.md)");
    a("align_first_n", align_first_n, "Align on the first N poses only (0 = whole track)",
      yaml::non_negative());
    a("association_tolerance_s", association_tolerance_s,
      "Largest time difference when pairing estimate and ground-truth poses [s]",
      yaml::non_negative());
    a("regression_covariates", regression_covariates,
      "Covariates of the section-error regression, river paper Eq. (13)", yaml::min_size(1));
    a("rpe_delta", rpe_delta, "RPE step, in rpe_unit", yaml::positive());
    a("rpe_unit", rpe_unit, "Unit of rpe_delta (as evo_rpe --delta_unit f|m)");
    a("kitti_lengths_m", kitti_lengths_m, "Segment lengths of the KITTI odometry metric [m]",
      yaml::positive());
    a("subtracks", subtracks, "Named time windows evaluated as tracks of their own (Table 2)");
    a("reference_point_m", reference_point_m,
      "Where the reference track is measured, from the camera in the ground truth's camera "
      "frame (OpenCV optical: x right, y down, z forward) [m]. [0, 0, 0]: the camera itself, "
      "exact. Otherwise the truth's positions move to that point while the estimate stays the "
      "camera's, as when a total station tracks a prism elsewhere on the vessel and nothing "
      "corrects for the lever arm (the river paper's ground truth, Sec. 2.1): turns then show "
      "up as position errors of about the lever arm times the change of heading",
      yaml::in_range(-100, 100));
  }
};

}  // namespace driftlab::eval
