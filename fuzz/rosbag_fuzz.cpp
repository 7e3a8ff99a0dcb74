// ROS 1 bags (`driftlab vo BAG --format rosbag`): the input is the bag's bytes, read with a
// fixed Kalibr camera chain for an 8x6 pair; every pair found is read too, so that the image
// messages are decoded, not only indexed.
#include "dataset/dataset.hpp"
#include "fuzz/fuzz_support.hpp"

namespace {

constexpr const char* kChain =
    "cam0:\n  T_cam_imu: [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]\n  camera_model: pinhole\n"
    "  intrinsics: [10, 10, 3.5, 2.5]\n  resolution: [8, 6]\n  rostopic: /cam0/image_raw\n"
    "cam1:\n  T_cam_imu: [[1,0,0,-0.1],[0,1,0,0],[0,0,1,0],[0,0,0,1]]\n"
    "  camera_model: pinhole\n  intrinsics: [10, 10, 3.5, 2.5]\n  resolution: [8, 6]\n"
    "  rostopic: /cam1/image_raw\n";

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  static const std::filesystem::path chain = fuzz::put_file("chain.yaml", kChain);
  const std::filesystem::path bag =
      fuzz::put_file("input.bag", std::string_view(reinterpret_cast<const char*>(data), size));
  fuzz::expect_user_errors_only([&] {
    dataset::ReadOptions options;
    options.calibration = chain;
    const dataset::StereoDataset d =
        dataset::read_dataset(bag, dataset::DatasetFormat::kRosbag, options);
    for (std::size_t i = 0; i < d.frames.size() && i < 8; ++i)
      (void)dataset::read_pair(d, d.frames[i]);
  });
  return 0;
}
