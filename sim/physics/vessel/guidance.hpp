// Missions and guidance: a mission is a list of segments (legs followed by
// line-of-sight guidance, turns in place, a tow run); the guidance turns the
// vessel state into thruster commands with a heading PID and a speed PI.
// Guidance sees the true state: it stands in for the vessel's own autopilot,
// which is not under test.
#pragma once

#include <string>
#include <vector>

#include "sim/physics/vessel/vessel_model.hpp"

namespace driftlab::sim {

struct MissionSegment {
  enum class Kind { kLeg, kTurn, kTow };
  Kind kind = Kind::kLeg;
  Vec2 from = Vec2::Zero();  // north, east [m] (legs and tow)
  Vec2 to = Vec2::Zero();
  double speed_mps = 0;
  double heading_rad = 0;  // target heading (turns)
};

/// Geometry of the world the mission is planned in.
struct MissionContext {
  double river_width_m = 20.0;
  double river_centre_east_m = 0.0;  // driftlab's rivers run north along this line
  double survey_leg_length_m = 100.0;
};

/// Plans the segments of `mission` for a vessel starting at `start` (north,
/// east) with heading `start_heading_rad`. Throws UserError for impossible
/// missions (fewer than 2 waypoints, zero length).
std::vector<MissionSegment> plan_mission(const MissionOptions& mission, const Vec2& start,
                                         double start_heading_rad, const MissionContext& context);

/// Total path length of the planned legs [m] (turns add none).
double planned_length_m(const std::vector<MissionSegment>& segments);

class Guidance {
 public:
  Guidance(const VesselModel& model, std::vector<MissionSegment> segments,
           const MissionOptions& mission);

  /// Commands for the next physics step of length dt_s, from the state at t_s.
  VesselInputs update(const VesselState& state, double t_s, double dt_s);

  bool done() const { return index_ >= segments_.size(); }
  std::size_t segment_index() const { return index_; }
  const std::vector<MissionSegment>& segments() const { return segments_; }
  /// Signed cross-track error of the current leg [m] (positive: starboard of the path).
  double cross_track_error_m() const { return cross_track_m_; }
  double desired_heading_rad() const { return heading_d_; }

 private:
  void next_segment(const VesselState& state, double t_s);

  const VesselModel& model_;
  std::vector<MissionSegment> segments_;
  MissionOptions mission_;
  std::size_t index_ = 0;
  double heading_integral_ = 0;
  double speed_integral_ = 0;
  double cross_track_m_ = 0;
  double heading_d_ = 0;
  double segment_start_s_ = 0;
  Vec3 tow_start_W_ = Vec3::Zero();
  bool tow_started_ = false;
};

}  // namespace driftlab::sim
