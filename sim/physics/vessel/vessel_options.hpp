// Options of the vessel and its mission (scenario sections `vessel` and `mission`).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/yaml_io.hpp"

namespace driftlab::sim {

enum class VesselPreset { kSurveyBoat, kBasinModel };
constexpr auto enum_table(VesselPreset) {
  return std::array{std::pair{VesselPreset::kSurveyBoat, "survey_boat"},
                    std::pair{VesselPreset::kBasinModel, "basin_model"}};
}

/// Box hull: the wetted surface that hydrostatic and wave pressure act on.
/// The body origin is the centre of gravity, at mid-length and mid-beam.
struct HullOptions {
  double length_m = 1.95;
  double beam_m = 0.73;
  double depth_m = 0.35;
  double kg_m = 0.15;
  int panels_along = 20;
  int panels_across = 8;

  template <class A>
  void visit(A& a) {
    a("length_m", length_m, "Hull length [m]",
      yaml::positive() & yaml::up_to(400, "longer than the largest ships"));
    a("beam_m", beam_m, "Hull beam [m]",
      yaml::positive() & yaml::up_to(70, "wider than the largest ships"));
    a("depth_m", depth_m, "Hull depth, keel to deck [m]",
      yaml::positive() & yaml::up_to(40, "deeper than the largest ships"));
    a("kg_m", kg_m, "Height of the centre of gravity above the keel [m]",
      yaml::non_negative() & yaml::up_to(40, "no hull is deeper"));
    a.require(kg_m < depth_m, "kg_m", "a centre of gravity below the deck (kg_m < depth_m)");
    a("panels_along", panels_along, "Pressure panels along the hull", yaml::in_range(2, 200));
    a("panels_across", panels_across, "Pressure panels across the hull", yaml::in_range(2, 200));
  }
};

/// Twin fixed thrusters at the stern, symmetric about the centre line.
struct ThrusterOptions {
  double x_m = -0.8;
  double lateral_offset_m = 0.25;
  double max_thrust_n = 25.0;
  double reverse_fraction = 0.6;
  double time_constant_s = 0.2;

  template <class A>
  void visit(A& a) {
    a("x_m", x_m, "Longitudinal position from the centre of gravity (bow positive) [m]");
    a("lateral_offset_m", lateral_offset_m, "Distance of each thruster from the centre line [m]",
      yaml::positive() & yaml::up_to(35, "no ship is wider than 70 m"));
    a("max_thrust_n", max_thrust_n, "Largest forward thrust of one thruster (0 = none) [N]",
      yaml::non_negative() & yaml::up_to(1e7, "more than the largest ship propellers"));
    a("reverse_fraction", reverse_fraction, "Largest reverse thrust as a fraction of forward",
      yaml::unit_interval());
    a("time_constant_s", time_constant_s, "First-order lag of the thrust response [s]",
      yaml::positive() & yaml::up_to(600, "a thruster that takes 10 minutes to respond"));
  }
};

/// Tow line from a point on the bow to a carriage moving at the mission speed.
struct TowOptions {
  double attach_x_m = 0.6;
  double rope_length_m = 1.0;
  double stiffness_n_m = 200.0;
  double damping_n_s_m = 20.0;

  template <class A>
  void visit(A& a) {
    a("attach_x_m", attach_x_m, "Tow point on the hull, from the centre of gravity [m]");
    a("rope_length_m", rope_length_m, "Unstretched rope length [m]",
      yaml::positive() & yaml::up_to(10000, "a 10 km tow line"));
    a("stiffness_n_m", stiffness_n_m, "Rope stiffness when taut [N/m]",
      yaml::positive() &
          yaml::up_to(1e10, "stiffer than a steel bar; the physics step cannot follow"));
    a("damping_n_s_m", damping_n_s_m, "Rope damping when taut [N s/m]", yaml::non_negative());
  }
};

/// Heading and speed controllers of the guidance.
struct ControlOptions {
  double heading_kp = 40.0;
  double heading_ki = 6.0;
  double heading_kd = 45.0;
  double speed_kp = 60.0;
  double speed_ki = 10.0;
  double lookahead_m = 4.0;
  double turn_tolerance_deg = 3.0;

  template <class A>
  void visit(A& a) {
    a("heading_kp", heading_kp, "Heading PID proportional gain [N m/rad]", yaml::non_negative());
    a("heading_ki", heading_ki, "Heading PID integral gain [N m/(rad s)]", yaml::non_negative());
    a("heading_kd", heading_kd, "Heading PID derivative gain [N m s/rad]", yaml::non_negative());
    a("speed_kp", speed_kp, "Speed PI proportional gain [N s/m]", yaml::non_negative());
    a("speed_ki", speed_ki, "Speed PI integral gain [N/m]", yaml::non_negative());
    a("lookahead_m", lookahead_m, "Line-of-sight lookahead distance [m]",
      yaml::positive() & yaml::up_to(10000, "a 10 km lookahead"));
    a("turn_tolerance_deg", turn_tolerance_deg,
      "A turn in place ends when the heading is this close [deg]", yaml::positive());
  }
};

struct VesselOptions {
  VesselPreset preset = VesselPreset::kSurveyBoat;
  std::array<double, 2> start_ne_m{0.0, 0.0};
  double start_heading_deg = 0.0;
  double physics_rate_hz = 400.0;
  double mass_kg = 55.0;
  std::array<double, 3> gyration_radii_m{0.30, 0.50, 0.50};
  std::array<double, 6> added_mass{2.75, 16.5, 55.0, 0.5, 11.0, 4.1};
  std::array<double, 6> linear_damping{5.0, 40.0, 248.0, 11.0, 66.0, 8.0};
  std::array<double, 6> quadratic_damping{15.0, 80.0, 0.0, 0.0, 0.0, 10.0};
  HullOptions hull;
  ThrusterOptions thrusters;
  TowOptions tow;
  ControlOptions control;

  /// The parameters of a preset (start pose and rate keep their defaults).
  static VesselOptions preset_defaults(VesselPreset preset);

  template <class A>
  void visit(A& a) {
    a("preset", preset,
      "Hull, mass and actuator preset; setting it resets the vessel parameters below to the "
      "preset's values (the defaults shown are survey_boat's)");
    a.when_reading([this] {
      if (preset != applied_preset_) {
        VesselOptions p = preset_defaults(preset);
        p.start_ne_m = start_ne_m;
        p.start_heading_deg = start_heading_deg;
        p.physics_rate_hz = physics_rate_hz;
        *this = p;
      }
    });
    a("start_ne_m", start_ne_m, "Initial position, north and east in the world NED frame [m]",
      yaml::plausible(-1e5, 1e5, "100 km from the world origin: float rendering loses precision"));
    a("start_heading_deg", start_heading_deg, "Initial heading (yaw), clockwise from north [deg]",
      yaml::in_range(-360, 360));
    a("physics_rate_hz", physics_rate_hz,
      "Fixed integration rate of the rigid-body physics (RK4) [Hz]", yaml::in_range(10, 10000));
    a("mass_kg", mass_kg, "Mass [kg]",
      yaml::positive() & yaml::up_to(1e9, "heavier than the largest ships"));
    a("gyration_radii_m", gyration_radii_m, "Radii of gyration about body x, y, z [m]",
      yaml::positive() & yaml::up_to(200, "no ship is larger"));
    a("added_mass", added_mass, "Diagonal added mass A11, A22, A33 [kg] and A44, A55, A66 [kg m^2]",
      yaml::non_negative());
    a("linear_damping", linear_damping,
      "Linear damping surge, sway, heave [N s/m], roll, pitch, yaw [N m s/rad]",
      yaml::non_negative());
    a("quadratic_damping", quadratic_damping,
      "Quadratic damping surge, sway, heave [N s^2/m^2], roll, pitch, yaw [N m s^2/rad^2]",
      yaml::non_negative());
    a("hull", hull, "Box hull for hydrostatics and wave pressure");
    a("thrusters", thrusters, "Twin stern thrusters");
    a("tow", tow, "Tow line (mission type: tow)");
    a("control", control, "Guidance controllers");
  }

 private:
  VesselPreset applied_preset_ = VesselPreset::kSurveyBoat;
};

inline VesselOptions VesselOptions::preset_defaults(VesselPreset preset) {
  VesselOptions o;  // survey_boat: a 1.95 m x 0.73 m river survey platform (ARC-Boat-like)
  if (preset == VesselPreset::kBasinModel) {
    // A towed 1.2 m ship model without propulsion (basin paper Section 2).
    o.mass_kg = 8.0;
    o.gyration_radii_m = {0.09, 0.30, 0.30};
    o.added_mass = {0.4, 4.0, 8.0, 0.0065, 0.58, 0.22};
    o.linear_damping = {2.0, 20.0, 35.0, 0.12, 2.0, 1.0};
    o.quadratic_damping = {4.0, 20.0, 0.0, 0.0, 0.0, 1.0};
    o.hull = {.length_m = 1.2,
              .beam_m = 0.25,
              .depth_m = 0.15,
              .kg_m = 0.06,
              .panels_along = 24,
              .panels_across = 6};
    o.thrusters.max_thrust_n = 0.0;
    o.control.lookahead_m = 1.0;
  }
  o.preset = preset;
  o.applied_preset_ = preset;
  return o;
}

enum class MissionType { kStraight, kTransects, kSurvey, kTow, kSpin, kWaypoints };
constexpr auto enum_table(MissionType) {
  return std::array{std::pair{MissionType::kStraight, "straight"},
                    std::pair{MissionType::kTransects, "transects"},
                    std::pair{MissionType::kSurvey, "survey"},
                    std::pair{MissionType::kTow, "tow"},
                    std::pair{MissionType::kSpin, "spin"},
                    std::pair{MissionType::kWaypoints, "waypoints"}};
}

struct YawWeaveOptions {
  double amplitude_deg = 0.0;
  double period_s = 10.0;

  template <class A>
  void visit(A& a) {
    a("amplitude_deg", amplitude_deg, "Amplitude of a sinusoidal heading weave [deg]",
      yaml::in_range(0, 90));
    a("period_s", period_s, "Period of the heading weave [s]",
      yaml::positive() & yaml::up_to(86400, "longer than any run"));
  }
};

struct MissionOptions {
  MissionType type = MissionType::kTransects;
  double speed_mps = 0.17;
  double duration_s = 0.0;
  int crossings = 4;
  double crossing_width_m = 13.5;
  double survey_length_m = 663.0;
  double survey_leg_length_m = 0.0;
  std::vector<std::array<double, 2>> waypoints_ne_m;
  std::string waypoints_file;
  YawWeaveOptions yaw_weave;

  template <class A>
  void visit(A& a) {
    a("type", type, "Mission pattern");
    a("speed_mps", speed_mps, "Commanded speed through the water [m/s]", yaml::in_range(0, 5));
    a("duration_s", duration_s,
      "Stop after this time; 0 runs until the mission pattern is complete [s]",
      yaml::non_negative() & yaml::up_to(86400, "a day of simulated time; longer than any survey"));
    a("crossings", crossings, "Number of river crossings (type: transects)",
      yaml::in_range(1, 1000));
    a("crossing_width_m", crossing_width_m, "Length of one crossing (type: transects) [m]",
      yaml::positive() & yaml::up_to(2000, "no river is wider"));
    a("survey_length_m", survey_length_m, "Track length (type: survey, straight, tow) [m]",
      yaml::positive() & yaml::up_to(100000, "100 km in one run"));
    a("survey_leg_length_m", survey_leg_length_m,
      "Length of one leg along the river (type: survey); 0: 80 % of the river reach's "
      "reach_length_m [m]",
      yaml::non_negative() & yaml::up_to(100000, "100 km in one run"));
    a("waypoints_ne_m", waypoints_ne_m, "Waypoints, north and east [m] (type: waypoints)",
      yaml::plausible(-1e5, 1e5, "100 km from the world origin: float rendering loses precision"));
    a("waypoints_file", waypoints_file,
      "CSV of waypoints 'north_m,east_m', relative to the scenario file; appended to "
      "waypoints_ne_m (type: waypoints)");
    a("yaw_weave", yaw_weave, "Deliberate heading weave to sweep yaw variability");
    a.require(speed_mps > 0 || type == MissionType::kSpin, "speed_mps",
              "a speed > 0 for every mission type but 'spin'");
  }
};

}  // namespace driftlab::sim
