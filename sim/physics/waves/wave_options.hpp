// Options of the water: the wave field and the current (scenario section `water`).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "core/yaml_io.hpp"

namespace driftlab::sim {

enum class WaveModel { kCalm, kAiry, kComponents, kJonswap };
constexpr auto enum_table(WaveModel) {
  return std::array{std::pair{WaveModel::kCalm, "calm"}, std::pair{WaveModel::kAiry, "airy"},
                    std::pair{WaveModel::kComponents, "components"},
                    std::pair{WaveModel::kJonswap, "jonswap"}};
}

/// One regular (Airy) wave component.
struct WaveComponentOptions {
  double amplitude_m = 0.005;
  double wavelength_m = 0.21;
  double period_s = 0.0;
  double direction_deg = 0.0;
  double phase_deg = 0.0;

  template <class A>
  void visit(A& a) {
    a("amplitude_m", amplitude_m, "Wave amplitude zeta_a [m]",
      yaml::non_negative() & yaml::up_to(20, "higher than the largest measured ocean waves"));
    a("wavelength_m", wavelength_m, "Wavelength lambda [m]",
      yaml::positive() & yaml::up_to(2000, "longer than any wind wave or swell"));
    a("period_s", period_s,
      "Wave period T [s]; 0: wavelength_m sets the wave. When > 0 the period sets it (wavelength "
      "from the finite-depth dispersion relation) and wavelength_m is not used",
      yaml::non_negative() & yaml::up_to(60, "longer than any swell"));
    a("direction_deg", direction_deg, "Direction the wave travels towards, from north [deg]",
      yaml::in_range(-360, 360));
    a("phase_deg", phase_deg, "Phase at the origin at t = 0 [deg]", yaml::in_range(-360, 360));
  }
};

struct WaveOptions {
  WaveModel model = WaveModel::kCalm;
  double water_depth_m = 3.0;
  WaveComponentOptions airy;
  std::vector<WaveComponentOptions> components;
  double significant_height_m = 0.05;
  double peak_period_s = 1.5;
  double peak_enhancement_gamma = 3.3;
  double mean_direction_deg = 0.0;
  double spreading_s = 10.0;
  int num_frequencies = 32;
  int num_directions = 8;

  template <class A>
  void visit(A& a) {
    a("model", model, "Wave field model");
    a("water_depth_m", water_depth_m, "Water depth for the finite-depth dispersion relation [m]",
      yaml::positive() & yaml::up_to(11000, "deeper than the deepest ocean"));
    a("airy", airy, "The regular wave (model: airy)");
    a("components", components, "Sum of regular waves (model: components)");
    a.require(model != WaveModel::kComponents || !components.empty(), "components",
              "at least one component when model is 'components'");
    a("significant_height_m", significant_height_m, "JONSWAP significant wave height Hs [m]",
      yaml::positive() & yaml::up_to(20, "above the largest sea states measured (Hs about 19 m)"));
    a("peak_period_s", peak_period_s, "JONSWAP peak period Tp [s]",
      yaml::positive() & yaml::up_to(30, "longer than any measured sea"));
    a("peak_enhancement_gamma", peak_enhancement_gamma, "JONSWAP peak enhancement factor gamma",
      yaml::at_least(1) & yaml::up_to(20, "measured seas give 1 to 7"));
    a("mean_direction_deg", mean_direction_deg, "JONSWAP mean direction of travel [deg]",
      yaml::in_range(-360, 360));
    a("spreading_s", spreading_s, "cos-2s directional spreading exponent s",
      yaml::positive() & yaml::up_to(1000, "s = 1000 is already a single direction"));
    a("num_frequencies", num_frequencies, "JONSWAP frequency components", yaml::in_range(1, 4096));
    a("num_directions", num_directions, "JONSWAP direction components", yaml::in_range(1, 512));
    // Linear theory needs water under every trough: a trough that reaches the
    // bottom is not a wave this model can describe.
    a.require(model != WaveModel::kAiry || airy.amplitude_m < water_depth_m, "airy",
              "an amplitude_m below water_depth_m (else the trough reaches the bottom)");
    double component_amplitudes_m = 0.0;
    for (const auto& c : components) component_amplitudes_m += c.amplitude_m;
    a.require(model != WaveModel::kComponents || component_amplitudes_m < water_depth_m,
              "components",
              "a sum of amplitude_m below water_depth_m (else the deepest trough reaches the "
              "bottom)");
    a.require(model != WaveModel::kJonswap || significant_height_m < water_depth_m,
              "significant_height_m",
              "a significant height below water_depth_m (else troughs reach the bottom)");
  }
};

enum class CurrentProfile { kUniform, kBankToBank };
constexpr auto enum_table(CurrentProfile) {
  return std::array{std::pair{CurrentProfile::kUniform, "uniform"},
                    std::pair{CurrentProfile::kBankToBank, "bank_to_bank"}};
}

struct CurrentOptions {
  double speed_mps = 0.0;
  double direction_deg = 0.0;
  CurrentProfile profile = CurrentProfile::kUniform;

  template <class A>
  void visit(A& a) {
    a("speed_mps", speed_mps, "Surface current speed (mid-channel for bank_to_bank) [m/s]",
      yaml::in_range(0, 5));
    a("direction_deg", direction_deg, "Direction the current flows towards, from north [deg]",
      yaml::in_range(-360, 360));
    a("profile", profile, "Cross-channel profile of the current");
  }
};

enum class RippleLevel { kSlick, kSpectrum };
constexpr auto enum_table(RippleLevel) {
  return std::array{std::pair{RippleLevel::kSlick, "slick"},
                    std::pair{RippleLevel::kSpectrum, "spectrum"}};
}

/// Wind over the water. It raises the short capillary-gravity ripples that
/// break a river's mirror image up; they are drawn by the renderer only (the
/// vessel physics does not feel them, and the wind exerts no force).
struct WindOptions {
  double speed_mps = 0.0;
  double direction_deg = 0.0;
  double shelter = 1.0;
  double fetch_m = 100.0;
  RippleLevel ripple_level = RippleLevel::kSlick;
  bool sway = true;

  template <class A>
  void visit(A& a) {
    a("speed_mps", speed_mps,
      "Wind speed over open terrain [m/s]; 0: a mirror-calm surface. The river paper's survey "
      "had a gentle breeze of 3.4-5.4 m/s (Kriechbaumer et al. 2015, Sec. 2.1)",
      yaml::in_range(0, 20));
    a("direction_deg", direction_deg, "Direction the wind blows towards, from north [deg]",
      yaml::in_range(-360, 360));
    a("shelter", shelter,
      "Fraction of the wind speed that reaches the water (banks and trees shelter a river); "
      "1: open water",
      yaml::in_range(0, 1));
    a("fetch_m", fetch_m,
      "Fetch: the open water upwind over which the wind raises the ripples [m]; it sets the "
      "ripple spectrum's peak (Elfouhaily et al. 1997)",
      yaml::at_least(1) & yaml::up_to(1e6, "longer than any ocean fetch"));
    a("ripple_level", ripple_level,
      "What sets the ripples' mean square slope: 'slick', Cox and Munk's slick-surface wind "
      "term 1.56e-3 U at the wind reaching the water (it falls to glassy water in light air); "
      "'spectrum', the integral of Elfouhaily et al.'s spectrum (fitted for U of 3 m/s and "
      "more; about 0.01 even in light air at a short fetch)");
    a("sway", sway,
      "The river bank's trees, bushes and reeds sway in this wind's gusts (a damped oscillator "
      "per plant driven by a Kaimal gust spectrum moving downwind; leaves also flutter: "
      "docs/renderer-and-scenes.md, Wind in the vegetation); their pixels are moving things "
      "of the masks. false: the vegetation stands still whatever the wind");
  }
};

struct WaterOptions {
  WaveOptions waves;
  CurrentOptions current;
  WindOptions wind;

  template <class A>
  void visit(A& a) {
    a("waves", waves, "Wave field shared by vessel physics and renderer");
    a("current", current, "Water current");
    a("wind", wind, "Wind ripples on the water surface (rendered only)");
  }
};

}  // namespace driftlab::sim
