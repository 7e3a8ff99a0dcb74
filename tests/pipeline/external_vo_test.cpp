// External VOs in a run: a real VO behind a command gives the built-in estimate; a command
// that fails, hangs or writes garbage is recorded and the run keeps its other results.
#include "pipeline/external_vo.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>

#include "core/error.hpp"
#include "core/trajectory_io.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::pipeline {
namespace {

namespace fs = std::filesystem;
using test::slurp;

std::string script(const std::string& name) {
  return "sh " + (test::source_dir() / "tests/data/external_vo" / name).string();
}

TEST(ExternalVo, CommandPlaceholdersAreQuotedAndUnknownOnesRejected) {
  EXPECT_EQ(expand_command("myvo --calib {dir}/calib.txt {dir} > {out}", "/d/it's", "/r", "/o",
                           "/bin/driftlab"),
            "myvo --calib '/d/it'\\''s'/calib.txt '/d/it'\\''s' > '/o'");
  EXPECT_EQ(expand_command("{driftlab} vo {root}", "/d", "/r", "/o", "/x"), "'/x' vo '/r'");
  try {
    expand_command("myvo {calib}", "/d", "/r", "/o", "/x");
    FAIL() << "no error";
  } catch (const UserError& e) {
    EXPECT_NE(std::string(e.what()).find("got '{calib}', expected placeholders"), std::string::npos)
        << e.what();
  }
  // The shell's braces stay as written: ${VAR} and anything but one word in braces.
  EXPECT_EQ(expand_command("echo ${HOME} | awk '{ print $1 }' > {out}; f() { :; }", "/d", "/r",
                           "/o", "/x"),
            "echo ${HOME} | awk '{ print $1 }' > '/o'; f() { :; }");
  EXPECT_EQ(expand_command("{out}{dir}{", "/d", "/r", "/o", "/x"), "'/o''/d'{");
  EXPECT_EQ(unknown_command_placeholder("a {dir} ${x} { y } {outt} {z}"), "{outt}");
  EXPECT_EQ(unknown_command_placeholder("a {dir} ${x} { y } {out}"), "");
}

TEST(ExternalVo, AnUnknownPlaceholderIsAScenarioErrorWithItsLine) {
  // Found when the scenario is read, not after the frame loop.
  try {
    parse_scenario(
        "name: x\npipeline:\n  external_vo:\n    - name: a\n      command: 'myvo {outt}'\n",
        "t.yaml", ".");
    FAIL() << "no error";
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("t.yaml:5:"), std::string::npos) << what;
    EXPECT_NE(what.find("command: got 'myvo {outt}', expected placeholders {dir}, {root}, {out} "
                        "or {driftlab} only, not {outt}"),
              std::string::npos)
        << what;
  }
  // The same through --set, named by it.
  try {
    parse_scenario("name: x\n", "t.yaml", ".",
                   {"pipeline.external_vo=[{name: a, command: 'x {outt}'}]"});
    FAIL() << "no error";
  } catch (const UserError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("--set pipeline.external_vo=[{name: a, command: 'x {outt}'}]: "
                        "pipeline.external_vo[0].command: got 'x {outt}', expected placeholders"),
              std::string::npos)
        << what;
  }
}

TEST(ExternalVo, NamesMustBeNewUniqueAndFileSafe) {
  const auto error_of = [](const std::string& list) {
    try {
      parse_scenario("name: x\npipeline: {external_vo: " + list + "}\n", "t.yaml", ".");
    } catch (const UserError& e) {
      return std::string(e.what());
    }
    return std::string("(no error)");
  };
  EXPECT_NE(error_of("[{name: sparse, command: a}]").find("got 'sparse', a built-in VO's name"),
            std::string::npos);
  EXPECT_NE(error_of("[{name: a, command: x}, {name: a, command: y}]").find("got 'a' twice"),
            std::string::npos);
  EXPECT_NE(error_of("[{name: 'a/b', command: x}]").find("letters, digits"), std::string::npos);
  EXPECT_NE(error_of("[{name: a, command: x, output: ply}]").find("expected one of: tum, kitti"),
            std::string::npos);
  EXPECT_NE(error_of("[{name: a, command: x, timeout_s: 0}]").find("timeout_s"), std::string::npos);
  EXPECT_EQ(error_of("[{name: my-vo_2, command: x, format: euroc, output: euroc}]"), "(no error)");
}

double largest_difference(const Trajectory& a, const Trajectory& b) {
  EXPECT_EQ(a.size(), b.size());
  double worst = 0;
  for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
    EXPECT_EQ(a[i].t_ns, b[i].t_ns);
    worst = std::max(worst, (a[i].T_W_C.inverse() * b[i].T_W_C).log().norm());
  }
  return worst;
}

TEST(ExternalVo, RealFailingHangingAndGarbageCommandsAreEachRecorded) {
  const fs::path out = test::unused_temp_path("external_vo_run");
  const std::string list =
      "[{name: mine, command: '" + script("driftlab_sparse.sh") +
      " {driftlab} {dir} {root} {out}'}, {name: broken, command: '" + script("exit1.sh") +
      " {dir}'}, {name: stuck, command: '" + script("hang.sh") +
      "', timeout_s: 1}, {name: deaf, command: \"trap '' TERM; sleep 300\", timeout_s: 1}, "
      "{name: junk, command: '" +
      script("garbage.sh") +
      " {out}'}, {name: mine_euroc, format: euroc, output: tum, command: 'test -f "
      "{dir}/mav0/imu0/data.csv && test -f {dir}/mav0/state_groundtruth_estimate0/data.csv && "
      "cp {root}/../../mine/trajectory.tum {out}'}, {name: mine_bag, format: rosbag, command: '" +
      script("driftlab_sparse.sh") +
      " {driftlab} {dir} {root} {out} rosbag'}, {name: mine_ros2, format: rosbag2, output: tum, "
      "command: 'test -f {dir}/rosbag2/metadata.yaml && test -f {dir}/rosbag2/rosbag2_0.db3 && "
      "cp {root}/../../mine/trajectory.tum {out}'}, {name: late, command: 'tail -n +6 "
      "{root}/../../mine/trajectory.tum > {out}'}]";
  const auto t0 = std::chrono::steady_clock::now();
  const auto r = test::run_cli(
      {"run", (test::source_dir() / "scenarios/river_crossing.yaml").string(), "--set",
       "pipeline.max_frames=20", "--set", "pipeline.external_vo=" + list, "--out", out.string()});
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_LT(seconds, 60);  // the hanging command was killed at its 1 s limit
  const auto m = nlohmann::json::parse(slurp(out / "metrics.json"));
  const auto& ext = m["external_vo"];
  EXPECT_EQ(ext["mine"]["status"], "ok");
  EXPECT_EQ(ext["mine_euroc"]["status"], "ok");  // a EuRoC export with IMU and ground truth
  EXPECT_EQ(ext["broken"]["status"], "failed");
  EXPECT_EQ(ext["broken"]["exit"], "exit code 1");
  EXPECT_NE(ext["broken"]["log_tail"].get<std::string>().find("permission denied"),
            std::string::npos);
  EXPECT_EQ(ext["stuck"]["status"], "timeout");
  // Deaf to timeout's TERM: killed 5 s later, timeout with it.
  EXPECT_EQ(ext["deaf"]["status"], "timeout");
  EXPECT_EQ(ext["deaf"]["exit"], "killed by signal 9 (Killed)");
  EXPECT_EQ(ext["junk"]["status"], "bad output");
  // Paths name the run's folder, not the temporary one it had until the end.
  EXPECT_NE(
      ext["mine"]["command"].get<std::string>().find((out / "external/mine/dataset").string()),
      std::string::npos)
      << ext["mine"]["command"];
  EXPECT_NE(ext["junk"]["message"].get<std::string>().find(
                (out / "external/junk/trajectory.tum").string() + ":1:"),
            std::string::npos)
      << ext["junk"]["message"];
  EXPECT_EQ(m.dump().find(".tmp."), std::string::npos);
  EXPECT_NE(ext["junk"]["message"].get<std::string>().find("expected 8 columns"),
            std::string::npos);
  const std::string warnings = m["warnings"].dump();
  for (const char* name : {"'broken'", "'stuck'", "'deaf'", "'junk'"})
    EXPECT_NE(warnings.find(name), std::string::npos) << name;
  // The real VO behind the command is driftlab's sparse VO on the export: the built-in estimate.
  EXPECT_TRUE(m["algorithms"].contains("mine"));
  EXPECT_TRUE(m["algorithms"].contains("sparse"));
  EXPECT_FALSE(m["algorithms"].contains("broken"));
  EXPECT_LT(largest_difference(read_tum(out / "estimates/mine.tum"),
                               read_tum(out / "estimates/sparse.tum")),
            1e-9);
  // The same VO reading the run's frames from a ROS 1 bag.
  EXPECT_EQ(ext["mine_bag"]["status"], "ok") << ext["mine_bag"];
  EXPECT_EQ(ext["mine_ros2"]["status"], "ok") << ext["mine_ros2"];  // a ROS 2 bag to read
  EXPECT_LT(largest_difference(read_tum(out / "estimates/mine_bag.tum"),
                               read_tum(out / "estimates/sparse.tum")),
            1e-9);
  // A VO that starts at the sixth frame (a stereo-inertial one initialising) is anchored at
  // that frame's true pose, not at the first's.
  EXPECT_EQ(ext["late"]["status"], "ok") << ext["late"];
  {
    // mine's poses are its raw ones anchored at the first frame; late's the same raw poses from
    // its first stamp on, anchored there: truth(t_k) mine_k^-1 mine_j.
    const Trajectory mine = read_tum(out / "estimates/mine.tum");
    const Trajectory late = read_tum(out / "estimates/late.tum");
    const Trajectory truth = read_tum(out / "groundtruth.tum");
    ASSERT_GT(late.size(), 3U);
    const auto at = [&](const Trajectory& t, TimeNs stamp) {
      const auto p =
          std::find_if(t.begin(), t.end(), [&](const StampedPose& q) { return q.t_ns == stamp; });
      EXPECT_NE(p, t.end()) << stamp;
      return static_cast<std::size_t>(p - t.begin());
    };
    const std::size_t k = at(mine, late.front().t_ns);
    EXPECT_GT(k, 0U);  // it does start later than mine
    Trajectory expected(mine.begin() + static_cast<std::ptrdiff_t>(k), mine.end());
    const SE3 anchor = truth[at(truth, late.front().t_ns)].T_W_C * mine[k].T_W_C.inverse();
    for (auto& p : expected) p.T_W_C = anchor * p.T_W_C;
    EXPECT_LT(largest_difference(late, expected), 1e-9);
  }
  EXPECT_NE(slurp(out / "report.md").find("| stuck | timeout | exit code 124 |"),
            std::string::npos);
  // The datasets are removed after the commands (keep_dataset: false); the logs stay.
  EXPECT_FALSE(fs::exists(out / "external/mine/dataset"));
  EXPECT_TRUE(fs::exists(out / "external/broken/log.txt"));
  fs::remove_all(out);
}

// The peers' runners (examples/external/*.sh), as the README runs them, with each system's
// program replaced by a stand-in (tests/data/peers/) that reads the files the export hands it
// as that system does and writes the system's own trajectory format from the true poses, in a
// world frame of its own: driftlab must read every one back as the truth.
TEST(ExternalVo, EachPeersRunnerReadsItsSystemsTrajectoryFormatAsTheTruth) {
  const fs::path out = test::unused_temp_path("external_vo_peers");
  const fs::path peers = test::source_dir() / "tests/data/peers";
  const auto r = test::run_shell(
      "cd " + test::shell_quote(test::source_dir().string()) +
      " && DRIFTLAB_OPENVINS=" + test::shell_quote((peers / "openvins").string()) +
      " DRIFTLAB_VINS_FUSION=" + test::shell_quote((peers / "vins-fusion").string()) +
      " DRIFTLAB_BASALT=" + test::shell_quote((peers / "basalt").string()) + " " +
      test::shell_quote(test::cli_path().string()) +
      " run scenarios/river_crossing.yaml --set pipeline.max_frames=12 --set "
      "\"pipeline.external_vo=$(cat examples/external/openvins.yaml "
      "examples/external/vins-fusion.yaml examples/external/basalt.yaml)\" --out " +
      test::shell_quote(out.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto m = nlohmann::json::parse(slurp(out / "metrics.json"));
  const Trajectory truth = read_tum(out / "groundtruth.tum");
  for (const char* name :
       {"openvins", "vins_fusion_imu", "vins_fusion", "basalt_vio", "basalt_vo"}) {
    SCOPED_TRACE(name);
    ASSERT_EQ(m["external_vo"][name]["status"], "ok") << m["external_vo"][name];
    const Trajectory estimate = read_tum(out / "estimates" / (std::string(name) + ".tum"));
    ASSERT_EQ(estimate.size(), truth.size());
    for (std::size_t i = 0; i < truth.size(); ++i) {
      // OpenVINS writes seconds with 5 decimals: its stamps are the frames' to 5 us.
      EXPECT_LE(std::abs(estimate[i].t_ns - truth[i].t_ns), 5000);
      // The systems' own precision: 5 decimals (VINS-Fusion) over a few metres of lever.
      const SE3 d = truth[i].T_W_C.inverse() * estimate[i].T_W_C;
      EXPECT_LT(d.translation().norm(), 2e-3);
      EXPECT_LT(Eigen::AngleAxisd(d.quaternion()).angle(), 1e-4);
    }
  }
  fs::remove_all(out);
}

// A runner handed a configuration its system does not have stops before running it, names the
// file, and writes no trajectory.
TEST(ExternalVo, BasaltsRunnerRefusesAConfigurationBasaltDoesNotHave) {
  const fs::path out = test::unused_temp_path("external_vo_basalt_config");
  fs::create_directories(out);
  const fs::path peers = test::source_dir() / "tests/data/peers";
  const auto r = test::run_shell(
      "cd " + test::shell_quote(test::source_dir().string()) +
      " && DRIFTLAB_BASALT=" + test::shell_quote((peers / "basalt").string()) +
      " bash examples/external/basalt.sh /nonexistent " +
      test::shell_quote((out / "trajectory.csv").string()) + " vio euroc_configg.json");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("CONFIG 'euroc_configg.json': no such file"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(out / "trajectory.csv"));
  fs::remove_all(out);
}

}  // namespace
}  // namespace driftlab::pipeline
