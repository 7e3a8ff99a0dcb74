#include "sim/physics/vessel/guidance.hpp"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numbers>

#include "core/error.hpp"
#include "core/rotation.hpp"

namespace driftlab::sim {
namespace {

double heading_of(const Vec2& d) { return std::atan2(d.y(), d.x()); }

Vec2 dir(double heading) { return Vec2(std::cos(heading), std::sin(heading)); }

// Adds a turn to the heading of the next leg, then the leg.
void add_leg(std::vector<MissionSegment>* out, const Vec2& from, const Vec2& to, double speed) {
  const Vec2 d = to - from;
  if (d.norm() < 1e-9) return;
  MissionSegment turn;
  turn.kind = MissionSegment::Kind::kTurn;
  turn.heading_rad = heading_of(d);
  out->push_back(turn);
  MissionSegment leg;
  leg.kind = MissionSegment::Kind::kLeg;
  leg.from = from;
  leg.to = to;
  leg.speed_mps = speed;
  leg.heading_rad = heading_of(d);
  out->push_back(leg);
}

}  // namespace

std::vector<MissionSegment> plan_mission(const MissionOptions& m, const Vec2& start,
                                         double start_heading, const MissionContext& ctx) {
  std::vector<MissionSegment> out;
  switch (m.type) {
    case MissionType::kStraight:
      add_leg(&out, start, start + m.survey_length_m * dir(start_heading), m.speed_mps);
      break;
    case MissionType::kTransects: {
      // Rivers run north-south in driftlab's scenes: crossings go east, then west, ...
      // The first turn brings the vessel into position (river paper Section 3.1).
      Vec2 p = start;
      for (int i = 0; i < m.crossings; ++i) {
        const Vec2 q = p + Vec2(0, (i % 2 == 0 ? 1.0 : -1.0) * m.crossing_width_m);
        add_leg(&out, p, q, m.speed_mps);
        p = q;
      }
      break;
    }
    case MissionType::kSurvey: {
      // Lawnmower along the river: legs north and south on two lanes a quarter
      // of the width from the banks, joined by crossings, until the planned
      // length is reached. The first lane is the one on the start's side of
      // the centre line; a start off it joins it along the first leg.
      const double offset = 0.25 * ctx.river_width_m;
      const double leg =
          m.survey_leg_length_m > 0 ? m.survey_leg_length_m : ctx.survey_leg_length_m;
      const double side = start.y() > ctx.river_centre_east_m ? 1.0 : -1.0;
      Vec2 p = start;
      double lane = ctx.river_centre_east_m + side * offset;
      double remaining = m.survey_length_m;
      for (int i = 0; remaining > 1e-9; ++i) {
        const bool along = i % 2 == 0;
        if (!along) lane = 2 * ctx.river_centre_east_m - lane;  // the other lane
        const double north = along ? ((i / 2) % 2 == 0 ? 1.0 : -1.0) * leg : 0.0;
        Vec2 q(p.x() + north, lane);
        const double len = (q - p).norm();
        if (len > remaining) q = p + (q - p) * (remaining / len);
        add_leg(&out, p, q, m.speed_mps);
        remaining -= std::min(len, remaining);
        p = q;
      }
      break;
    }
    case MissionType::kTow: {
      MissionSegment tow;
      tow.kind = MissionSegment::Kind::kTow;
      tow.from = start;
      tow.to = start + m.survey_length_m * dir(start_heading);
      tow.speed_mps = m.speed_mps;
      tow.heading_rad = start_heading;
      out.push_back(tow);
      break;
    }
    case MissionType::kSpin: {
      const int turns = 4;
      for (int i = 1; i <= turns; ++i) {
        MissionSegment turn;
        turn.kind = MissionSegment::Kind::kTurn;
        turn.heading_rad = wrap_angle_rad(start_heading + i * std::numbers::pi / 2);
        out.push_back(turn);
      }
      break;
    }
    case MissionType::kWaypoints: {
      const auto& w = m.waypoints_ne_m;
      if (w.size() < 2)
        throw UserError(
            fmt::format("mission.waypoints_ne_m: got {} waypoints, expected at least 2", w.size()));
      Vec2 p = start;
      for (const auto& q : w) {
        add_leg(&out, p, Vec2(q[0], q[1]), m.speed_mps);
        p = Vec2(q[0], q[1]);
      }
      break;
    }
  }
  if (out.empty()) throw UserError("mission: the planned mission has no segments (zero length)");
  return out;
}

double planned_length_m(const std::vector<MissionSegment>& segments) {
  double s = 0;
  for (const auto& g : segments)
    if (g.kind != MissionSegment::Kind::kTurn) s += (g.to - g.from).norm();
  return s;
}

Guidance::Guidance(const VesselModel& model, std::vector<MissionSegment> segments,
                   const MissionOptions& mission)
    : model_(model), segments_(std::move(segments)), mission_(mission) {}

void Guidance::next_segment(const VesselState&, double t_s) {
  ++index_;
  heading_integral_ = 0;
  segment_start_s_ = t_s;
  tow_started_ = false;
}

VesselInputs Guidance::update(const VesselState& s, double t, double dt) {
  VesselInputs in;
  if (done()) return in;
  const auto& c = model_.options().control;
  const auto& o = model_.options();
  const EulerZYX e = euler_zyx_from_quat(s.q_W_B);
  const double r = s.w_B.z();
  const double u = s.v_B.x();
  MissionSegment& seg = segments_[index_];
  double speed_d = 0;

  switch (seg.kind) {
    case MissionSegment::Kind::kTurn: {
      heading_d_ = seg.heading_rad;
      if (std::abs(wrap_angle_rad(heading_d_ - e.yaw_rad)) < deg2rad(c.turn_tolerance_deg) &&
          std::abs(r) < 0.05) {
        next_segment(s, t);
        return update(s, t, dt);
      }
      break;
    }
    case MissionSegment::Kind::kLeg: {
      // Line-of-sight guidance (Fossen 2011, Section 10.3.2): aim at a point
      // `lookahead` ahead along the path.
      const Vec2 d = seg.to - seg.from;
      const double len = d.norm();
      const Vec2 t_hat = d / len;
      const Vec2 rel = s.p_W.head<2>() - seg.from;
      const double along = rel.dot(t_hat);
      cross_track_m_ = -rel.x() * t_hat.y() + rel.y() * t_hat.x();
      if (along >= len) {
        next_segment(s, t);
        return update(s, t, dt);
      }
      heading_d_ = std::atan2(t_hat.y(), t_hat.x()) - std::atan(cross_track_m_ / c.lookahead_m);
      const auto& weave = mission_.yaw_weave;
      if (weave.amplitude_deg > 0)
        heading_d_ +=
            deg2rad(weave.amplitude_deg) * std::sin(2 * std::numbers::pi * t / weave.period_s);
      speed_d = seg.speed_mps;
      break;
    }
    case MissionSegment::Kind::kTow: {
      if (!tow_started_) {
        // The carriage starts where the rope is just taut, ahead of the bow.
        const Vec3 attach_W = s.p_W + s.q_W_B * model_.tow_point_B();
        const Vec3 ahead(std::cos(seg.heading_rad), std::sin(seg.heading_rad), 0);
        tow_start_W_ = attach_W + o.tow.rope_length_m * ahead;
        tow_start_W_.z() = attach_W.z();
        tow_started_ = true;
        segment_start_s_ = t;
      }
      const double travelled = seg.speed_mps * (t - segment_start_s_);
      if (travelled >= (seg.to - seg.from).norm()) {
        next_segment(s, t);
        return update(s, t, dt);
      }
      in.tow_active = true;
      const Vec3 v(std::cos(seg.heading_rad), std::sin(seg.heading_rad), 0);
      in.tow_carriage_velocity_W = seg.speed_mps * v;
      // Carriage position at time 0 such that it is at tow_start at segment start.
      in.tow_carriage_W = tow_start_W_ - segment_start_s_ * in.tow_carriage_velocity_W;
      return in;
    }
  }

  // Heading PID -> yaw moment; speed PI with drag feedforward -> surge force.
  const double err = wrap_angle_rad(heading_d_ - e.yaw_rad);
  heading_integral_ = std::clamp(heading_integral_ + err * dt, -1.0, 1.0);
  const double N = c.heading_kp * err + c.heading_ki * heading_integral_ - c.heading_kd * r;
  const double d1 = o.linear_damping[0], d2 = o.quadratic_damping[0];
  const double ev = speed_d - u;
  speed_integral_ = std::clamp(speed_integral_ + ev * dt, -2.0, 2.0);
  const double X = d1 * speed_d + d2 * speed_d * std::abs(speed_d) + c.speed_kp * ev +
                   c.speed_ki * speed_integral_;
  const double y = o.thrusters.lateral_offset_m;
  // Allocation with yaw priority: limit the moment to what both thrusters can
  // give around the surge force, so that saturation never turns a pure turn
  // into a surge.
  const double fwd = o.thrusters.max_thrust_n;
  const double rev = o.thrusters.reverse_fraction * fwd;
  const double Xc = std::clamp(X, -2 * rev, 2 * fwd);
  const double n_lim = 2 * y * std::max(0.0, std::min(fwd - Xc / 2, rev + Xc / 2));
  const double Nc = std::clamp(N, -n_lim, n_lim);
  // Port thrust turns the bow to starboard (positive yaw in FRD).
  in.thrust_command_n = {Xc / 2 + Nc / (2 * y), Xc / 2 - Nc / (2 * y)};
  return in;
}

}  // namespace driftlab::sim
