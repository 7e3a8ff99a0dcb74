// 6-DOF vessel dynamics in Fossen's form (Fossen 2011, "Handbook of Marine
// Craft Hydrodynamics and Motion Control", Eq. 6.2):
//
//   (M_RB + M_A) nu_dot + C_RB(nu) nu + C_A(nu_r) nu_r + D(nu_r) nu_r = tau
//
// about the centre of gravity, with nu = [v_B; w_B] (body FRD) and
// nu_r = nu - nu_current (the water current at the CG). Hydrostatic
// restoring and wave excitation (Froude-Krylov) are not scripted: they come
// from integrating the pressure of the WaveField over the wetted panels of the
// hull at its instantaneous pose, so that the response to amplitude, length
// and heading emerges.
//
// Model/state split as MuJoCo's mjModel/mjData: VesselModel is immutable; the
// state is a plain value integrated by the simulator.
#pragma once

#include <array>
#include <vector>

#include "core/se3.hpp"
#include "sim/physics/vessel/vessel_options.hpp"
#include "sim/physics/waves/wave_field.hpp"

namespace driftlab::sim {

using Vec6 = Eigen::Matrix<double, 6, 1>;
using Mat6 = Eigen::Matrix<double, 6, 6>;

/// Rigid-body state: pose of the body (CG, FRD) in the world (NED) and body velocities.
struct VesselState {
  Vec3 p_W = Vec3::Zero();               // position of the CG [m]
  Quat q_W_B = Quat::Identity();         // attitude
  Vec3 v_B = Vec3::Zero();               // linear velocity in body axes [m/s]
  Vec3 w_B = Vec3::Zero();               // angular velocity of B in B [rad/s]
  std::array<double, 2> thrust_n{0, 0};  // actual thrust of port, starboard thrusters [N]

  SE3 T_W_B() const { return SE3(q_W_B, p_W); }
};

/// Time derivative of VesselState (the quaternion derivative as a 4-vector).
struct VesselStateDot {
  Vec3 p_dot = Vec3::Zero();
  Eigen::Vector4d q_dot = Eigen::Vector4d::Zero();  // (x, y, z, w) as Eigen's coeffs()
  Vec3 v_dot = Vec3::Zero();
  Vec3 w_dot = Vec3::Zero();
  std::array<double, 2> thrust_dot{0, 0};
};

/// Inputs held constant over one physics step.
struct VesselInputs {
  std::array<double, 2> thrust_command_n{0, 0};  // port, starboard
  bool tow_active = false;
  Vec3 tow_carriage_W = Vec3::Zero();  // carriage position at t = 0 [m]
  Vec3 tow_carriage_velocity_W = Vec3::Zero();
};

/// Where the generalized forces come from (body axes, about the CG) [N, N m].
struct ForceBreakdown {
  Vec6 gravity = Vec6::Zero();
  Vec6 pressure = Vec6::Zero();  // hydrostatics + Froude-Krylov
  Vec6 damping = Vec6::Zero();
  Vec6 coriolis = Vec6::Zero();  // -(C_RB + C_A) terms
  Vec6 thrust = Vec6::Zero();
  Vec6 tow = Vec6::Zero();
  Vec6 total() const { return gravity + pressure + damping + coriolis + thrust + tow; }
};

/// Environment the vessel floats in (not owned).
struct Environment {
  const WaveField* waves = nullptr;
  CurrentOptions current;
  double channel_half_width_m = 10.0;
  bool damping_enabled = true;
};

class VesselModel {
 public:
  /// Validates `options` (UserError naming the field) and builds the hull panels.
  explicit VesselModel(const VesselOptions& options);

  const VesselOptions& options() const { return options_; }
  double mass_kg() const { return options_.mass_kg; }
  /// Rigid-body + added mass matrix (6x6, diagonal for this hull).
  const Mat6& mass_matrix() const { return M_; }
  /// Design draft in calm water: displaced volume / waterplane area [m].
  double design_draft_m() const;
  /// CG depth (NED z) at the design draft, level [m].
  double design_cg_z_m() const;
  /// Analytic hydrostatic stiffness of the box: C33 [N/m], C44, C55 [N m/rad].
  double heave_stiffness() const;
  double roll_stiffness() const;
  double pitch_stiffness() const;

  /// Generalized forces at `state`, time `t_s`.
  ForceBreakdown forces(const VesselState& state, const VesselInputs& in, const Environment& env,
                        double t_s) const;
  /// State derivative (Fossen's equations of motion).
  VesselStateDot derivative(const VesselState& state, const VesselInputs& in,
                            const Environment& env, double t_s,
                            ForceBreakdown* breakdown = nullptr) const;

  /// Total mechanical energy in calm water without current: kinetic (with
  /// added mass) + gravity + hydrostatic potential rho g * integral of depth
  /// over the displaced volume (the potential whose gradient is buoyancy),
  /// computed here from the hull geometry by columns. [J]
  double calm_water_energy(const VesselState& state, int columns_along = 400,
                           int columns_across = 150) const;

  /// World positions of the thruster and tow attachment points.
  Vec3 tow_point_B() const {
    return Vec3(options_.tow.attach_x_m, 0, -options_.hull.depth_m + options_.hull.kg_m);
  }

 private:
  struct Panel {   // a flat piece of the hull, in body axes
    Vec3 bottom;   // bottom edge centre (or centre for a bottom cell)
    Vec3 up;       // from bottom edge to top edge (zero for bottom cells)
    Vec3 normal;   // outward unit normal
    double width;  // width (or area for bottom cells)
    bool is_strip;
  };

  VesselOptions options_;
  Mat6 M_ = Mat6::Zero();
  Mat6 M_inv_ = Mat6::Zero();
  Vec3 inertia_ = Vec3::Zero();  // principal moments about the CG
  std::vector<Panel> panels_;
};

}  // namespace driftlab::sim
