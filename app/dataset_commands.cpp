#include "app/dataset_commands.hpp"

#include <fmt/format.h>
#include <fmt/ranges.h>
#include <unistd.h>

#include <algorithm>
#include <iostream>
#include <string>
#include <vector>

#include "app/cli_main.hpp"
#include "core/error.hpp"
#include "pipeline/dataset_run.hpp"
#include "pipeline/export_stage.hpp"
#include "pipeline/scenario.hpp"
#include "vo/registry.hpp"

namespace driftlab::app {
namespace {

// For a CLI11 check: "" when `name` is one of `names`, else what was expected.
std::string one_of(const std::string& name, const std::vector<std::string>& names) {
  if (std::find(names.begin(), names.end(), name) != names.end()) return "";
  return fmt::format("got '{}', expected one of: {}", name, fmt::join(names, ", "));
}

}  // namespace

DatasetCommands::DatasetCommands(CLI::App& app) {
  export_ = app.add_subcommand(
      "export",
      "Render a scenario into a dataset other tools read (KITTI, EuRoC, TUM RGB-D, ROS bags)");
  export_->add_option("SCENARIO", scenario_, "Scenario YAML file")->required();
  export_
      ->add_option("--format", format_, "Dataset layout: kitti, euroc, tum-rgbd, rosbag or rosbag2")
      ->capture_default_str();
  export_->add_option("--out", out_, "Output folder (written atomically)")->required();
  export_->add_option("--sequence", sequence_, "KITTI sequence number")->capture_default_str();
  export_->add_option("--frames", frames_, "Number of stereo frames (0 = the whole mission)")
      ->check(CLI::NonNegativeNumber);
  export_->add_option("--set", sets_, "Override a key: KEY.PATH=VALUE (repeatable)");
  export_->add_option("--seed", seed_, "Override the scenario seed")->check(seed_check());
  export_->add_flag("--force", force_, "Replace an existing output folder");
  add_frame_cache_option(export_);

  vo_ = app.add_subcommand(
      "vo", "Run the built-in VOs on a KITTI, EuRoC or ROS 1 bag stereo dataset and evaluate them");
  vo_->add_option("DATASET", dataset_, "Dataset folder, or a ROS 1 bag (a .bag file)")->required();
  vo_->add_option("--format", format_, "Dataset layout: kitti, euroc or rosbag")
      ->capture_default_str();
  vo_->add_option("--gt-topic", gt_topic_,
                  "rosbag: the ground truth's topic (PoseStamped, TransformStamped or Odometry of "
                  "the IMU; default: /groundtruth/pose, else EuRoC's "
                  "/vicon/firefly_sbx/firefly_sbx)");
  vo_->add_option("--calibration", calibration_,
                  "rosbag: a Kalibr camera chain (default: kalibr_imucam_chain.yaml beside the "
                  "bag)");
  vo_->add_option("--algo", algos_, "VO algorithms (default: the settings' pipeline.vo)")
      ->delimiter(',')
      ->check(CLI::Validator(
          [](std::string& name) { return one_of(name, vo::available_vo_names()); }, "NAME"));
  vo_->add_option("--fusion", fusion_,
                  "Filters following each VO: ca_smoother, eskf, ned_kf, ned_pf, or none "
                  "(default: the settings' pipeline.fusion; eskf needs the dataset's IMU, the "
                  "NED filters a compass)")
      ->delimiter(',')
      ->check(CLI::Validator(
          [](std::string& name) {
            std::vector<std::string> names{"none"};
            for (const auto& [value, text] : enum_table(pipeline::FusionAlgorithm{}))
              names.emplace_back(text);
            return one_of(name, names);
          },
          "NAME"));
  vo_->add_option("--out", out_, "Output folder (written atomically)")->required();
  vo_->add_option("--sequence", sequence_, "KITTI sequence number")->capture_default_str();
  vo_->add_option("--settings", settings_,
                  "Scenario file whose pipeline (VO options), eval and seed are used (default: "
                  "the built-in defaults; an export's scenario.resolved.yaml reproduces its run)");
  vo_->add_option("--set", sets_, "Override a key of the settings: KEY.PATH=VALUE (repeatable)");
  vo_->add_option("--seed", seed_, "Override the seed")->check(seed_check());
  vo_->add_option("--frames", frames_, "Stop after this many stereo frames (0 = all)")
      ->check(CLI::NonNegativeNumber);
  vo_->add_flag("--force", force_, "Replace an existing output folder");
}

std::optional<int> DatasetCommands::dispatch() {
  if (export_->parsed()) return export_dataset();
  if (vo_->parsed()) return run_vo();
  return std::nullopt;
}

int DatasetCommands::export_dataset() {
  std::vector<std::string> sets = sets_;
  if (!seed_.empty()) sets.push_back("seed=" + seed_);
  if (frames_ > 0) sets.push_back(fmt::format("pipeline.max_frames={}", frames_));
  const auto scenario = pipeline::load_scenario(scenario_, sets);
  pipeline::ExportOptions o;
  o.format = as_usage_error("--format", [&] { return dataset::format_from_name(format_); });
  o.sequence = sequence_;
  o.replace_existing = force_;
  o.progress = stderr;
  o.progress_tty = isatty(STDERR_FILENO) != 0;
  o.frame_cache = pipeline::FrameCacheOptions::from_environment();
  const auto summary = pipeline::export_dataset(scenario, out_, o);
  std::cout << summary.brief() << "\n";
  std::cerr << fmt::format("driftlab export: wrote {} ({})\n", out_, format_);
  return 0;
}

int DatasetCommands::run_vo() {
  std::vector<std::string> sets = sets_;
  if (!seed_.empty()) sets.push_back("seed=" + seed_);
  if (!algos_.empty()) {  // checked by the scenario reader, with its messages
    std::string list;
    for (const auto& a : algos_) list += (list.empty() ? "" : ",") + a;
    sets.push_back("pipeline.vo=[" + list + "]");
  }
  if (!fusion_.empty()) {  // checked by the scenario reader too
    std::string list;
    for (const auto& f : fusion_)
      if (f != "none") list += (list.empty() ? "" : ",") + f;
    sets.push_back("pipeline.fusion=[" + list + "]");
  }
  const auto settings = settings_.empty() ? pipeline::parse_scenario("name: driftlab-vo\n",
                                                                     "built-in defaults", ".", sets)
                                          : pipeline::load_scenario(settings_, sets);
  const auto format =
      as_usage_error("--format", [&] { return dataset::format_from_name(format_); });
  dataset::ReadOptions read;
  read.sequence = sequence_;
  read.gt_topic = gt_topic_;
  read.calibration = calibration_;
  const dataset::StereoDataset data = dataset::read_dataset(dataset_, format, read);
  pipeline::DatasetRunOptions o;
  o.fusion_on_command_line = !fusion_.empty();
  o.max_frames = frames_ > 0 ? static_cast<std::size_t>(frames_) : 0;
  o.replace_existing = force_;
  o.progress = stderr;
  o.progress_tty = isatty(STDERR_FILENO) != 0;
  const auto summary = pipeline::run_on_dataset(data, settings, out_, o);
  std::cout << summary.brief() << "\n";
  std::cerr << fmt::format("driftlab vo: wrote {}\n", out_);
  return 0;
}

}  // namespace driftlab::app
