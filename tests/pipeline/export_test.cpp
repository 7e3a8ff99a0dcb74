// `driftlab export` and `driftlab vo`: a built-in VO on an exported dataset gives the estimate
// of a scenario run, frame for frame (same images, same stamps, same dropped frames).
#include "pipeline/export_stage.hpp"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <nlohmann/json.hpp>
#include <set>
#include <sstream>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/csv.hpp"
#include "core/trajectory_io.hpp"
#include "eval/evaluate.hpp"
#include "eval/sections.hpp"
#include "pipeline/dataset_run.hpp"
#include "pipeline/run.hpp"
#include "pipeline/vo_stage.hpp"
#include "record/run_record.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::pipeline {
namespace {

namespace fs = std::filesystem;
using test::slurp;

Scenario short_crossing_with_drops() {
  Scenario s = load_scenario(test::source_dir() / "scenarios/river_crossing.yaml");
  s.pipeline.max_frames = 30;
  s.pipeline.vo = {"sparse", "sparse_kf"};
  s.sensors.camera.clock.drop_probability = 0.1;
  s.eval.section_length_m = 0.25;  // sections in the 30 frames' metre or two
  return s;
}

// frames.csv's VO cells of each row, without the timing column (NAME_ms) and the mean depth,
// which is kept apart as a number: EuRoC's rig comes back through cam1's T_BS, whose baseline
// differs from the scenario's in the last bits, so the depths agree to about 1e-15, not in
// every printed digit.
struct VoCells {
  std::vector<std::string> rows;
  std::vector<double> mean_depths_m;  // NaN where the cell is empty
};

VoCells vo_cells(const fs::path& frames_csv, const std::string& name) {
  std::istringstream in(slurp(frames_csv));
  std::string line;
  std::getline(in, line);
  const auto header = split_csv_line(line);
  const auto names = split_csv_line(vo_csv_header(name).substr(1));
  const std::set<std::string> columns(names.begin(), names.end());
  VoCells out;
  while (std::getline(in, line)) {
    const auto cells = split_csv_line(line);
    std::string row = cells[0];  // t_ns
    for (std::size_t i = 0; i < header.size(); ++i)
      if (header[i] == name + "_mean_depth_m")
        out.mean_depths_m.push_back(cells[i].empty() ? std::nan("") : std::stod(cells[i]));
      else if (columns.count(header[i]) && header[i] != name + "_ms")
        row += "," + cells[i];
    out.rows.push_back(row);
  }
  return out;
}

void expect_same_vo_cells(const VoCells& a, const VoCells& b, const std::string& name) {
  EXPECT_EQ(a.rows, b.rows) << name;
  ASSERT_EQ(a.mean_depths_m.size(), b.mean_depths_m.size()) << name;
  for (std::size_t i = 0; i < a.mean_depths_m.size(); ++i) {
    const double x = a.mean_depths_m[i], y = b.mean_depths_m[i];
    EXPECT_EQ(std::isnan(x), std::isnan(y)) << name << " row " << i;
    if (!std::isnan(x)) {
      EXPECT_NEAR(x, y, 1e-9 * std::abs(x)) << name << " row " << i;
    }
  }
}

// The run's estimate against the dataset run's, both expressed relative to their first pose.
double largest_relative_difference(const Trajectory& a, const Trajectory& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    EXPECT_EQ(a[i].t_ns, b[i].t_ns);
    const SE3 ra = a.front().T_W_C.inverse() * a[i].T_W_C;
    const SE3 rb = b.front().T_W_C.inverse() * b[i].T_W_C;
    worst = std::max(worst, (ra.inverse() * rb).log().norm());
  }
  return worst;
}

class ExportRoundTrip : public ::testing::TestWithParam<dataset::DatasetFormat> {};

TEST_P(ExportRoundTrip, BuiltInVoOnTheExportGivesTheRunsEstimate) {
  const fs::path root = test::unused_temp_path("export_rt");
  const Scenario sc = short_crossing_with_drops();
  const fs::path run = root / "run", exported = root / "export", vo = root / "vo";
  run_scenario(sc, run, {});
  ExportOptions o;
  o.format = GetParam();
  const ExportSummary summary = export_dataset(sc, exported, o);
  const Trajectory run_sparse = read_tum(run / "estimates/sparse.tum");
  ASSERT_LT(run_sparse.size(), 30u);  // frames were dropped
  EXPECT_EQ(summary.frames, run_sparse.size());
  EXPECT_EQ(slurp(exported / "scenario.resolved.yaml"), slurp(run / "scenario.resolved.yaml"));

  const dataset::StereoDataset data = dataset::read_dataset(exported, GetParam());
  const Scenario settings = load_scenario(exported / "scenario.resolved.yaml");
  run_on_dataset(data, settings, vo, {});
  for (const char* name : {"sparse", "sparse_kf"}) {
    const Trajectory from_run = read_tum(run / "estimates" / (std::string(name) + ".tum"));
    const Trajectory from_vo = read_tum(vo / "estimates" / (std::string(name) + ".tum"));
    EXPECT_LT(largest_relative_difference(from_run, from_vo), 1e-9) << name;
    expect_same_vo_cells(vo_cells(run / "frames.csv", name), vo_cells(vo / "frames.csv", name),
                         name);
  }
  // The dataset's ground truth is the run's (KITTI: relative to the first camera).
  const Trajectory run_gt = read_tum(run / "groundtruth.tum");
  const Trajectory vo_gt = read_tum(vo / "groundtruth.tum");
  const auto vo_gt0 = dataset::pose_at(vo_gt, run_gt.front().t_ns);
  ASSERT_TRUE(vo_gt0.has_value());
  std::size_t compared = 0;
  const auto exact = [&](TimeNs t) {
    return std::any_of(vo_gt.begin(), vo_gt.end(),
                       [&](const StampedPose& q) { return q.t_ns == t; });
  };
  for (const StampedPose& p : run_gt) {  // EuRoC: body poses at 200 Hz, interpolated
    const auto T = dataset::pose_at(vo_gt, p.t_ns);
    // KITTI has a pose per delivered image only: no comparison at a dropped frame's time.
    if (!T || (GetParam() == dataset::DatasetFormat::kKitti && !exact(p.t_ns))) continue;
    const SE3 expected = run_gt.front().T_W_C.inverse() * p.T_W_C;
    EXPECT_LT(((vo_gt0->inverse() * *T).inverse() * expected).log().norm(), 1e-5) << p.t_ns;
    ++compared;
  }
  EXPECT_GE(compared, run_sparse.size() - 1);
  // `driftlab eval --covariates` on the VO run's frames.csv finds the covariates its own
  // evaluation used: the same sections.csv rows.
  const eval::FrameTable vo_frames = eval::read_frame_table((vo / "frames.csv").string());
  const std::string vo_sections = slurp(vo / "sections.csv");
  for (const std::string name : {"sparse", "sparse_kf_ca"}) {
    eval::EvaluationInput in;
    in.gt = data.camera_gt;
    in.est = read_tum(vo / "estimates" / (name + ".tum"));
    in.algorithm = name;
    in.options = settings.eval;
    in.frames = eval::run_vo_covariates(
        vo_frames, eval::run_vo_of(eval::run_vo_names(vo_frames), name), "frames.csv");
    const std::string csv = eval::sections_csv(eval::evaluate(in));
    EXPECT_EQ(csv.substr(0, csv.find('\n')), vo_sections.substr(0, vo_sections.find('\n')));
    auto rows_of = [&](const std::string& text) {
      std::istringstream in(text);
      std::vector<std::string> rows;
      for (std::string line; std::getline(in, line);)
        if (line.rfind(name + ",", 0) == 0) rows.push_back(line);
      return rows;
    };
    EXPECT_FALSE(rows_of(csv).empty()) << name;
    EXPECT_EQ(rows_of(csv), rows_of(vo_sections)) << name;
  }
  const auto metrics = nlohmann::json::parse(slurp(vo / "metrics.json"));
  EXPECT_TRUE(metrics["algorithms"].contains("sparse"));
  EXPECT_EQ(metrics["dataset"]["frames_used"].get<std::size_t>(), run_sparse.size());
  fs::remove_all(root);
}

// An export of `format` at 1 and 2 threads: the same bytes in every file (more than `files`).
void expect_same_bytes_whatever_the_thread_count(dataset::DatasetFormat format,
                                                 std::size_t files_at_least) {
  const fs::path root = test::unused_temp_path("export_threads");
  Scenario sc = short_crossing_with_drops();
  sc.pipeline.max_frames = 8;
  ExportOptions o;
  o.format = format;
  sc.pipeline.threads = 1;
  export_dataset(sc, root / "one", o);
  sc.pipeline.threads = 2;
  export_dataset(sc, root / "two", o);
  std::size_t files = 0;
  for (const auto& e : fs::recursive_directory_iterator(root / "one")) {
    if (!e.is_regular_file()) continue;
    const fs::path rel = fs::relative(e.path(), root / "one");
    if (rel == "scenario.resolved.yaml") continue;                     // says threads: 1 or 2
    EXPECT_TRUE(slurp(e.path()) == slurp(root / "two" / rel)) << rel;  // bytes: not printed
    ++files;
  }
  EXPECT_GT(files, files_at_least);
  fs::remove_all(root);
}

TEST_P(ExportRoundTrip, ExportIsTheSameBytesWhateverTheThreadCount) {
  // A bag keeps every stream in one file, beside its 6 calibration and info files.
  expect_same_bytes_whatever_the_thread_count(
      GetParam(), GetParam() == dataset::DatasetFormat::kRosbag ? 6u : 10u);
}

// A scene with movers (the crossing with its traffic, in a breeze that sways the trees) exports
// their masks beside the dataset:
// mask_0/NNNNNN.png for each frame and mask_0/moving_px.csv, whose share is the PNG's (read
// back by OpenCV), the same bytes with one or two threads.
TEST(ExportMasks, ATrafficSceneGetsAMaskPerFrameAndItsShare) {
  const fs::path root = test::unused_temp_path("export_masks");
  Scenario sc = load_scenario(test::source_dir() / "scenarios/river_crossing_traffic.yaml");
  sc.pipeline.max_frames = 5;
  sc.water.wind.speed_mps = 4.4;  // and the vegetation swaying: the survey's breeze
  ExportOptions o;
  o.format = dataset::DatasetFormat::kKitti;
  for (int threads : {1, 2}) {
    sc.pipeline.threads = threads;
    export_dataset(sc, root / std::to_string(threads), o);
  }
  std::istringstream csv(slurp(root / "1" / "mask_0" / "moving_px.csv"));
  std::string line;
  std::getline(csv, line);
  EXPECT_EQ(line, "frame,t_ns,moving_px");
  int frames = 0;
  while (std::getline(csv, line)) {
    const std::vector<std::string> cells = split_csv_line(line);
    ASSERT_EQ(cells.size(), 3u) << line;
    const fs::path png = root / "1" / "mask_0" / fmt::format("{:06d}.png", frames);
    const cv::Mat mask = cv::imread(png.string(), cv::IMREAD_UNCHANGED);
    ASSERT_FALSE(mask.empty()) << png;
    const double share = cv::countNonZero(mask) / static_cast<double>(mask.total());
    EXPECT_EQ(std::stod(cells[2]), share) << line;
    EXPECT_GT(share, 0.05) << line;  // the moored boat and the trees
    const fs::path rel = fs::relative(png, root / "1");
    EXPECT_TRUE(slurp(png) == slurp(root / "2" / rel)) << rel;
    ++frames;
  }
  EXPECT_EQ(frames, 5);
  EXPECT_EQ(slurp(root / "1" / "mask_0" / "moving_px.csv"),
            slurp(root / "2" / "mask_0" / "moving_px.csv"));
  fs::remove_all(root);
}

// A ROS 2 bag (written only: its round trip is the decoder test's, tests/dataset/rosbag_test):
// the database, metadata.yaml and the 6 calibration and info files.
TEST(ExportRosbag2, IsTheSameBytesWhateverTheThreadCount) {
  expect_same_bytes_whatever_the_thread_count(dataset::DatasetFormat::kRosbag2, 7u);
}

INSTANTIATE_TEST_SUITE_P(Formats, ExportRoundTrip,
                         ::testing::Values(dataset::DatasetFormat::kKitti,
                                           dataset::DatasetFormat::kEuroc,
                                           dataset::DatasetFormat::kRosbag),
                         [](const auto& info) {
                           switch (info.param) {
                             case dataset::DatasetFormat::kKitti:
                               return std::string("Kitti");
                             case dataset::DatasetFormat::kEuroc:
                               return std::string("Euroc");
                             default:
                               return std::string("Rosbag");
                           }
                         });

// EuRoC's ground truth rows of an export: t_ns and the numbers after it.
std::map<TimeNs, std::vector<double>> euroc_rows(const fs::path& csv) {
  std::istringstream in(slurp(csv));
  std::string line;
  std::getline(in, line);  // header
  std::map<TimeNs, std::vector<double>> rows;
  while (std::getline(in, line)) {
    const auto cells = split_csv_line(line);
    std::vector<double> values;
    for (std::size_t i = 1; i < cells.size(); ++i) values.push_back(std::stod(cells[i]));
    rows[std::stoll(cells[0])] = values;
  }
  return rows;
}

TEST(Export, EurocGroundTruthCarriesTheSimulatedImusBiases) {
  // A noise-free IMU whose biases walk: its reading is the true one plus the bias, so the
  // difference from the same IMU without biases is the bias at that sample, which the
  // ground truth's b_w_RS_S and b_a_RS_S columns must give at the same time stamps.
  const fs::path root = test::unused_temp_path("export_bias");
  Scenario sc = load_scenario(test::source_dir() / "scenarios/river_crossing.yaml");
  sc.pipeline.max_frames = 12;
  sc.sensors.imu.apply_preset(sim::ImuPreset::kIdeal);
  sc.sensors.imu.gyro_range_rad_s = sc.sensors.imu.accel_range_m_s2 = 0;
  ExportOptions o;
  o.format = dataset::DatasetFormat::kEuroc;
  export_dataset(sc, root / "plain", o);
  sc.sensors.imu.gyro_turn_on_bias_rad_s = 0.01;
  sc.sensors.imu.gyro_random_walk_rad_s2_sqrt_hz = 0.002;
  sc.sensors.imu.accel_turn_on_bias_m_s2 = 0.05;
  sc.sensors.imu.accel_random_walk_m_s3_sqrt_hz = 0.01;
  export_dataset(sc, root / "biased", o);
  const auto plain = euroc_rows(root / "plain/mav0/imu0/data.csv");
  const auto biased = euroc_rows(root / "biased/mav0/imu0/data.csv");
  const fs::path gt_csv = root / "biased/mav0/state_groundtruth_estimate0/data.csv";
  EXPECT_NE(slurp(gt_csv).find(",b_w_RS_S_x [rad s^-1]"), std::string::npos);
  const auto gt = euroc_rows(gt_csv);
  std::size_t compared = 0;
  double first_gyro_bias = 0, last_gyro_bias = 0;
  for (const auto& [t, row] : gt) {
    ASSERT_EQ(row.size(), 16u);  // p (3), q (4), v (3), b_w (3), b_a (3)
    const auto b = biased.find(t), p = plain.find(t);
    if (b == biased.end() || p == plain.end()) continue;
    for (int i = 0; i < 6; ++i)  // w_RS_S (3) then a_RS_S (3): the same order as b_w, b_a
      EXPECT_NEAR(row[10 + i], b->second[i] - p->second[i], 1e-9) << t << " " << i;
    (compared ? last_gyro_bias : first_gyro_bias) = row[10];
    ++compared;
  }
  EXPECT_GT(compared, 200u);                   // 1.3 s at 200 Hz
  EXPECT_NE(first_gyro_bias, last_gyro_bias);  // the bias walks
  // The IMU without biases: columns of zeros.
  for (const auto& [t, row] : euroc_rows(root / "plain/mav0/state_groundtruth_estimate0/data.csv"))
    for (int i = 10; i < 16; ++i) EXPECT_EQ(row.at(i), 0.0) << t;
  fs::remove_all(root);
}

// A scenario with every filter and no GPS (a dataset's GPS fixes are not read: they carry no
// validity time) and no dropped frames (the run's ESKF starts at the first frame, dropped or
// not; the dataset's at its first image).
Scenario filtered_crossing() {
  Scenario s = load_scenario(test::source_dir() / "scenarios/river_crossing.yaml");
  s.pipeline.max_frames = 30;
  s.pipeline.vo = {"sparse"};
  s.pipeline.fusion = {FusionAlgorithm::kCaSmoother, FusionAlgorithm::kEskf,
                       FusionAlgorithm::kNedKf, FusionAlgorithm::kNedPf};
  s.pipeline.ca_smoother.rts_backward_pass = true;  // NAME_ca_rts too
  s.sensors.gps.enabled = false;
  return s;
}

const char* const kFilteredEstimates[] = {"sparse",      "sparse_ca",     "sparse_ca_rts",
                                          "sparse_eskf", "sparse_ned_kf", "sparse_ned_pf"};

TEST(ExportFilters, EveryFilterOnTheEurocExportFollowsTheRunsFilter) {
  // The export carries the IMU with its noise model, the compass and the camera's mount, so
  // each filter on the dataset gives the run's estimate. Compared relative to the first pose,
  // as for the VOs: the dataset's anchor is its 200 Hz ground truth interpolated at the first
  // frame, which moves the whole estimate by a few micrometres.
  const fs::path root = test::unused_temp_path("export_filters");
  const Scenario sc = filtered_crossing();
  run_scenario(sc, root / "run", {});
  ExportOptions o;
  o.format = dataset::DatasetFormat::kEuroc;
  export_dataset(sc, root / "export", o);
  const dataset::StereoDataset data = dataset::read_dataset(root / "export", o.format);
  ASSERT_TRUE(data.imu_noise.has_value());
  EXPECT_EQ(data.imu_noise->gyroscope_noise_density,
            sc.sensors.imu.gyro_noise_density_rad_s_sqrt_hz);
  EXPECT_FALSE(data.compass.empty());
  const auto summary =
      run_on_dataset(data, load_scenario(root / "export/scenario.resolved.yaml"), root / "vo", {});
  for (const char* name : kFilteredEstimates) {
    const Trajectory from_run = read_tum(root / "run/estimates" / (std::string(name) + ".tum"));
    const Trajectory from_vo = read_tum(root / "vo/estimates" / (std::string(name) + ".tum"));
    EXPECT_LT(largest_relative_difference(from_run, from_vo), 1e-9) << name;
  }
  // Both runs' metrics.json (a scenario run's, and `driftlab vo`'s with its dataset and levelled
  // world), read into the typed record and written back, are the same bytes.
  for (const char* folder : {"run", "vo"})
    EXPECT_EQ(record::metrics_text(record::read_run_record(root / folder)),
              slurp(root / folder / "metrics.json"))
        << folder;
  const auto run = nlohmann::json::parse(slurp(root / "run/metrics.json"));
  const auto vo = nlohmann::json::parse(slurp(root / "vo/metrics.json"));
  for (const char* name : {"sparse_eskf", "sparse_ned_kf", "sparse_ned_pf"})  // same inputs
    EXPECT_EQ(run["algorithms"][name]["filter"], vo["algorithms"][name]["filter"]) << name;
  EXPECT_EQ(vo["filters_world"]["down_axis"], "+z");  // the scenario's world is NED
  EXPECT_LT(vo["filters_world"]["tilt_deg"].get<double>(), 1.0);
  EXPECT_GT(vo["algorithms"]["sparse_eskf"]["filter"]["imu_samples"].get<int>(), 100);
  fs::remove_all(root);
}

TEST(ExportFilters, ADatasetWhoseWorldIsZUpGivesTheSameEstimatesInItsWorld) {
  // EuRoC's own ground truth is in a z-up world. The same export with its ground truth turned
  // half a turn about north (z up, y west): every estimate, filters included, is the first
  // one's turned the same way, because the filters level the world on gravity.
  const fs::path root = test::unused_temp_path("export_zup");
  Scenario sc = filtered_crossing();
  sc.pipeline.max_frames = 15;
  ExportOptions o;
  o.format = dataset::DatasetFormat::kEuroc;
  export_dataset(sc, root / "export", o);
  const Scenario settings = load_scenario(root / "export/scenario.resolved.yaml");
  run_on_dataset(dataset::read_dataset(root / "export", o.format), settings, root / "ned", {});
  const fs::path gt = root / "export/mav0/state_groundtruth_estimate0/data.csv";
  const SE3 T_U_N(Mat3(Vec3(1, -1, -1).asDiagonal()), Vec3::Zero());
  Trajectory turned = read_euroc_groundtruth(gt);
  for (StampedPose& p : turned) p.T_W_C = T_U_N * p.T_W_C;
  write_euroc_groundtruth(gt, turned);
  run_on_dataset(dataset::read_dataset(root / "export", o.format), settings, root / "zup", {});
  for (const char* name : kFilteredEstimates) {
    const Trajectory ned = read_tum(root / "ned/estimates" / (std::string(name) + ".tum"));
    Trajectory zup = read_tum(root / "zup/estimates" / (std::string(name) + ".tum"));
    ASSERT_EQ(ned.size(), zup.size()) << name;
    double worst = 0;
    for (std::size_t i = 0; i < ned.size(); ++i)
      worst = std::max(worst, ((T_U_N * ned[i].T_W_C).inverse() * zup[i].T_W_C).log().norm());
    EXPECT_LT(worst, 1e-12) << name;
  }
  const auto metrics = nlohmann::json::parse(slurp(root / "zup/metrics.json"));
  EXPECT_EQ(metrics["filters_world"]["down_axis"], "-z");
  fs::remove_all(root);
}

TEST(ExportFilters, AFilterTheDatasetCannotFeedIsAnErrorWhenAskedForAndSkippedOtherwise) {
  const fs::path root = test::unused_temp_path("export_nofeed");
  const std::string scenario = (test::source_dir() / "scenarios/river_crossing.yaml").string();
  auto r = test::run_cli({"export", scenario, "--frames", "4", "--out", (root / "kitti").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cli({"vo", (root / "kitti").string(), "--fusion", "ca_smoother,eskf", "--out",
                     (root / "vo").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("--fusion: eskf needs the camera's pose on the body"), std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(root / "vo"));
  // From the settings (the export's own scenario asks for the ESKF): skipped, and said so.
  r = test::run_cli({"vo", (root / "kitti").string(), "--set",
                     "pipeline.fusion=[ca_smoother, eskf]", "--out", (root / "vo").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(root / "vo/estimates/sparse_ca.tum"));
  EXPECT_FALSE(fs::exists(root / "vo/estimates/sparse_eskf.tum"));
  const auto metrics = nlohmann::json::parse(slurp(root / "vo/metrics.json"));
  // One warning says so (others, such as a filter no better than its VO, depend on the frames).
  const auto& warnings = metrics["warnings"];
  EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                          [](const nlohmann::json& w) {
                            return w.get<std::string>().find("eskf needs") != std::string::npos;
                          }),
            1)
      << warnings.dump();
  fs::remove_all(root);
}

TEST(ExportCli, WritesEachFormatAndVoReadsIt) {
  const fs::path root = test::unused_temp_path("export_cli");
  const std::string scenario = (test::source_dir() / "scenarios/river_crossing.yaml").string();
  auto r = test::run_cli({"export", scenario, "--format", "tum-rgbd", "--frames", "3", "--out",
                          (root / "tum").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(root / "tum" / "depth.txt"));
  EXPECT_TRUE(fs::exists(root / "tum" / "info.yaml"));
  r = test::run_cli({"export", scenario, "--format", "mcap", "--out", (root / "x").string()});
  EXPECT_EQ(r.exit_code, 2);  // a bad command line
  EXPECT_NE(r.err.find("--format: unknown dataset format: got 'mcap', expected one of: kitti, "
                       "euroc, tum-rgbd, rosbag, rosbag2"),
            std::string::npos)
      << r.err;
  EXPECT_FALSE(fs::exists(root / "x"));  // nothing half-written
  r = test::run_cli({"export", scenario, "--frames", "5", "--out", (root / "kitti").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = test::run_cli(
      {"vo", (root / "kitti").string(), "--algo", "sparse,pnp", "--out", (root / "vo").string()});
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(root / "vo" / "estimates" / "pnp.tum"));
  EXPECT_TRUE(fs::exists(root / "vo" / "tables.md"));
  r = test::run_cli(
      {"vo", (root / "kitti").string(), "--algo", "orb", "--out", (root / "vo2").string()});
  EXPECT_EQ(r.exit_code, 2);  // a bad command line
  EXPECT_NE(r.err.find("'orb'"), std::string::npos) << r.err;
  r = test::run_cli(
      {"vo", (root / "tum").string(), "--format", "tum-rgbd", "--out", (root / "vo3").string()});
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.err.find("has one camera"), std::string::npos) << r.err;
  fs::remove_all(root);
}

}  // namespace
}  // namespace driftlab::pipeline
