// The installed package (in-process plug-ins): `cmake --install`, then
// examples/custom_vo built against it with find_package(driftlab), its VO registered by name
// and run by its own driftlab command line beside the built-in ones.
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "core/trajectory_io.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab {
namespace {

namespace fs = std::filesystem;
using test::run_shell;
using test::shell_quote;

TEST(InstalledPackage, CustomVoProjectBuildsRegistersAndRuns) {
  const fs::path root = test::fresh_temp_dir("install");
  const fs::path prefix = root / "prefix", build = root / "build", run = root / "run";
  const std::string cmake = shell_quote(DRIFTLAB_CMAKE_COMMAND);
  auto r = run_shell(cmake + " --install " + shell_quote(test::binary_dir().string()) +
                     " --prefix " + shell_quote(prefix.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(prefix / "lib/cmake/driftlab/driftlabConfig.cmake"));
  EXPECT_TRUE(fs::exists(prefix / "include/vo/registry.hpp"));
  EXPECT_TRUE(fs::exists(prefix / "bin/driftlab"));
  r = run_shell(cmake + " -S " + shell_quote((test::source_dir() / "examples/custom_vo").string()) +
                " -B " + shell_quote(build.string()) + " -G " +
                shell_quote(DRIFTLAB_CMAKE_GENERATOR) +
                " -DCMAKE_PREFIX_PATH=" + shell_quote(prefix.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_shell(cmake + " --build " + shell_quote(build.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // The user's command line runs its VO beside the built-in sparse VO.
  const std::string scenario = (test::source_dir() / "scenarios/river_crossing.yaml").string();
  r = run_shell(shell_quote((build / "my-driftlab").string()) + " run " + shell_quote(scenario) +
                " --set pipeline.max_frames=100 --set 'pipeline.vo=[sparse, lk_pnp]' --set "
                "'pipeline.fusion=[]' --out " +
                shell_quote(run.string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto m = nlohmann::json::parse(test::slurp(run / "metrics.json"));
  EXPECT_TRUE(m["algorithms"].contains("lk_pnp"));
  EXPECT_TRUE(m["algorithms"].contains("sparse"));
  // A real VO: after 100 frames its end point is nearer the truth than half the way travelled.
  const Trajectory gt = read_tum(run / "groundtruth.tum");
  const Trajectory est = read_tum(run / "estimates/lk_pnp.tum");
  ASSERT_EQ(est.size(), gt.size());
  const double travelled = (gt.back().T_W_C.translation() - gt.front().T_W_C.translation()).norm();
  const double miss = (est.back().T_W_C.translation() - gt.back().T_W_C.translation()).norm();
  EXPECT_GT(travelled, 0.5);
  EXPECT_LT(miss, 0.5 * travelled) << "travelled " << travelled;

  // Its options (pipeline.plugins.lk_pnp) through driftlab's strict reader: set, written back,
  // documented, checked, and in effect (no frame has more inliers than corners detected).
  r = run_shell(shell_quote((build / "my-driftlab").string()) + " run " + shell_quote(scenario) +
                " --set pipeline.max_frames=12 --set 'pipeline.vo=[lk_pnp]' --set "
                "'pipeline.fusion=[]' --set pipeline.plugins.lk_pnp.max_corners=100 --out " +
                shell_quote((root / "few").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(test::slurp(root / "few/scenario.resolved.yaml")
                .find("    lk_pnp:\n      max_corners: 100  #"),
            std::string::npos);
  {
    std::istringstream frames(test::slurp(root / "few/frames.csv"));
    std::string line;
    auto cells_of = [](const std::string& row) {
      std::vector<std::string> cells;
      std::stringstream ss(row);
      for (std::string c; std::getline(ss, c, ',');) cells.push_back(c);
      return cells;
    };
    std::getline(frames, line);
    const std::vector<std::string> header = cells_of(line);
    const auto column = [&](const std::string& name) {
      const auto it = std::find(header.begin(), header.end(), name);
      EXPECT_NE(it, header.end()) << name << " in " << line;
      return static_cast<std::size_t>(it - header.begin());
    };
    const std::size_t valid_col = column("lk_pnp_valid"), inliers_col = column("lk_pnp_inliers");
    int valid = 0;
    while (std::getline(frames, line)) {
      const std::vector<std::string> cells = cells_of(line);
      ASSERT_GT(cells.size(), std::max(valid_col, inliers_col)) << line;
      if (cells[valid_col] != "1") continue;
      ++valid;
      EXPECT_LE(std::stoi(cells[inliers_col]), 100) << line;
    }
    EXPECT_GT(valid, 5);
  }
  const std::string my = shell_quote((build / "my-driftlab").string());
  r = run_shell(my + " scenario schema");
  EXPECT_NE(
      r.output.find("`pipeline.plugins.lk_pnp.max_corners` | integer | `600` | in [10, 10000]"),
      std::string::npos)
      << r.output.substr(0, 2000);
  r = run_shell(my + " scenario check -q " + shell_quote(scenario) +
                " --set pipeline.plugins.lk_pnp.max_corners=5");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("pipeline.plugins.lk_pnp.max_corners: got 5, expected a value in [10, "
                          "10000]"),
            std::string::npos)
      << r.output;
  r = run_shell(my + " scenario check -q " + shell_quote(scenario) +
                " --set pipeline.plugins.lk_pnp.min_inliers=700");
  EXPECT_EQ(r.exit_code, 1);
  EXPECT_NE(r.output.find("pipeline.plugins.lk_pnp.min_inliers: expected no more than max_corners"),
            std::string::npos)
      << r.output;

  // A sweep over the plug-in's option beside a built-in VO: planned, each job's scenario with
  // its value, and the first job run by the user's program.
  {
    std::ofstream sweep(root / "corners.yaml");
    sweep << "name: corners\nbase: "
          << (test::source_dir() / "tests/data/sweeps/tiny_base.yaml").string()
          << "\nseed: 3\ndesign: grid\nset:\n  pipeline.vo: [sparse, lk_pnp]\naxes:\n"
             "  - key: pipeline.plugins.lk_pnp.max_corners\n    values: [40, 200]\n";
  }
  r = run_shell(my + " sweep plan " + shell_quote((root / "corners.yaml").string()) + " --out " +
                shell_quote((root / "sweep").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = run_shell(my + " sweep run " + shell_quote((root / "sweep").string()) + " -j 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  std::vector<std::string> corners;
  for (const auto& job : fs::directory_iterator(root / "sweep/runs")) {
    const std::string resolved = test::slurp(job.path() / "scenario.resolved.yaml");
    for (const char* n : {"40", "200"})
      if (resolved.find(std::string("max_corners: ") + n + "  #") != std::string::npos)
        corners.push_back(n);
    const auto jm = nlohmann::json::parse(test::slurp(job.path() / "metrics.json"));
    EXPECT_TRUE(jm["algorithms"].contains("lk_pnp")) << job.path();
  }
  std::sort(corners.begin(), corners.end());
  EXPECT_EQ(corners, (std::vector<std::string>{"200", "40"}));
  r = run_shell(my + " sweep merge " + shell_quote((root / "sweep").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;

  // The installed driftlab reads the scene's meshes and the photographs' manifest from the
  // prefix (share/driftlab/assets), not from the source tree; DRIFTLAB_ASSET_DIR overrides both.
  EXPECT_TRUE(fs::exists(prefix / "share/driftlab/assets/bollard.obj"));
  const std::string installed = shell_quote((prefix / "bin/driftlab").string()) + " run " +
                                shell_quote(scenario) +
                                " --set pipeline.max_frames=2 --set 'pipeline.fusion=[]' --out ";
  r = run_shell("env -u DRIFTLAB_ASSET_DIR " + installed + shell_quote((root / "run2").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto m2 = nlohmann::json::parse(test::slurp(root / "run2/metrics.json"));
  EXPECT_EQ(fs::path(m2["render"]["assets"].get<std::string>()), prefix / "share/driftlab/assets");
  r = run_shell("DRIFTLAB_ASSET_DIR=" + shell_quote((root / "nowhere").string()) + " " + installed +
                shell_quote((root / "run3").string()));
  EXPECT_EQ(r.exit_code, 1);
  // The first shipped asset the river reach reads: the photographs' manifest.
  EXPECT_TRUE(fs::exists(prefix / "share/driftlab/assets/photographs.tsv"));
  EXPECT_NE(r.output.find("nowhere/photographs.tsv': cannot be read"), std::string::npos)
      << r.output;
  EXPECT_NE(r.output.find("$DRIFTLAB_ASSET_DIR"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(root / "run3"));

#ifdef DRIFTLAB_PYTHON_EXECUTABLE
  // `import driftlab` from the prefix's dist-packages: its runs read the prefix's assets too.
  fs::path site;
  for (const auto& e : fs::directory_iterator(prefix / "lib"))
    if (fs::exists(e.path() / "dist-packages/driftlab/__init__.py"))
      site = e.path() / "dist-packages";
  ASSERT_FALSE(site.empty()) << "no driftlab package under " << prefix / "lib";
  r = run_shell("env -u DRIFTLAB_ASSET_DIR PYTHONPATH=" + shell_quote(site.string()) + " " +
                shell_quote(DRIFTLAB_PYTHON_EXECUTABLE) + " -c " +
                shell_quote("import driftlab, sys; s = driftlab.Scenario.load(sys.argv[1], "
                            "set={'pipeline.max_frames': 2, 'pipeline.fusion': []}); "
                            "print(driftlab.run(s, sys.argv[2]).render.assets)") +
                " " + shell_quote(scenario) + " " + shell_quote((root / "run4").string()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find((prefix / "share/driftlab/assets").string()), std::string::npos)
      << r.output;
#endif

  // driftlab itself has no lk_pnp: the reader names the choices.
  auto plain =
      test::run_cli({"scenario", "check", scenario, "-q", "--set", "pipeline.vo=[lk_pnp]"});
  EXPECT_EQ(plain.exit_code, 1);
  EXPECT_NE(plain.err.find("got 'lk_pnp', expected one of: sparse, sparse_kf, pnp, dense"),
            std::string::npos)
      << plain.err;
  plain = test::run_cli(
      {"scenario", "check", scenario, "-q", "--set", "pipeline.plugins.lk_pnp.max_corners=40"});
  EXPECT_EQ(plain.exit_code, 1);
  EXPECT_NE(plain.err.find("pipeline.plugins: got 'lk_pnp', expected the name of a VO registered "
                           "with options (this program has none)"),
            std::string::npos)
      << plain.err;
  fs::remove_all(root);
}

}  // namespace
}  // namespace driftlab
