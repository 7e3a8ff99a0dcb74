// The ROS 1 message types the bag writer and reader use, made usable in C++20. ROS 1's
// generated messages name `ContainerAllocator::rebind<T>::other`, which std::allocator<void>
// no longer has in C++20; the messages are templates over that allocator, so they are
// instantiated here with one that has it (a std::allocator with rebind; the bytes on the wire
// are the same).
#pragma once

#include <geometry_msgs/PointStamped.h>
#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/QuaternionStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/MagneticField.h>
#include <sensor_msgs/NavSatFix.h>
#include <tf2_msgs/TFMessage.h>

#include <memory>

namespace driftlab::dataset::ros1 {

template <class T>
struct RebindingAllocator : std::allocator<T> {
  template <class U>
  struct rebind {
    using other = RebindingAllocator<U>;
  };
  RebindingAllocator() = default;
  template <class U>
  RebindingAllocator(const RebindingAllocator<U>&) noexcept {}
};
using Allocator = RebindingAllocator<void>;

using Header = std_msgs::Header_<Allocator>;
using Image = sensor_msgs::Image_<Allocator>;
using CameraInfo = sensor_msgs::CameraInfo_<Allocator>;
using Imu = sensor_msgs::Imu_<Allocator>;
using MagneticField = sensor_msgs::MagneticField_<Allocator>;
using NavSatFix = sensor_msgs::NavSatFix_<Allocator>;
using NavSatStatus = sensor_msgs::NavSatStatus_<Allocator>;
using Point = geometry_msgs::Point_<Allocator>;
using Quaternion = geometry_msgs::Quaternion_<Allocator>;
using Vector3 = geometry_msgs::Vector3_<Allocator>;
using PoseStamped = geometry_msgs::PoseStamped_<Allocator>;
using QuaternionStamped = geometry_msgs::QuaternionStamped_<Allocator>;
using TransformStamped = geometry_msgs::TransformStamped_<Allocator>;
using Odometry = nav_msgs::Odometry_<Allocator>;
using TFMessage = tf2_msgs::TFMessage_<Allocator>;

}  // namespace driftlab::dataset::ros1
