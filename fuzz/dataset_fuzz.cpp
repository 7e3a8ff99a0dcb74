// Imported datasets (read_dataset): the index, calibration and ground truth that
// `driftlab vo` reads. The first input byte picks the format; the rest carries the files,
// separated by "%%" lines:
//   KITTI: calib.txt %% times.txt %% poses/00.txt (image_0/000000.png is a fixed 8x6 image);
//   EuRoC: cam0/sensor.yaml %% cam1/sensor.yaml %% cam0/data.csv %% cam1/data.csv
//          %% state_groundtruth_estimate0/data.csv %% imu0/data.csv.
#include <opencv2/imgcodecs.hpp>

#include "dataset/dataset.hpp"
#include "fuzz/fuzz_support.hpp"

namespace {

using driftlab::fuzz::put_file;
namespace fs = std::filesystem;

fs::path kitti_files(const std::vector<std::string>& p) {
  const fs::path root = driftlab::fuzz::scratch_dir() / "kitti";
  fs::remove_all(root);
  fs::create_directories(root / "sequences/00/image_0");
  cv::imwrite((root / "sequences/00/image_0/000000.png").string(), cv::Mat(6, 8, CV_8UC1, 128));
  put_file("kitti/sequences/00/calib.txt", p[0]);
  put_file("kitti/sequences/00/times.txt", p[1]);
  if (!p[2].empty()) put_file("kitti/poses/00.txt", p[2]);
  return root;
}

fs::path euroc_files(const std::vector<std::string>& p) {
  const fs::path root = driftlab::fuzz::scratch_dir() / "euroc";
  fs::remove_all(root);
  const char* names[] = {"cam0/sensor.yaml",
                         "cam1/sensor.yaml",
                         "cam0/data.csv",
                         "cam1/data.csv",
                         "state_groundtruth_estimate0/data.csv",
                         "imu0/data.csv"};
  for (std::size_t i = 0; i < 6; ++i)
    if (i < 4 || !p[i].empty()) put_file(fs::path("euroc/mav0") / names[i], p[i]);
  return root;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  if (size == 0) return 0;
  const bool kitti = data[0] % 2 == 0;
  const auto parts = fuzz::split_parts(fuzz::as_text(data + 1, size - 1), kitti ? 3 : 6);
  fuzz::expect_user_errors_only([&] {
    if (kitti)
      (void)dataset::read_dataset(kitti_files(parts), dataset::DatasetFormat::kKitti);
    else
      (void)dataset::read_dataset(euroc_files(parts), dataset::DatasetFormat::kEuroc);
  });
  return 0;
}
