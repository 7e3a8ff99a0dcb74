// Trajectory and IMU files, including what external VOs write back: the same bytes through
// every reader (TUM, KITTI poses and times, EuRoC ground truth and IMU).
#include "core/trajectory_io.hpp"
#include "fuzz/fuzz_support.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace driftlab;
  const auto file = fuzz::put_file("trajectory.txt", fuzz::as_text(data, size));
  fuzz::expect_user_errors_only([&] { (void)read_tum(file); });
  fuzz::expect_user_errors_only([&] { (void)read_kitti(file); });
  fuzz::expect_user_errors_only([&] { (void)read_kitti_times(file); });
  fuzz::expect_user_errors_only([&] { (void)read_euroc_groundtruth(file); });
  fuzz::expect_user_errors_only([&] { (void)read_euroc_imu(file); });
  return 0;
}
