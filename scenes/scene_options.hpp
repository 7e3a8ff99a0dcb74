// Options of the rendered world (scenario section `scene`).
#pragma once

#include <array>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "core/yaml_io.hpp"

namespace driftlab::scenes {

enum class SceneType { kRiverReach, kWaveBasin };
constexpr auto enum_table(SceneType) {
  return std::array{std::pair{SceneType::kRiverReach, "river_reach"},
                    std::pair{SceneType::kWaveBasin, "wave_basin"}};
}

enum class TreeModel { kSkeleton, kEllipsoid };
constexpr auto enum_table(TreeModel) {
  return std::array{std::pair{TreeModel::kSkeleton, "skeleton"},
                    std::pair{TreeModel::kEllipsoid, "ellipsoid"}};
}

enum class ReedModel { kBlades, kCards };
constexpr auto enum_table(ReedModel) {
  return std::array{std::pair{ReedModel::kBlades, "blades"}, std::pair{ReedModel::kCards, "cards"}};
}

enum class Sky { kOvercast, kSun };
constexpr auto enum_table(Sky) {
  return std::array{std::pair{Sky::kOvercast, "overcast"}, std::pair{Sky::kSun, "sun"}};
}

/// Another vessel on the river (docs/renderer-and-scenes.md, "Other vessels: a moving world"): a
/// motor boat under way along the river at a steady speed, or moored (speed 0), rocking in roll,
/// pitch and heave (sim::MoverMotion). Its pixels are the moving things of the masks
/// (`driftlab render --masks`, frames.csv moving_px).
struct OtherVesselOptions {
  double north_m = 0;
  double east_m = 7;
  double speed_mps = 0;
  double length_m = 7;
  double beam_m = 2.4;
  double freeboard_m = 0.7;
  double roll_deg = 1.5;
  double roll_period_s = 3.2;
  double pitch_deg = 0.5;
  double heave_m = 0.02;
  double pitch_period_s = 2.1;

  template <class A>
  void visit(A& a) {
    a("north_m", north_m, "Where its centre is at t = 0, along the river (NED north) [m]",
      yaml::in_range(-1e5, 1e5));
    a("east_m", east_m,
      "Its centre line's distance from the river's centre line (east positive) [m]; the hull "
      "must float between the banks: |east_m| + beam_m / 2 <= bank_distance_m",
      yaml::in_range(-1000, 1000));
    a("speed_mps", speed_mps,
      "Speed along the river [m/s]: positive northwards, negative southwards, 0 moored "
      "(heading north, alongside the bank)",
      yaml::in_range(-15, 15));
    a("length_m", length_m, "Hull length [m]", yaml::in_range(2, 60));
    a("beam_m", beam_m, "Hull width [m]", yaml::in_range(0.8, 15));
    a("freeboard_m", freeboard_m, "Deck height above the water [m]", yaml::in_range(0.2, 5));
    a("roll_deg", roll_deg, "Amplitude of its roll [deg]", yaml::in_range(0, 20));
    a("roll_period_s", roll_period_s, "Period of its roll [s]", yaml::in_range(0.5, 60));
    a("pitch_deg", pitch_deg, "Amplitude of its pitch [deg]", yaml::in_range(0, 10));
    a("heave_m", heave_m, "Amplitude of its heave [m]", yaml::in_range(0, 1));
    a("pitch_period_s", pitch_period_s, "Period of its pitch and heave [s]",
      yaml::in_range(0.5, 60));
  }
};

struct RiverReachOptions {
  double river_width_m = 20.0;
  double reach_length_m = 120.0;
  double bank_height_m = 1.5;
  double bank_slope_deg = 30.0;
  double bank_distance_m = 10.0;
  double tree_line_distance_m = 4.0;
  double tree_height_m = 12.0;
  double vegetation_density = 0.6;
  TreeModel tree_model = TreeModel::kSkeleton;
  int leaf_cards_per_tree = 45;
  ReedModel reed_model = ReedModel::kCards;
  double waterline_stones_per_m = 1.5;
  double far_trees_per_m = 0.1;
  int bank_roots_per_tree = 4;
  double bank_undercut_share = 0;
  double tree_detail_distance_m = 7.0;
  double texture_contrast = 2.0;
  bool photographs = true;
  double cloud_contrast = 0.08;
  std::optional<double> visibility_m = 9000.0;  // null: the sky's own haze (outdoor_lighting)
  bool bridge = true;
  bool quay_wall = true;
  double quay_ladder_spacing_m = 15;
  double quay_stain_height_m = 0.5;
  int buildings = 4;
  double view_margin_m = 150.0;
  std::vector<OtherVesselOptions> vessels;

  template <class A>
  void visit(A& a) {
    // river_width_m and bank_distance_m describe one quantity (the river is
    // symmetric about its centre line y = 0: width = 2 x bank distance). A
    // document may set either, and the other follows; setting both to values
    // that disagree is an error. To tell which keys this document sets, the
    // reader (only the reader runs when_reading) parks both at NaN, which only
    // a key present in the document overwrites, and restores the absent one.
    double width_before = river_width_m, bank_before = bank_distance_m;
    a.when_reading([&] {
      width_before = river_width_m;
      bank_before = bank_distance_m;
      river_width_m = bank_distance_m = std::numeric_limits<double>::quiet_NaN();
    });
    a("river_width_m", river_width_m,
      "Water width between the banks [m]; always 2 x bank_distance_m (set either)",
      yaml::positive() & yaml::up_to(2000, "wider than the rivers a survey boat maps"));
    a("reach_length_m", reach_length_m,
      "Length of one reach tile [m]; tiles are laid end to end along the river, each with its "
      "own bridge, quay and buildings (vegetation differs from tile to tile)",
      yaml::at_least(10) & yaml::up_to(5000, "one tile; a longer river is tiles laid end to end"));
    a("bank_height_m", bank_height_m, "Bank top above the water [m]",
      yaml::non_negative() & yaml::up_to(100, "a gorge, not a river bank"));
    a("bank_slope_deg", bank_slope_deg, "Bank slope [deg]", yaml::in_range(1, 90));
    a("bank_distance_m", bank_distance_m,
      "Distance from the river centre line to the water's edge [m]; always river_width_m / 2 "
      "(set either)",
      yaml::positive() & yaml::up_to(1000, "no river is wider than 2 km"));
    a.when_reading([&] {
      const bool width_set = !std::isnan(river_width_m), bank_set = !std::isnan(bank_distance_m);
      if (!width_set) river_width_m = width_before;
      if (!bank_set) bank_distance_m = bank_before;
      if (width_set && !bank_set) bank_distance_m = river_width_m / 2;
      if (bank_set && !width_set) river_width_m = 2 * bank_distance_m;
    });
    a.require(std::abs(river_width_m - 2 * bank_distance_m) <= 1e-9 * river_width_m,
              "bank_distance_m", "river_width_m / 2 (the two describe the same river)");
    a("tree_line_distance_m", tree_line_distance_m,
      "Distance of the tree line behind the water's edge [m]",
      yaml::non_negative() & yaml::up_to(1000, "trees further away are not scenery a VO sees"));
    a("tree_height_m", tree_height_m,
      "Mean tree height [m]; each tree is drawn uniformly in [0.75, 1.25] x this",
      yaml::positive() & yaml::up_to(120, "taller than the tallest trees"));
    a("vegetation_density", vegetation_density,
      "Trees and reeds per unit bank (0 = bare, 1 = a tree every 4 m in each of two rows)",
      yaml::unit_interval());
    a("tree_model", tree_model,
      "skeleton: alders, willows (leaning over the water), weeping willows and poplars grown "
      "as trunks, limbs and twigs (Weber and Penn 1995) in photographed bark, dressed with "
      "alpha-tested leaf-cluster cards (docs/renderer-and-scenes.md, Trees); ellipsoid: a "
      "6-sided trunk under a lumpy ellipsoid, the cheaper crowns of earlier rounds");
    a("leaf_cards_per_tree", leaf_cards_per_tree,
      "Leaf-cluster cards on a near tree (half as many, each twice the area, at the mid level "
      "of detail); skeleton trees only",
      yaml::in_range(8, 400));
    a("reed_model", reed_model,
      "blades: each clump 14 single-triangle blades in the reed texture; cards: three "
      "alpha-tested cards crossed at 60 deg, each a drawn clump of tapering blades "
      "(scenes/leaf_textures.hpp), the strip cards of docs/renderer-and-scenes.md");
    a("waterline_stones_per_m", waterline_stones_per_m,
      "Stones at the water's edge per metre of bank on each side (lumpy flattened ellipsoids of "
      "0.08-0.43 m radius, sunk a third into the bank or the river bed); 0: none",
      yaml::in_range(0, 5));
    a("far_trees_per_m", far_trees_per_m,
      "Far trees per metre of the far wood on each side: world-fixed crossed billboards, 10-16 m "
      "tall, growing out of the wood's canopy within 25 m of its front; 0: none",
      yaml::in_range(0, 2));
    a("bank_roots_per_tree", bank_roots_per_tree,
      "Roots laid bare by the current where a tree stands within 6 m of the water's edge: each "
      "a tapering tube of bark (5 to 1 cm) out of the bank slope (at most 3 m up it), arching "
      "out over the toe and into the water within 1.5 m of the trunk's line; none where the "
      "slope runs less than 0.5 m (a vertical bank, or none); 0: none",
      yaml::in_range(0, 12));
    a("bank_undercut_share", bank_undercut_share,
      "Share of each bank's length undercut by the current, in stretches of 3-10 m: a lip of "
      "earth 0.15 m thick, 0.3-0.6 m above the water, overhanging the water's edge by up to "
      "0.4 m (jagged, tapering at each stretch's ends), over the slope's foot in its shade "
      "(the soil at 0.4 of its albedo); none at the quay or the bridge, nor on a bank lower "
      "than 0.5 m or whose slope runs less than 0.5 m; 0: none",
      yaml::in_range(0, 1));
    a("tree_detail_distance_m", tree_detail_distance_m,
      "Trees at most this far behind the water's edge get twigs and the full set of cards; "
      "those further back three-sided limbs and half the cards (skeleton trees only)",
      yaml::non_negative() & yaml::up_to(1000, "trees further away are not scenery a VO sees"));
    a("texture_contrast", texture_contrast,
      "Contrast of procedural textures: scales each texture's deviation from its mean grey, "
      "clamped to [0, 255]. 2 gives frames whose spectrum slope, gradients and corners per "
      "50x50 cell match four outdoor photographs (docs/renderer-and-scenes.md, `driftlab "
      "imagestats`); 1 is the "
      "textures as drawn",
      yaml::in_range(0, 4));
    a("photographs", photographs,
      "Photographed materials where there are photographs (grass, soil, bark, stones, bricks, "
      "concrete: Debian's ufoai-textures, fetched by scripts/fetch-materials and credited in the "
      "README), each scaled to the mean grey of the procedural texture it replaces; false: "
      "procedural textures everywhere. texture_contrast applies to procedural textures only");
    a("cloud_contrast", cloud_contrast,
      "The overcast sky's cloud deck: relative rms of the sky's luminance it adds, before its "
      "fading with distance (docs/renderer-and-scenes.md, Sky); 0: the sky's gradient alone. "
      "Ignored under sky: sun",
      yaml::in_range(0, 0.5));
    a("visibility_m", visibility_m,
      "Meteorological visibility of the haze over the river [m]: a surface d metres away keeps "
      "exp(-3.912 d / visibility_m) of its contrast against the horizon's grey (Koschmieder's "
      "law, a 2 % contrast threshold); 9 km by default, the river paper's survey day. null: "
      "the sky's own haze, 1.56 km under overcast and 3.13 km under sun (extinction lengths of "
      "400 and 800 m). The cloud deck keeps its own fading. A misty morning: "
      "scenarios/river_crossing_mist.yaml",
      yaml::at_least(10) & yaml::up_to(3e5, "clearer than the clearest air (about 300 km)"));
    a("bridge", bridge, "Road bridge with piers across each reach tile");
    a("quay_wall", quay_wall,
      "Feature-poor sheet-piled quay wall (~30 m) on the east bank of each tile");
    a("quay_ladder_spacing_m", quay_ladder_spacing_m,
      "Steel ladders on the quay wall's face, one every this many metres along it (the first "
      "half a spacing from its south end; each two 50 mm rails 0.45 m apart with 30 mm rungs "
      "every 0.3 m, from 1 m below the water to handholds 0.9 m above the capping beam); 0: "
      "none",
      yaml::non_negative() & yaml::up_to(1000, "no quay is longer"));
    a("quay_stain_height_m", quay_stain_height_m,
      "A dark wet band of algae and rust on the quay wall's piling from the water up to this "
      "height [m] (the piling's grain at 0.55 of its albedo); 0: none",
      yaml::non_negative() & yaml::up_to(3, "the piling stands about 1.9 m above the water"));
    a("buildings", buildings, "Number of buildings behind the banks, per reach tile",
      yaml::in_range(0, 100));
    a("view_margin_m", view_margin_m,
      "Scenery built beyond both ends of the cameras' north range [m]; past it (rounded up to "
      "whole tiles) a wooded river bend closes the valley",
      yaml::in_range(0, 2000));
    a("vessels", vessels,
      "Other vessels on the river, each under way or moored (empty: none). "
      "scenarios/river_crossing_traffic.yaml has one of each");
    for (std::size_t i = 0; i < vessels.size(); ++i) {
      const OtherVesselOptions& v = vessels[i];
      const double edge = std::abs(v.east_m) + v.beam_m / 2;
      a.require(edge <= bank_distance_m, "vessels",
                "vessel " + std::to_string(i) +
                    " on the water: |east_m| + beam_m / 2 = " + yaml::format_double(edge) +
                    " m, at most bank_distance_m (" + yaml::format_double(bank_distance_m) + " m)");
    }
  }
};

struct WaveBasinOptions {
  double length_m = 30.0;
  double width_m = 4.0;
  double wall_height_m = 2.0;
  double beach_distance_m = 3.0;
  double water_depth_m = 0.6;
  double beach_slope_deg = 20.0;
  bool posters = true;

  template <class A>
  void visit(A& a) {
    a("length_m", length_m, "Basin length from the wave generator (x = 0) northwards [m]",
      yaml::positive() & yaml::up_to(2000, "longer than the longest towing tanks (under 1 km)"));
    a("width_m", width_m, "Basin width, walls at y = +-width_m / 2 [m]",
      yaml::positive() & yaml::up_to(500, "wider than the largest wave basins (about 100 m)"));
    a("wall_height_m", wall_height_m, "Wall height above the still water (the ceiling) [m]",
      yaml::at_least(0.5) & yaml::up_to(100, "no basin hall is higher"));
    a("beach_distance_m", beach_distance_m,
      "Distance from the wave generator to where the wave-absorbing beach meets the still "
      "water [m]",
      yaml::positive() & yaml::up_to(2000, "no basin is longer"));
    a.require(beach_distance_m < length_m, "beach_distance_m", "less than length_m");
    a("water_depth_m", water_depth_m,
      "Depth of the basin floor below the still water [m] (keep equal to "
      "water.waves.water_depth_m)",
      yaml::positive() & yaml::up_to(100, "deeper than the deepest basin pit"));
    a("beach_slope_deg", beach_slope_deg, "Slope of the beach [deg]", yaml::in_range(5, 60));
    a("posters", posters,
      "Printed posters on the walls (A1, about one every 2 m, 40 cm above the water: the "
      "basin's richest texture, ours: the basin paper shows no walls); false: the painted walls "
      "with only the windows, pipes, rails, beach and wave generator for a VO to hold to "
      "(docs/twin-vs-paper.md, \"Plain walls\")");
  }
};

struct SceneOptions {
  SceneType type = SceneType::kRiverReach;
  Sky sky = Sky::kOvercast;
  RiverReachOptions river_reach;
  WaveBasinOptions wave_basin;
  std::vector<std::string> extra_assets;

  template <class A>
  void visit(A& a) {
    a("type", type, "Which scene to build");
    a("sky", sky, "Sky and lighting");
    a("river_reach", river_reach, "River reach parameters (type: river_reach)");
    a("wave_basin", wave_basin, "Wave basin parameters (type: wave_basin)");
    a("extra_assets", extra_assets,
      "Extra meshes (OBJ, PLY, glTF) placed in the scene, paths relative to the scenario file");
  }
};

}  // namespace driftlab::scenes
