#include "pipeline/scenario_checks.hpp"

#include <fmt/format.h>

#include <cmath>
#include <numbers>

#include "sim/physics/waves/wave_field.hpp"

namespace driftlab::pipeline {
namespace {

// Miche's breaking limit for a regular wave: H / lambda <= 0.142 tanh(k d) (deep water
// 1/7; shallower water breaks lower). H = 2 x amplitude.
constexpr double kMicheSteepness = 0.142;

struct RegularWave {
  std::string keys;  // the keys that set it, for messages
  std::string path;  // the first of them, where the message points in the file
  double height_m = 0;
  double wavelength_m = 0;
};

double wavelength_of(const sim::WaveComponentOptions& w, double depth_m) {
  if (w.period_s <= 0) return w.wavelength_m;
  const double k = sim::dispersion_wavenumber(2 * std::numbers::pi / w.period_s, depth_m);
  return 2 * std::numbers::pi / k;
}

// The regular waves of the field (JONSWAP: a wave of Hs at the peak period).
std::vector<RegularWave> regular_waves(const sim::WaveOptions& w) {
  std::vector<RegularWave> out;
  const auto one = [&](const sim::WaveComponentOptions& a, const std::string& at) {
    const std::string period = a.period_s > 0 ? "period_s" : "wavelength_m";
    out.push_back({fmt::format("{0}.amplitude_m and {0}.{1}", at, period), at + ".amplitude_m",
                   2 * a.amplitude_m, wavelength_of(a, w.water_depth_m)});
  };
  if (w.model == sim::WaveModel::kAiry) one(w.airy, "water.waves.airy");
  if (w.model == sim::WaveModel::kComponents)
    for (std::size_t i = 0; i < w.components.size(); ++i)
      one(w.components[i], fmt::format("water.waves.components[{}]", i));
  if (w.model == sim::WaveModel::kJonswap) {
    const double k =
        sim::dispersion_wavenumber(2 * std::numbers::pi / w.peak_period_s, w.water_depth_m);
    out.push_back({"water.waves.significant_height_m and peak_period_s",
                   "water.waves.significant_height_m", w.significant_height_m,
                   2 * std::numbers::pi / k});
  }
  return out;
}

void check_steepness(const Scenario& s, std::vector<std::string>* out) {
  for (const RegularWave& r : regular_waves(s.water.waves)) {
    if (r.height_m <= 0) continue;
    const double k = 2 * std::numbers::pi / r.wavelength_m;
    const double limit = kMicheSteepness * std::tanh(k * s.water.waves.water_depth_m);
    if (r.height_m / r.wavelength_m > limit)
      out->push_back(fmt::format(
          "{}: a wave {:.3g} m high and {:.3g} m long (steepness H/lambda {:.3g}) is steeper "
          "than the {:.3g} at which waves break in {} m of water (Miche): linear wave theory "
          "still computes it, but no basin or river makes it",
          r.keys, r.height_m, r.wavelength_m, r.height_m / r.wavelength_m, limit,
          s.water.waves.water_depth_m));
  }
}

void check_waves(const Scenario& s, std::vector<yaml::Problem>* out) {
  for (const RegularWave& r : regular_waves(s.water.waves)) {
    const auto& basin = s.scene.wave_basin;
    if (s.scene.type == scenes::SceneType::kWaveBasin && r.wavelength_m > basin.length_m)
      out->push_back(
          {r.path,
           fmt::format(
               "{} with scene.wave_basin.length_m: got a wave {:.3g} m long in a basin {} m long, "
               "expected a wave shorter than the basin",
               r.keys, r.wavelength_m, basin.length_m)});
  }
}

// Box hull floating level at rest: draft = mass / (rho L B).
void check_hull(const Scenario& s, std::vector<yaml::Problem>* out) {
  const auto& v = s.vessel;
  const double draft_m = v.mass_kg / (sim::kWaterDensity_kg_m3 * v.hull.length_m * v.hull.beam_m);
  if (draft_m >= v.hull.depth_m) {
    out->push_back(
        {"vessel.mass_kg",
         fmt::format(
             "vessel.mass_kg with vessel.hull.length_m, beam_m and depth_m: got {} kg in a {} x {} "
             "x {} m box, a draft of {:.3g} m, expected a draft below the hull depth (it sinks)",
             v.mass_kg, v.hull.length_m, v.hull.beam_m, v.hull.depth_m, draft_m)});
    return;
  }
  // The camera's height above the still water at rest: CG at kg_m above the keel, the
  // mount's z pointing down from the CG.
  const double camera_above_water_m =
      v.hull.kg_m - s.sensors.camera.mount.position_frd_m[2] - draft_m;
  if (camera_above_water_m <= 0)
    out->push_back(
        {"sensors.camera.mount.position_frd_m[2]",
         fmt::format(
             "sensors.camera.mount.position_frd_m[2] with vessel.hull.kg_m and vessel.mass_kg: the "
             "camera sits {:.3g} m below the still water at rest (draft {:.3g} m), expected it "
             "above the water line",
             -camera_above_water_m, draft_m)});
}

// Whether north/east lies on the water of the scene.
bool on_water(const Scenario& s, double north, double east) {
  if (s.scene.type == scenes::SceneType::kRiverReach)
    return std::abs(east) < s.scene.river_reach.bank_distance_m;
  const auto& b = s.scene.wave_basin;
  return north > 0 && north < b.beach_distance_m && std::abs(east) < b.width_m / 2;
}

std::string scene_extent(const Scenario& s) {
  if (s.scene.type == scenes::SceneType::kRiverReach)
    return fmt::format("the river's water, |east| < scene.river_reach.bank_distance_m = {} m",
                       s.scene.river_reach.bank_distance_m);
  const auto& b = s.scene.wave_basin;
  return fmt::format(
      "the basin's water, 0 < north < scene.wave_basin.beach_distance_m = {} m and |east| < "
      "scene.wave_basin.width_m / 2 = {} m",
      b.beach_distance_m, b.width_m / 2);
}

void check_mission(const Scenario& s, std::vector<yaml::Problem>* out) {
  const auto& start = s.vessel.start_ne_m;
  const auto point = [&](const std::string& key, double n, double e) {
    if (!on_water(s, n, e))
      out->push_back({key, fmt::format("{}: got ({}, {}), expected a point on {}", key, n, e,
                                       scene_extent(s))});
  };
  point("vessel.start_ne_m", start[0], start[1]);
  const auto& m = s.mission;
  if (m.type == sim::MissionType::kWaypoints)
    for (std::size_t i = 0; i < m.waypoints_ne_m.size(); ++i)
      point(fmt::format("mission.waypoints_ne_m[{}]", i), m.waypoints_ne_m[i][0],
            m.waypoints_ne_m[i][1]);
  if (m.type == sim::MissionType::kTransects && s.scene.type == scenes::SceneType::kRiverReach &&
      m.crossing_width_m >= s.scene.river_reach.river_width_m)
    out->push_back(
        {"mission.crossing_width_m",
         fmt::format(
             "mission.crossing_width_m with scene.river_reach.river_width_m: got crossings {} m "
             "long on a river {} m wide, expected crossings shorter than the river is wide",
             m.crossing_width_m, s.scene.river_reach.river_width_m)});
  if ((m.type == sim::MissionType::kTow || m.type == sim::MissionType::kStraight) &&
      s.scene.type == scenes::SceneType::kWaveBasin) {
    const double h = s.vessel.start_heading_deg * std::numbers::pi / 180;
    const double n = start[0] + m.survey_length_m * std::cos(h);
    const double e = start[1] + m.survey_length_m * std::sin(h);
    if (on_water(s, start[0], start[1]) && !on_water(s, n, e))
      out->push_back(
          {"mission.survey_length_m",
           fmt::format(
               "mission.survey_length_m with vessel.start_ne_m and start_heading_deg: the track "
               "ends at ({:.3g}, {:.3g}), expected it to end on {}",
               n, e, scene_extent(s))});
  }
}

// The overhead camera hangs from a wave basin's ceiling.
void check_overhead(const Scenario& s, std::vector<yaml::Problem>* out) {
  if (s.sensors.overhead.enabled && s.scene.type != scenes::SceneType::kWaveBasin)
    out->push_back({"sensors.overhead.enabled",
                    fmt::format("sensors.overhead.enabled with scene.type: got true with {}, "
                                "expected scene.type wave_basin (the camera hangs from the "
                                "basin's ceiling)",
                                yaml::enum_name(s.scene.type))});
}

}  // namespace

std::vector<yaml::Problem> impossible_combinations(const Scenario& scenario) {
  std::vector<yaml::Problem> out;
  check_waves(scenario, &out);
  check_hull(scenario, &out);
  check_mission(scenario, &out);
  check_overhead(scenario, &out);
  return out;
}

std::vector<std::string> implausible_values(const Scenario& scenario) {
  std::vector<std::string> out;
  check_steepness(scenario, &out);
  return out;
}

}  // namespace driftlab::pipeline
