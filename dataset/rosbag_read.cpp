// The ROS 1 bag reader (rosbag.hpp has driftlab's topics; EuRoC's published bags use the same
// image and IMU topics). Debian's rosbag_storage reads the bag (any chunk compression); the
// cameras come from a Kalibr camera chain, since a recorded bag carries no calibration of its
// own; raw, distorted images are rectified as the EuRoC folder reader does.
#include <fmt/format.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>

#include <cmath>
#include <map>
#include <mutex>
#include <opencv2/imgproc.hpp>

#include "core/error.hpp"
#include "core/rotation.hpp"
#include "dataset/dataset_detail.hpp"
#include "dataset/ros_messages.hpp"
#include "dataset/rosbag.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace names = rosbag_names;
namespace {

// The open bag, shared by the reader and the image source (rosbag::Bag is not thread-safe).
struct OpenBag {
  fs::path path;
  mutable std::mutex mutex;
  mutable rosbag::Bag bag;
};

TimeNs stamp_ns(const ros::Time& t) { return static_cast<TimeNs>(t.toNSec()); }

// The message as `T`; UserError naming the bag, topic and type when it is another type.
template <class T>
boost::shared_ptr<T> instantiate(const OpenBag& b, const rosbag::MessageInstance& m) {
  boost::shared_ptr<T> msg;
  try {
    msg = m.instantiate<T>();
  } catch (const ros::Exception& e) {  // a record whose bytes do not deserialise
    throw UserError(fmt::format("{}: {} at {} ns: a malformed {} message ({})", b.path.string(),
                                m.getTopic(), stamp_ns(m.getTime()), m.getDataType(), e.what()));
  }
  if (!msg)
    throw UserError(fmt::format("{}: {}: got messages of type {}, expected {}", b.path.string(),
                                m.getTopic(), m.getDataType(),
                                ros::message_traits::DataType<T>::value()));
  return msg;
}

// An 8-bit gray image of a sensor_msgs/Image (mono8, or colour converted).
cv::Mat gray_of(const OpenBag& b, const std::string& topic, const ros1::Image& m) {
  static const std::map<std::string, std::pair<int, int>> kEncodings = {
      {"mono8", {1, -1}},
      {"8UC1", {1, -1}},
      {"bgr8", {3, cv::COLOR_BGR2GRAY}},
      {"rgb8", {3, cv::COLOR_RGB2GRAY}},
      {"bgra8", {4, cv::COLOR_BGRA2GRAY}},
      {"rgba8", {4, cv::COLOR_RGBA2GRAY}}};
  const std::string encoding(m.encoding.begin(), m.encoding.end());
  const auto e = kEncodings.find(encoding);
  const auto where = [&] {
    return fmt::format("{}: {} at {} ns", b.path.string(), topic, stamp_ns(m.header.stamp));
  };
  if (e == kEncodings.end())
    throw UserError(fmt::format(
        "{}: encoding: got '{}', expected mono8, bgr8, rgb8, bgra8 or rgba8", where(), encoding));
  const int channels = e->second.first;
  if (m.width == 0 || m.height == 0 || m.width > 16384 || m.height > 16384 ||
      m.step < m.width * static_cast<std::uint32_t>(channels) ||
      m.data.size() != static_cast<std::size_t>(m.step) * m.height)
    throw UserError(fmt::format("{}: {}x{} pixels, step {}, {} bytes: the sizes do not agree",
                                where(), m.width, m.height, m.step, m.data.size()));
  const cv::Mat view(static_cast<int>(m.height), static_cast<int>(m.width), CV_8UC(channels),
                     const_cast<std::uint8_t*>(m.data.data()), m.step);
  cv::Mat gray;
  if (channels == 1)
    gray = view.clone();
  else
    cv::cvtColor(view, gray, e->second.second);
  return gray;
}

class BagImages final : public ImageSource {
 public:
  BagImages(std::shared_ptr<const OpenBag> bag, std::array<std::string, 2> topics, cv::Size size)
      : bag_(std::move(bag)), topics_(std::move(topics)), size_(size) {}
  std::pair<cv::Mat, cv::Mat> read(const DatasetFrame& frame) const override {
    return {image(0, frame.left_record_ns, frame.t_ns),
            image(1, frame.right_record_ns, frame.t_ns)};
  }

 private:
  cv::Mat image(int i, TimeNs record_ns, TimeNs t_ns) const {
    const std::string& topic = topics_[static_cast<std::size_t>(i)];
    const std::lock_guard<std::mutex> lock(bag_->mutex);
    ros::Time at;
    at.fromNSec(static_cast<std::uint64_t>(record_ns));
    try {
      rosbag::View view(bag_->bag, rosbag::TopicQuery(topic), at, at);
      for (const rosbag::MessageInstance& m : view) {
        const auto msg = instantiate<ros1::Image>(*bag_, m);
        if (stamp_ns(msg->header.stamp) != t_ns) continue;
        cv::Mat gray = gray_of(*bag_, topic, *msg);
        if (gray.size() != size_)
          throw UserError(fmt::format(
              "{}: {} at {} ns: {}x{} pixels, expected the calibration's "
              "{}x{}",
              bag_->path.string(), topic, t_ns, gray.cols, gray.rows, size_.width, size_.height));
        return gray;
      }
    } catch (const rosbag::BagException& e) {
      throw UserError(fmt::format("{}: {} at {} ns: cannot read the image ({})",
                                  bag_->path.string(), topic, t_ns, e.what()));
    }
    throw UserError(
        fmt::format("{}: {}: no image stamped {} ns any more", bag_->path.string(), topic, t_ns));
  }
  std::shared_ptr<const OpenBag> bag_;
  std::array<std::string, 2> topics_;
  cv::Size size_;  // the raw images' (both cameras have the same, as rectify_pair checks)
};

// Each topic's messages in record order, through `f`.
template <class F>
void for_each_message(const OpenBag& b, const std::string& topic, F&& f) {
  rosbag::View view(b.bag, rosbag::TopicQuery(topic));
  for (const rosbag::MessageInstance& m : view) f(m);
}

bool has_topic(const OpenBag& b, const std::string& topic) {
  rosbag::View view(b.bag, rosbag::TopicQuery(topic));
  return view.size() > 0;
}

// The pairs: the stamps both image topics have (as the EuRoC folder reader pairs them).
std::vector<DatasetFrame> read_frames(const OpenBag& b, const std::array<std::string, 2>& topics) {
  std::array<std::map<TimeNs, TimeNs>, 2> record;  // header stamp -> record time
  for (std::size_t i = 0; i < 2; ++i) {
    for_each_message(b, topics[i], [&](const rosbag::MessageInstance& m) {
      const TimeNs t = stamp_ns(instantiate<ros1::Image>(b, m)->header.stamp);
      if (!record[i].emplace(t, stamp_ns(m.getTime())).second)
        throw UserError(fmt::format("{}: {}: two images stamped {} ns, expected one a stamp",
                                    b.path.string(), topics[i], t));
    });
    if (record[i].empty())
      throw UserError(fmt::format("{}: {}: no images, expected the {} camera's", b.path.string(),
                                  topics[i], i == 0 ? "left" : "right"));
  }
  std::vector<DatasetFrame> frames;
  for (const auto& [t, left_record] : record[0]) {
    const auto right = record[1].find(t);
    if (right == record[1].end()) continue;
    DatasetFrame f;
    f.t_ns = t;
    f.left_record_ns = left_record;
    f.right_record_ns = right->second;
    frames.push_back(f);
  }
  if (frames.empty())
    throw UserError(
        fmt::format("{}: no time stamp in both {} and {}", b.path.string(), topics[0], topics[1]));
  return frames;
}

std::vector<ImuSample> read_imu(const OpenBag& b, const std::string& topic) {
  std::vector<ImuSample> out;
  for_each_message(b, topic, [&](const rosbag::MessageInstance& m) {
    const auto msg = instantiate<ros1::Imu>(b, m);
    ImuSample s;
    s.t_ns = stamp_ns(msg->header.stamp);
    const auto& w = msg->angular_velocity;
    const auto& a = msg->linear_acceleration;
    s.gyro_rad_s = Vec3(w.x, w.y, w.z);
    s.accel_m_s2 = Vec3(a.x, a.y, a.z);
    if (!out.empty() && s.t_ns <= out.back().t_ns)
      throw UserError(fmt::format("{}: {}: stamp {} ns after {} ns, expected increasing stamps",
                                  b.path.string(), topic, s.t_ns, out.back().t_ns));
    out.push_back(s);
  });
  return out;
}

// driftlab's /compass/heading, with /mag's field at the same stamps.
std::vector<CompassReading> read_compass(const OpenBag& b) {
  std::map<TimeNs, Vec3> field;
  for_each_message(b, names::kMag, [&](const rosbag::MessageInstance& m) {
    const auto msg = instantiate<ros1::MagneticField>(b, m);
    const auto& f = msg->magnetic_field;
    field[stamp_ns(msg->header.stamp)] = Vec3(f.x, f.y, f.z) * 1e9;  // T -> nT
  });
  std::vector<CompassReading> out;
  for_each_message(b, names::kHeading, [&](const rosbag::MessageInstance& m) {
    const auto msg = instantiate<ros1::QuaternionStamped>(b, m);
    const auto& q = msg->quaternion;
    CompassReading r;
    r.t_ns = stamp_ns(msg->header.stamp);
    r.heading_rad = wrap_angle_rad(2 * std::atan2(q.z, q.w));
    if (const auto f = field.find(r.t_ns); f != field.end()) r.field_S_nt = f->second;
    if (!out.empty() && r.t_ns <= out.back().t_ns)
      throw UserError(fmt::format("{}: {}: stamp {} ns after {} ns, expected increasing stamps",
                                  b.path.string(), names::kHeading, r.t_ns, out.back().t_ns));
    out.push_back(r);
  });
  return out;
}

SE3 pose_of(const ros1::Point& p, const ros1::Quaternion& q) {
  const double n = std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z);
  if (!(std::abs(n - 1) < kUnitTolerance)) throw std::domain_error("not a unit quaternion");
  return SE3(Quat(q.w / n, q.x / n, q.y / n, q.z / n), Vec3(p.x, p.y, p.z));
}

// The IMU's true poses on `topic` (PoseStamped, TransformStamped or Odometry).
Trajectory read_groundtruth(const OpenBag& b, const std::string& topic) {
  Trajectory out;
  for_each_message(b, topic, [&](const rosbag::MessageInstance& m) {
    const std::string type = m.getDataType();
    StampedPose p;
    try {
      if (type == "geometry_msgs/PoseStamped") {
        const auto msg = instantiate<ros1::PoseStamped>(b, m);
        p = {stamp_ns(msg->header.stamp), pose_of(msg->pose.position, msg->pose.orientation)};
      } else if (type == "geometry_msgs/TransformStamped") {
        const auto msg = instantiate<ros1::TransformStamped>(b, m);
        ros1::Point t;
        t.x = msg->transform.translation.x, t.y = msg->transform.translation.y;
        t.z = msg->transform.translation.z;
        p = {stamp_ns(msg->header.stamp), pose_of(t, msg->transform.rotation)};
      } else if (type == "nav_msgs/Odometry") {
        const auto msg = instantiate<ros1::Odometry>(b, m);
        p = {stamp_ns(msg->header.stamp),
             pose_of(msg->pose.pose.position, msg->pose.pose.orientation)};
      } else {
        throw UserError(fmt::format(
            "{}: {}: got ground truth of type {}, expected geometry_msgs/PoseStamped, "
            "geometry_msgs/TransformStamped or nav_msgs/Odometry (a full pose; position-only "
            "truth such as EuRoC's /leica/position cannot give camera poses)",
            b.path.string(), topic, type));
      }
    } catch (const std::domain_error&) {
      throw UserError(fmt::format("{}: {} at {} ns: the orientation is not a unit quaternion",
                                  b.path.string(), topic, stamp_ns(m.getTime())));
    }
    if (!out.empty() && p.t_ns <= out.back().t_ns)
      throw UserError(fmt::format("{}: {}: stamp {} ns after {} ns, expected increasing stamps",
                                  b.path.string(), topic, p.t_ns, out.back().t_ns));
    out.push_back(p);
  });
  return out;
}

// The ground-truth topic: the one asked for (which must be there), or the first known one.
std::string groundtruth_topic(const OpenBag& b, const std::string& asked) {
  if (!asked.empty()) {
    if (!has_topic(b, asked))
      throw UserError(fmt::format("{}: --gt-topic: no messages on '{}'", b.path.string(), asked));
    return asked;
  }
  for (const char* topic : {names::kGroundTruth, names::kEurocVicon, names::kTumViMocap})
    if (has_topic(b, topic)) return topic;
  return "";
}

fs::path bag_file(const fs::path& path) {
  if (fs::is_regular_file(path)) return path;
  if (fs::is_directory(path)) {
    if (fs::is_regular_file(path / names::kBagFile)) return path / names::kBagFile;
    std::vector<fs::path> bags;
    for (const auto& e : fs::directory_iterator(path))
      if (e.is_regular_file() && e.path().extension() == ".bag") bags.push_back(e.path());
    if (bags.size() == 1) return bags.front();
    throw UserError(fmt::format("{}: found {} .bag files, expected one (or name the bag)",
                                path.string(), bags.size()));
  }
  throw UserError(fmt::format("{}: no such bag", path.string()));
}

// The dataset read from the open bag `b` with the camera chain at `camchain`.
StereoDataset read_open_bag(const std::shared_ptr<OpenBag>& b, const fs::path& camchain,
                            const ReadOptions& options) {
  StereoDataset d;
  d.format = DatasetFormat::kRosbag;
  d.root = b->path;
  const KalibrChain chain = read_kalibr_camchain(camchain);
  const RectifiedPair pair = rectify_pair(chain.cameras[0], chain.cameras[1], camchain);
  d.rig = pair.rig;
  d.rectification = pair.rectification;
  d.T_S_C = chain.cameras[0].T_B_C * pair.T_C0_Crect;
  d.has_extrinsics = true;
  std::array<std::string, 2> topics;
  for (std::size_t i = 0; i < 2; ++i)
    topics[i] = chain.topics[i].empty() ? names::kImage[i] : chain.topics[i];
  d.frames = read_frames(*b, topics);
  const PinholeCamera& raw = chain.cameras[0].camera;
  d.images = std::make_shared<BagImages>(b, topics, cv::Size(raw.width, raw.height));
  const fs::path imu_chain = camchain.parent_path() / names::kImuChainFile;
  d.imu = read_imu(*b, names::kImu);
  if (!d.imu.empty() && fs::exists(imu_chain)) d.imu_noise = read_kalibr_imu_chain(imu_chain);
  d.compass = read_compass(*b);
  const std::string gt = groundtruth_topic(*b, options.gt_topic);
  if (!gt.empty())
    for (const StampedPose& p : read_groundtruth(*b, gt))
      d.camera_gt.push_back({p.t_ns, p.T_W_C * d.T_S_C});
  return d;
}

}  // namespace

StereoDataset read_rosbag(const fs::path& path, const ReadOptions& options) {
  auto b = std::make_shared<OpenBag>();
  b->path = bag_file(path);
  const fs::path camchain = !options.calibration.empty()
                                ? options.calibration
                                : b->path.parent_path() / names::kCamchainFile;
  if (!fs::exists(camchain))
    throw UserError(fmt::format(
        "{}: no camera calibration: expected {} beside the bag, or --calibration FILE (a Kalibr "
        "camera chain, as OpenVINS ships for EuRoC in config/euroc_mav)",
        b->path.string(), names::kCamchainFile));
  check_bag_structure(b->path);
  try {
    b->bag.open(b->path.string(), rosbag::bagmode::Read);
    return read_open_bag(b, camchain, options);
  } catch (const rosbag::BagException& e) {
    throw UserError(fmt::format("{}: not a readable ROS 1 bag ({})", b->path.string(), e.what()));
  } catch (const ros::Exception& e) {
    throw UserError(fmt::format("{}: a malformed record ({})", b->path.string(), e.what()));
  }
}

}  // namespace driftlab::dataset::detail
