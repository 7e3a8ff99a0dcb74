// The ROS 1 bag writer's sink (bag_writer.hpp; rosbag.hpp has the topics and frames): ROS 1
// messages, written with Debian's rosbag_storage.
#include <fmt/format.h>
#include <rosbag/bag.h>

#include "core/error.hpp"
#include "dataset/bag_writer.hpp"
#include "dataset/dataset_detail.hpp"
#include "dataset/ros_messages.hpp"
#include "dataset/rosbag.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace names = rosbag_names;
namespace {

ros::Time ros_time(TimeNs t_ns) {
  ros::Time t;
  t.fromNSec(static_cast<std::uint64_t>(t_ns));
  return t;
}

ros1::Header header(TimeNs t_ns, const char* frame, std::uint32_t seq) {
  ros1::Header h;
  h.seq = seq;
  h.stamp = ros_time(t_ns);
  h.frame_id = frame;
  return h;
}

ros1::Quaternion quaternion_msg(const Quat& q) {
  ros1::Quaternion m;
  m.w = q.w(), m.x = q.x(), m.y = q.y(), m.z = q.z();
  return m;
}

ros1::Vector3 vector3_msg(const Vec3& v) {
  ros1::Vector3 m;
  m.x = v.x(), m.y = v.y(), m.z = v.z();
  return m;
}

ros1::TransformStamped transform_msg(TimeNs t_ns, const char* parent, const char* child,
                                     const SE3& T_parent_child) {
  ros1::TransformStamped m;
  m.header = header(t_ns, parent, 0);
  m.child_frame_id = child;
  m.transform.translation = vector3_msg(T_parent_child.translation());
  m.transform.rotation = quaternion_msg(T_parent_child.quaternion());
  return m;
}

ros1::Image image_msg(const ros1::Header& h, const cv::Mat& gray) {
  if (gray.type() != CV_8UC1) throw InternalError("rosbag writer: expected 8-bit gray images");
  ros1::Image m;
  m.header = h;
  m.height = static_cast<std::uint32_t>(gray.rows);
  m.width = static_cast<std::uint32_t>(gray.cols);
  m.encoding = "mono8";
  m.is_bigendian = 0;
  m.step = m.width;
  m.data.resize(static_cast<std::size_t>(gray.rows) * gray.cols);
  for (int r = 0; r < gray.rows; ++r)
    std::copy_n(gray.ptr<std::uint8_t>(r), gray.cols, m.data.data() + std::size_t(r) * gray.cols);
  return m;
}

// The rectified pair's camera_info: no distortion, R the identity, P = K [I | (-B, 0, 0)].
ros1::CameraInfo camera_info_msg(const ros1::Header& h, const StereoRig& rig, int i) {
  const PinholeCamera& c = rig.camera;
  ros1::CameraInfo m;
  m.header = h;
  m.height = static_cast<std::uint32_t>(c.height);
  m.width = static_cast<std::uint32_t>(c.width);
  m.distortion_model = "plumb_bob";
  m.D.assign(5, 0.0);
  m.K = {c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1};
  m.R = {1, 0, 0, 0, 1, 0, 0, 0, 1};
  m.P = {c.fx, 0, c.cx, i == 0 ? 0.0 : -c.fx * rig.baseline_m, 0, c.fy, c.cy, 0, 0, 0, 1, 0};
  return m;
}

class Ros1Sink final : public BagSink {
 public:
  explicit Ros1Sink(const fs::path& file) : file_(file) {
    guarded([&] { bag_.open(file.string(), rosbag::bagmode::Write); });
  }
  void image(int cam, TimeNs t, std::uint32_t seq, const cv::Mat& gray) override {
    write(names::kImage[cam], t, image_msg(header(t, names::kOpticalFrame[cam], seq), gray));
  }
  void camera_info(int cam, TimeNs t, std::uint32_t seq, const StereoRig& rig) override {
    write(names::kCameraInfo[cam], t,
          camera_info_msg(header(t, names::kOpticalFrame[cam], seq), rig, cam));
  }
  void imu(const ImuSample& s, std::uint32_t seq, double gyro_var, double accel_var) override {
    ros1::Imu m;
    m.header = header(s.t_ns, names::kImuFrame, seq);
    m.orientation_covariance[0] = -1;  // no orientation estimate
    m.angular_velocity = vector3_msg(s.gyro_rad_s);
    m.linear_acceleration = vector3_msg(s.accel_m_s2);
    for (int i = 0; i < 3; ++i) {
      m.angular_velocity_covariance[4 * i] = gyro_var;
      m.linear_acceleration_covariance[4 * i] = accel_var;
    }
    write(names::kImu, s.t_ns, m);
  }
  void gps(const GpsRecord& g, std::uint32_t seq) override {
    ros1::NavSatFix m;
    m.header = header(g.t_ns, "gps", seq);
    m.status.status = g.fix ? ros1::NavSatStatus::STATUS_FIX : ros1::NavSatStatus::STATUS_NO_FIX;
    m.status.service = ros1::NavSatStatus::SERVICE_GPS;
    m.latitude = g.latitude_deg, m.longitude = g.longitude_deg, m.altitude = g.height_m;
    m.position_covariance_type = ros1::NavSatFix::COVARIANCE_TYPE_UNKNOWN;
    if (g.covariance_enu_m2) {
      for (int i = 0; i < 3; ++i) m.position_covariance[4 * i] = (*g.covariance_enu_m2)[i];
      m.position_covariance_type = ros1::NavSatFix::COVARIANCE_TYPE_APPROXIMATED;
    }
    write(names::kGps, g.t_ns, m);
  }
  void compass(const CompassReading& r, std::uint32_t seq) override {
    ros1::MagneticField field;
    field.header = header(r.t_ns, "compass", seq);
    field.magnetic_field = vector3_msg(r.field_S_nt * 1e-9);  // nT -> T
    write(names::kMag, r.t_ns, field);
    ros1::QuaternionStamped heading;
    heading.header = header(r.t_ns, names::kWorldFrame, seq);
    heading.quaternion = quaternion_msg(heading_quaternion(r.heading_rad));
    write(names::kHeading, r.t_ns, heading);
  }
  void pose(TimeNs t, const SE3& T_W_S, std::uint32_t seq) override {
    ros1::PoseStamped m;
    m.header = header(t, names::kWorldFrame, seq);
    m.pose.position.x = T_W_S.translation().x();
    m.pose.position.y = T_W_S.translation().y();
    m.pose.position.z = T_W_S.translation().z();
    m.pose.orientation = quaternion_msg(T_W_S.quaternion());
    write(names::kGroundTruth, t, m);
  }
  void tf_static(TimeNs t, const std::vector<TransformRecord>& transforms) override;
  void close() override {
    guarded([&] { bag_.close(); });
  }

 private:
  template <class F>
  void guarded(F&& f) {
    try {
      f();
    } catch (const rosbag::BagException& e) {
      throw UserError(fmt::format("{}: cannot write the bag ({})", file_.string(), e.what()));
    }
  }
  template <class Message>
  void write(const std::string& topic, TimeNs t_ns, const Message& m) {
    guarded([&] { bag_.write(topic, ros_time(names::record_ns(t_ns)), m); });
  }

  fs::path file_;
  rosbag::Bag bag_;
};

void Ros1Sink::tf_static(TimeNs t, const std::vector<TransformRecord>& transforms) {
  ros1::TFMessage m;
  for (const TransformRecord& r : transforms)
    m.transforms.push_back(transform_msg(t, r.parent.c_str(), r.child.c_str(), r.T_parent_child));
  const auto connection = boost::make_shared<ros::M_string>();
  // With a connection header of its own, rosbag_storage writes it as given: the type fields
  // go in by hand.
  (*connection)["type"] = ros::message_traits::datatype(m);
  (*connection)["md5sum"] = ros::message_traits::md5sum(m);
  (*connection)["message_definition"] = ros::message_traits::definition(m);
  (*connection)["latching"] = "1";
  guarded([&] { bag_.write(names::kTfStatic, ros_time(names::record_ns(t)), m, connection); });
}

}  // namespace

std::unique_ptr<DatasetWriter> make_rosbag_writer(const fs::path& root,
                                                  const ExportCalibration& calibration) {
  return make_bag_writer(root, calibration, std::make_unique<Ros1Sink>(root / names::kBagFile),
                         "rosbag", names::kBagFile);
}

}  // namespace driftlab::dataset::detail
