// The photographed materials (scenes/photographs.hpp): the manifest, the SHA-256 check, the
// decoding, and the river reach's use of them. The photographs are fetched by
// scripts/fetch-materials (scripts/build runs it).
#include "scenes/photographs.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "core/error.hpp"
#include "scenes/river_reach.hpp"
#include "scenes/scene_options.hpp"
#include "scenes/textures.hpp"
#include "tests/support/test_support.hpp"

namespace driftlab::scenes {
namespace {

using test::expect_user_error;

// Every TextureKind, to find a manifest row's kind among them.
TextureKind kind_named(const std::string& name) {
  for (int k = 0; k <= static_cast<int>(TextureKind::kMetalPanel); ++k)
    if (texture_kind_name(static_cast<TextureKind>(k)) == name) return static_cast<TextureKind>(k);
  ADD_FAILURE() << "no texture kind named '" << name << "'";
  return TextureKind::kGrass;
}

// Sets an environment variable for one test (DRIFTLAB_MATERIALS, DRIFTLAB_ASSET_DIR).
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const std::string& value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = old, had_ = true;
    setenv(name, value.c_str(), 1);
  }
  ~ScopedEnv() {
    if (had_)
      setenv(name_, old_.c_str(), 1);
    else
      unsetenv(name_);
  }

 private:
  const char* name_;
  std::string old_;
  bool had_ = false;
};

TEST(Photographs, Sha256OfTheFipsTestVectors) {
  // FIPS 180-2, Appendix B.1 and B.2.
  EXPECT_EQ(sha256_hex("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
  EXPECT_EQ(sha256_hex("abcdbcdecdefdefgefghfghighijhijkijkljklmklmnlmnomnopnopq"),
            "248d6a61d20638b8e5c026930c3e6039a33ce45964ff2167f6ecedd419db06c1");
}

TEST(Photographs, ManifestNamesKnownKindsOnceEach) {
  const std::vector<PhotographEntry> rows = photograph_manifest();
  ASSERT_GE(rows.size(), 4u);
  std::set<std::string> kinds;
  for (const PhotographEntry& e : rows) {
    kind_named(e.kind);
    EXPECT_TRUE(kinds.insert(e.kind).second) << e.kind << " twice";
    EXPECT_FALSE(e.licence.empty());
    EXPECT_FALSE(e.credit.empty());
  }
}

TEST(Photographs, EveryFileMatchesItsChecksumAsSha256sumComputesIt) {
  // The fetched files against the manifest, through coreutils' sha256sum (a second
  // implementation).
  for (const PhotographEntry& e : photograph_manifest()) {
    const std::string path = (std::filesystem::path(materials_dir()) / e.file_name()).string();
    const test::CommandResult r = test::run_shell("sha256sum " + test::shell_quote(path));
    ASSERT_EQ(r.exit_code, 0) << r.output << " (scripts/fetch-materials fetches the files)";
    EXPECT_EQ(r.out.substr(0, 64), e.sha256) << path;
    EXPECT_EQ(sha256_hex(test::slurp(path)), e.sha256) << path;
  }
}

TEST(Photographs, TextureIsThePhotographHalvedAndScaledToTheMean) {
  for (const PhotographEntry& e : photograph_manifest()) {
    const std::string path = (std::filesystem::path(materials_dir()) / e.file_name()).string();
    cv::Mat gray = cv::imread(path, cv::IMREAD_GRAYSCALE);
    ASSERT_FALSE(gray.empty()) << path;
    for (int turn = 0; turn < e.quarter_turns; ++turn)
      cv::transpose(gray, gray), cv::flip(gray, gray, 1);
    // A photograph twice as tall as wide is laid twice side by side (and so on).
    const int edge = std::max(gray.cols, gray.rows);
    gray = cv::repeat(gray, edge / gray.rows, edge / gray.cols);
    const sim::Texture t = load_photograph(kind_named(e.kind), 100.0, 256);
    // The expectation in double: the mean of each block of whole pixels, without the
    // implementation's rounding at every halving.
    int factor = 1;
    while (std::max(gray.cols, gray.rows) / factor > 256) factor *= 2;
    ASSERT_EQ(t.width, gray.cols / factor) << path;
    ASSERT_EQ(t.height, gray.rows / factor) << path;
    std::vector<double> block(static_cast<std::size_t>(t.width) * t.height, 0.0);
    double sum = 0;
    for (int y = 0; y < t.height * factor; ++y)
      for (int x = 0; x < t.width * factor; ++x)
        block[static_cast<std::size_t>(y / factor) * t.width + x / factor] +=
            gray.at<std::uint8_t>(y, x) / double(factor * factor);
    for (double b : block) sum += b;
    const double gain = 100.0 / (sum / static_cast<double>(block.size()));
    int worst = 0;
    for (std::size_t i = 0; i < block.size(); ++i) {
      const double want = std::clamp(block[i] * gain, 0.0, 255.0);
      worst = std::max(worst, static_cast<int>(std::ceil(std::abs(t.pixels[i] - want))));
    }
    // Rounding at each halving (half a grey level each) and at the scaling.
    EXPECT_LE(worst, 2 + static_cast<int>(std::ceil(std::log2(factor) * 0.5 * gain))) << path;
    EXPECT_NEAR(mean_gray(t), 100.0, 1.0) << path;
    EXPECT_EQ(t.name, e.kind);
  }
}

TEST(Photographs, MalformedManifestRowsNameFileLineFieldAndValue) {
  const auto dir = test::fresh_temp_dir("bad_manifest");
  const std::string manifest = (dir / "photographs.tsv").string();
  const ScopedEnv env("DRIFTLAB_ASSET_DIR", dir.string());
  const std::string sha(64, 'a');
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"grass\t" + sha + "\tx/grass.jpg\t0\tGPL-2+",
       manifest + " line 2: 5 tab-separated fields, expected 6"},
      {"grass\tABC\tx/grass.jpg\t0\tGPL-2+\tsomeone",
       manifest + " line 2: field sha256: 'ABC' is not 64 lower-case hex digits"},
      {"grass\t" + sha + "\tx/grass.jpg\t4\tGPL-2+\tsomeone",
       manifest + " line 2: field quarter_turns: '4', expected 0, 1, 2 or 3"},
      {"grass\t" + sha + "\tx/grass.tga\t0\tGPL-2+\tsomeone",
       manifest + " line 2: field source: 'x/grass.tga' is not a .jpg or .png file"}};
  for (const auto& [row, message] : cases) {
    std::ofstream(manifest) << "# a comment\n" << row << "\n";
    expect_user_error([] { photograph_manifest(); }, message);
  }
  std::filesystem::remove_all(dir);
}

TEST(Photographs, MissingFolderNamesTheFileAndTheFetchScript) {
  const auto dir = test::fresh_temp_dir("no_materials");
  const ScopedEnv env("DRIFTLAB_MATERIALS", dir.string());
  const PhotographEntry e = photograph_manifest().front();
  expect_user_error([&] { load_photograph(kind_named(e.kind), 100.0); },
                    (dir / e.file_name()).string() + "' (" + e.kind + ") is missing");
  expect_user_error([&] { load_photograph(kind_named(e.kind), 100.0); }, "scripts/fetch-materials");
  // A scenario's river reach says the same; without photographs it needs none.
  RiverReachOptions o;
  expect_user_error([&] { build_river_reach(o, Sky::kOvercast, 1, 0, 10); },
                    "scripts/fetch-materials");
  o.photographs = false;
  EXPECT_NO_THROW(build_river_reach(o, Sky::kOvercast, 1, 0, 10));
  std::filesystem::remove_all(dir);
}

TEST(Photographs, AnotherFileIsRefusedWithBothChecksums) {
  const auto dir = test::fresh_temp_dir("altered_materials");
  const PhotographEntry e = photograph_manifest().front();
  const std::string original = (std::filesystem::path(materials_dir()) / e.file_name()).string();
  std::string bytes = test::slurp(original);
  ASSERT_FALSE(bytes.empty()) << original;
  bytes[bytes.size() / 2] ^= 1;
  std::ofstream(dir / e.file_name(), std::ios::binary) << bytes;
  const ScopedEnv env("DRIFTLAB_MATERIALS", dir.string());
  const std::string message =
      test::user_error_of([&] { load_photograph(kind_named(e.kind), 100); });
  EXPECT_NE(message.find(e.sha256), std::string::npos) << message;
  EXPECT_NE(message.find(sha256_hex(bytes)), std::string::npos) << message;
  EXPECT_NE(message.find(e.source), std::string::npos) << message;
  std::filesystem::remove_all(dir);
}

TEST(Photographs, RiverReachUsesThemForTheirKindsOnly) {
  RiverReachOptions with, without;
  without.photographs = false;
  const sim::SceneGeometry a = build_river_reach(with, Sky::kOvercast, 7, 0, 10);
  const sim::SceneGeometry b = build_river_reach(without, Sky::kOvercast, 7, 0, 10);
  ASSERT_EQ(a.textures.size(), b.textures.size());
  std::set<std::string> photographed;
  for (const PhotographEntry& e : photograph_manifest()) photographed.insert(e.kind);
  int replaced = 0;
  for (std::size_t i = 0; i < a.textures.size(); ++i) {
    ASSERT_EQ(a.textures[i].name, b.textures[i].name);
    if (photographed.count(a.textures[i].name) != 0) {
      ++replaced;
      EXPECT_NE(a.textures[i].pixels, b.textures[i].pixels) << a.textures[i].name;
      // At the procedural texture's mean grey, within the clamping's shift.
      EXPECT_NEAR(mean_gray(a.textures[i]), mean_gray(b.textures[i]), 2.0) << a.textures[i].name;
    } else {
      EXPECT_EQ(a.textures[i].pixels, b.textures[i].pixels) << a.textures[i].name;
    }
  }
  EXPECT_EQ(replaced, static_cast<int>(photographed.size()));
  // The meshes are the same either way.
  ASSERT_EQ(a.meshes.size(), b.meshes.size());
  for (std::size_t i = 0; i < a.meshes.size(); ++i)
    EXPECT_EQ(a.meshes[i].indices, b.meshes[i].indices);
}

}  // namespace
}  // namespace driftlab::scenes
