// The scenario: every parameter of one run, loaded from YAML, validated, and
// written back with defaults filled in (`scenario.resolved.yaml`).
#pragma once

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "dataset/dataset_format.hpp"
#include "eval/eval_options.hpp"
#include "fusion/ca_smoother.hpp"
#include "fusion/eskf.hpp"
#include "fusion/ned_filters.hpp"
#include "scenes/scene_options.hpp"
#include "sim/physics/vessel/vessel_options.hpp"
#include "sim/physics/waves/wave_options.hpp"
#include "sim/render/render_options.hpp"
#include "sim/sensors/sensor_options.hpp"
#include "vo/dense/dense_options.hpp"
#include "vo/pnp/pnp_options.hpp"
#include "vo/registry.hpp"
#include "vo/sparse/sparse_options.hpp"

namespace driftlab::pipeline {

/// The options of sparse_kf: the sparse VO's, keyframes on.
inline vo::SparseVoOptions sparse_kf_defaults() {
  vo::SparseVoOptions o;
  o.keyframes = true;
  return o;
}

enum class FusionAlgorithm { kCaSmoother, kNedKf, kNedPf, kEskf };
constexpr auto enum_table(FusionAlgorithm) {
  return std::array{std::pair{FusionAlgorithm::kCaSmoother, "ca_smoother"},
                    std::pair{FusionAlgorithm::kNedKf, "ned_kf"},
                    std::pair{FusionAlgorithm::kNedPf, "ned_pf"},
                    std::pair{FusionAlgorithm::kEskf, "eskf"}};
}

/// The first word in braces of an external VO's command that is not one of its placeholders
/// ({dir}, {root}, {out}, {driftlab}), e.g. "{outt}"; empty when there is none. "${HOME}" and
/// braces around anything but one word ("{ print $1 }") are the shell's.
std::string unknown_command_placeholder(const std::string& command);

/// A VO of the user's, run as a command on an export of the run's own frames (docs/datasets.md,
/// "External VOs in runs and sweeps").
struct ExternalVoOptions {
  std::string name;
  std::string command;
  dataset::DatasetFormat format = dataset::DatasetFormat::kKitti;
  TrajectoryFormat output = TrajectoryFormat::kTum;
  double timeout_s = 600;
  bool keep_dataset = false;

  template <class A>
  void visit(A& a) {
    a("name", name,
      "Name of the estimate (estimates/NAME.tum, tables, metrics): letters, digits, '_' and "
      "'-', not a built-in VO's name",
      yaml::non_empty());
    a("command", command,
      "Shell command (/bin/sh -c) run once the frames are exported; placeholders: {dir} the "
      "dataset (KITTI: its sequence folder with calib.txt; EuRoC and TUM: the folder holding "
      "mav0/ or rgb.txt), {root} the export's root (info.yaml), {out} the trajectory file the "
      "command must write, {driftlab} this driftlab executable. Any other word in braces is an "
      "error; ${VAR} and braces around anything but one word are the shell's",
      yaml::non_empty() & yaml::text_rule([](const std::string& text) -> std::string {
        const std::string unknown = unknown_command_placeholder(text);
        if (unknown.empty()) return "";
        return "placeholders {dir}, {root}, {out} or {driftlab} only, not " + unknown +
               " (a word in braces is a placeholder; ${VAR} is the shell's)";
      }));
    a("format", format, "Layout of the export the command reads (driftlab export --format)");
    a("output", output,
      "Format of the trajectory the command writes at {out}: tum or kitti (left-camera poses, "
      "x right, y down, z forward, in any world frame; KITTI: one pose per exported image) or "
      "euroc (body = IMU poses, as EuRoC's ground truth; turned into the left camera with "
      "the export's T_BS)");
    a("timeout_s", timeout_s,
      "Wall-clock limit of the command [s]; past it the command's process group is killed and "
      "the failure recorded",
      yaml::positive());
    a("keep_dataset", keep_dataset,
      "Keep the exported frames in external/NAME/ after the command (they are large: about "
      "0.3 MB per stereo pair at 640x480)");
  }
};

/// Which stages run, and the options of each algorithm.
struct PipelineOptions {
  std::vector<std::string> vo{"sparse"};
  std::vector<FusionAlgorithm> fusion{FusionAlgorithm::kCaSmoother};
  std::vector<ExternalVoOptions> external_vo;
  int max_frames = 0;
  int threads = 0;
  // Options of each algorithm (used when it runs).
  vo::SparseVoOptions sparse;
  vo::SparseVoOptions sparse_kf = sparse_kf_defaults();
  vo::PnpVoOptions pnp;
  vo::DenseVoOptions dense;
  fusion::CaSmootherOptions ca_smoother;
  fusion::NedFilterOptions ned_kf;
  fusion::NedParticleFilterOptions ned_pf;
  fusion::EskfOptions eskf;
  /// Options of the VOs the program registered with options (vo/registry.hpp).
  yaml::NamedOptions plugins = vo::plugin_options();

  /// The filters' sensor noise is left null: a run fills it in from the scenario's sensor
  /// models (FilterTrack, with_sensor_noise()), so that the filters follow the sensors simulated.
  PipelineOptions();

  template <class A>
  void visit(A& a) {
    a("vo", vo,
      "Visual odometry algorithms to run: the built-in ones and any VO the program registered "
      "(vo/registry.hpp)",
      yaml::one_of(&vo::available_vo_names));
    a("fusion", fusion, "Filters and smoothers to run on the VO output");
    a("external_vo", external_vo,
      "VOs of your own, each a command run on an export of this run's frames and evaluated "
      "with the built-in ones (docs/datasets.md: External VOs)");
    a("max_frames", max_frames, "Stop after this many stereo frames (0 = whole mission)",
      yaml::non_negative());
    a("threads", threads,
      "Threads of the frame loop: 0 = every core; 1 = render and each VO in turn; 2 or more "
      "= rendering on a thread of its own, up to 4 frames ahead, and the VOs side by side, up "
      "to this many at a time, each along its own frames up to 4 frames apart (driftlab vo: the "
      "VOs of a frame side by side). The output bytes are the same whatever the count",
      yaml::in_range(0, 256));
    a("sparse", sparse, "Options of the sparse VO (river paper Section 2.3.1)");
    a("sparse_kf", sparse_kf,
      "Options of sparse_kf: the sparse VO matching against keyframes (keyframes: true; ours, "
      "beyond the paper)");
    a("pnp", pnp, "Options of the GFTT+PnP VO (basin paper Section 3.1)");
    a("dense", dense, "Options of the dense photometric VO (river paper Section 2.3.2)");
    a("ca_smoother", ca_smoother,
      "Options of the constant-acceleration smoother (river paper Eqs. (4)-(5))");
    a("ned_kf", ned_kf, "Options of the NED Kalman filter (basin paper Section 3.1.1)");
    a("ned_pf", ned_pf, "Options of the NED particle filter (basin paper Section 3.1.2)");
    a("eskf", eskf, "Options of the error-state VO + IMU + GPS + compass filter");
    a("plugins", plugins,
      "Options of the VOs a program of your own registered with options, by name: "
      "plugins.my_vo.KEY (vo/registry.hpp; docs/datasets.md: Your VO in-process)");
  }
};

struct Scenario {
  std::string name = "unnamed";
  std::string description;
  std::uint64_t seed = 1;
  scenes::SceneOptions scene;
  sim::WaterOptions water;
  sim::VesselOptions vessel;
  sim::MissionOptions mission;
  sim::SensorOptions sensors;
  sim::RenderOptions render;
  PipelineOptions pipeline;
  eval::EvalOptions eval;

  template <class A>
  void visit(A& a) {
    a("name", name, "Scenario name, used in reports", yaml::non_empty());
    a("description", description, "Free text: what the scenario reproduces");
    a("seed", seed, "Seed of every random stream of the run");
    a("scene", scene, "The rendered world");
    a("water", water, "Waves and current");
    a("vessel", vessel, "The vessel carrying the sensors");
    a("mission", mission, "Where and how the vessel goes");
    a("sensors", sensors, "Camera, IMU, GPS and compass");
    a("render", render, "Off-screen renderer");
    a("pipeline", pipeline, "Which VO and filters run");
    a("eval", eval, "Error statistics");
  }
};

/// Loads `path`, applies `overrides` ("key.path=value", in order), resolves
/// files named in the scenario relative to its folder, and validates. Throws
/// UserError listing every problem (file, line, key path, value, expectation).
Scenario load_scenario(const std::filesystem::path& path,
                       const std::vector<std::string>& overrides = {});

/// Parses a scenario from YAML text (`label` names it in errors; relative
/// files resolve against `base_dir`).
Scenario parse_scenario(const std::string& text, const std::string& label,
                        const std::filesystem::path& base_dir,
                        const std::vector<std::string>& overrides = {});

/// Every value out of its range and every rule broken, those that span sections included:
/// each problem with the key path it is about and a message starting with it; empty when the
/// scenario can run.
std::vector<yaml::Problem> scenario_problems(const Scenario& scenario);

/// Throws UserError with every problem of scenario_problems(), under "LABEL: invalid scenario:".
/// (parse_scenario() and load_scenario() check the same, and say where in the file.)
void validate_scenario(const Scenario& scenario, const std::string& label);

/// The resolved scenario as YAML: every key, defaults filled in, doc comments.
std::string resolved_yaml(const Scenario& scenario);

/// Markdown reference of every scenario key with type, default, constraint and meaning.
std::string scenario_reference_markdown();

}  // namespace driftlab::pipeline

// Each walk over the whole scenario (reading, writing, checking, listing its keys) is compiled
// once, in scenario.cpp, rather than again in every file that hashes, checks or lists a
// scenario: about 30 visit() bodies a walk (docs/performance.md, Build and CI).
namespace driftlab::yaml {
extern template void read_into<pipeline::Scenario>(const YAML::Node&, const Source&,
                                                   pipeline::Scenario*, bool);
extern template std::string to_yaml<pipeline::Scenario>(const pipeline::Scenario&, bool);
extern template std::vector<Problem> validation_problems<pipeline::Scenario>(
    const pipeline::Scenario&, const std::string&);
extern template std::vector<SchemaRow> schema_of<pipeline::Scenario>(const pipeline::Scenario&);
}  // namespace driftlab::yaml
