// The ROS 2 bag writer's sink (bag_writer.hpp; rosbag.hpp has the topics and frames): the
// messages in CDR (XCDR1, little endian, serialised with eProsima's Fast CDR) in rosbag2's
// sqlite3 storage, a folder with metadata.yaml and one .db3 file that Humble and every later
// distro read (`ros2 bag play`, `ros2 bag info`).
//
// Database (rosbag2_storage_default_plugins, sqlite_storage.cpp): tables topics(id, name, type,
// serialization_format, offered_qos_profiles) and messages(id, topic_id, timestamp [ns],
// data), an index on the time stamps; without a schema table and with offered_qos_profiles
// it is read as rosbag2's schema version 2. The message layouts are ROS 2's (Header without
// seq; builtin_interfaces/Time with int32 sec and uint32 nanosec). metadata.yaml is rosbag2's
// version 5 (relative_file_paths and files), the newest that Humble reads.
#include <fastcdr/Cdr.h>
#include <fastcdr/FastBuffer.h>
#include <fmt/format.h>
#include <sqlite3.h>

#include <map>

#include "core/atomic_file.hpp"
#include "core/error.hpp"
#include "dataset/bag_writer.hpp"
#include "dataset/dataset_detail.hpp"
#include "dataset/rosbag.hpp"

namespace driftlab::dataset::detail {
namespace fs = std::filesystem;
namespace names = rosbag_names;
namespace {

// One message's bytes: the CDR encapsulation header (00 01 00 00), then the fields with
// alignment counted from after it. Fast CDR leaves the alignment padding as it finds it, so
// the message is written into zeroed memory of `capacity` bytes: the same bytes every time.
class CdrMessage {
 public:
  explicit CdrMessage(std::size_t capacity = 1024)
      : memory_(capacity, '\0'),
        buffer_(memory_.data(), memory_.size()),
        cdr_(buffer_, eprosima::fastcdr::Cdr::LITTLE_ENDIANNESS, eprosima::fastcdr::Cdr::DDS_CDR) {
    cdr_.serialize_encapsulation();
  }
  CdrMessage& header(TimeNs t_ns, const std::string& frame) {
    cdr_ << static_cast<std::int32_t>(t_ns / 1'000'000'000)
         << static_cast<std::uint32_t>(t_ns % 1'000'000'000) << frame;
    return *this;
  }
  template <class T>
  CdrMessage& operator<<(const T& v) {
    cdr_ << v;
    return *this;
  }
  CdrMessage& vec3(const Vec3& v) { return *this << v.x() << v.y() << v.z(); }
  CdrMessage& quat(const Quat& q) { return *this << q.x() << q.y() << q.z() << q.w(); }
  // A fixed-size float64 array (no length on the wire).
  template <std::size_t N>
  CdrMessage& array(const std::array<double, N>& a) {
    cdr_.serializeArray(a.data(), N);
    return *this;
  }
  std::string bytes() const { return std::string(memory_.data(), cdr_.getSerializedDataLength()); }

 private:
  std::vector<char> memory_;
  eprosima::fastcdr::FastBuffer buffer_;
  eprosima::fastcdr::Cdr cdr_;
};

std::array<double, 9> diagonal(double a, double b, double c) { return {a, 0, 0, 0, b, 0, 0, 0, c}; }

// rosbag2's QoS profile YAML: reliable, and volatile or (/tf_static) transient local.
std::string qos_profiles(bool transient_local) {
  const std::string forever = "\n    sec: 9223372036\n    nsec: 854775807";
  return fmt::format(
      "- history: 3\n  depth: 0\n  reliability: 1\n  durability: {}\n  deadline:{}\n"
      "  lifespan:{}\n  liveliness: 1\n  liveliness_lease_duration:{}\n"
      "  avoid_ros_namespace_conventions: false",
      transient_local ? 1 : 2, forever, forever, forever);
}

// A YAML double-quoted scalar.
std::string quoted(const std::string& text) {
  std::string out = "\"";
  for (char ch : text)
    out += ch == '\n' ? std::string("\\n") : ch == '"' ? "\\\"" : std::string(1, ch);
  return out + "\"";
}

struct Topic {
  int id = 0;
  std::string type;
  bool transient_local = false;
  std::size_t count = 0;
};

class Ros2Sink final : public BagSink {
 public:
  explicit Ros2Sink(const fs::path& folder);
  ~Ros2Sink() override {
    if (insert_) sqlite3_finalize(insert_);
    if (db_) sqlite3_close(db_);
  }
  void image(int cam, TimeNs t, std::uint32_t, const cv::Mat& gray) override;
  void camera_info(int cam, TimeNs t, std::uint32_t, const StereoRig& rig) override;
  void imu(const ImuSample& s, std::uint32_t, double gyro_var, double accel_var) override;
  void gps(const GpsRecord& g, std::uint32_t) override;
  void compass(const CompassReading& r, std::uint32_t) override;
  void pose(TimeNs t, const SE3& T_W_S, std::uint32_t) override;
  void tf_static(TimeNs t, const std::vector<TransformRecord>& transforms) override;
  void close() override;

 private:
  void check(int rc, const char* what) const {
    if (rc != SQLITE_OK && rc != SQLITE_DONE)
      throw UserError(fmt::format("{}: cannot write the bag's database ({}: {})", file_.string(),
                                  what, sqlite3_errmsg(db_)));
  }
  void exec(const std::string& sql) {
    check(sqlite3_exec(db_, sql.c_str(), nullptr, nullptr, nullptr), "exec");
  }
  void write(const std::string& topic, const std::string& type, TimeNs t, const CdrMessage& m,
             bool transient_local = false);
  std::string metadata_yaml() const;

  fs::path folder_, file_;
  sqlite3* db_ = nullptr;
  sqlite3_stmt* insert_ = nullptr;
  std::map<std::string, Topic> topics_;
  std::size_t count_ = 0;
  TimeNs first_ = 0, last_ = 0;
};

Ros2Sink::Ros2Sink(const fs::path& folder)
    : folder_(folder), file_(folder / (folder.filename().string() + "_0.db3")) {
  fs::create_directories(folder);
  if (sqlite3_open_v2(file_.string().c_str(), &db_, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE,
                      nullptr) != SQLITE_OK)
    throw UserError(fmt::format("{}: cannot create the bag's database", file_.string()));
  exec(
      "PRAGMA journal_mode=OFF; PRAGMA synchronous=OFF;"
      "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, "
      "serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL);"
      "CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, timestamp "
      "INTEGER NOT NULL, data BLOB NOT NULL);"
      "BEGIN TRANSACTION;");
  check(sqlite3_prepare_v2(db_, "INSERT INTO messages (topic_id, timestamp, data) VALUES (?, ?, ?)",
                           -1, &insert_, nullptr),
        "prepare");
}

void Ros2Sink::write(const std::string& topic, const std::string& type, TimeNs t,
                     const CdrMessage& m, bool transient_local) {
  auto it = topics_.find(topic);
  if (it == topics_.end()) {
    Topic created{static_cast<int>(topics_.size()) + 1, type, transient_local, 0};
    exec(fmt::format("INSERT INTO topics VALUES ({}, '{}', '{}', 'cdr', '{}');", created.id, topic,
                     type, qos_profiles(transient_local)));
    it = topics_.emplace(topic, created).first;
  }
  const std::string data = m.bytes();
  check(sqlite3_bind_int(insert_, 1, it->second.id), "bind");
  check(sqlite3_bind_int64(insert_, 2, t), "bind");
  check(sqlite3_bind_blob(insert_, 3, data.data(), static_cast<int>(data.size()), SQLITE_STATIC),
        "bind");
  check(sqlite3_step(insert_), "insert");
  check(sqlite3_reset(insert_), "reset");
  ++it->second.count;
  first_ = count_ == 0 ? t : std::min(first_, t);
  last_ = count_ == 0 ? t : std::max(last_, t);
  ++count_;
}

void Ros2Sink::image(int cam, TimeNs t, std::uint32_t, const cv::Mat& gray) {
  if (gray.type() != CV_8UC1 || !gray.isContinuous())
    throw InternalError("rosbag2 writer: expected continuous 8-bit gray images");
  const std::vector<std::uint8_t> pixels(gray.datastart, gray.dataend);
  CdrMessage m(pixels.size() + 256);
  m.header(t, names::kOpticalFrame[cam])
      << static_cast<std::uint32_t>(gray.rows) << static_cast<std::uint32_t>(gray.cols)
      << std::string("mono8") << std::uint8_t{0} << static_cast<std::uint32_t>(gray.cols) << pixels;
  write(names::kImage[cam], "sensor_msgs/msg/Image", t, m);
}

void Ros2Sink::camera_info(int cam, TimeNs t, std::uint32_t, const StereoRig& rig) {
  const PinholeCamera& c = rig.camera;
  CdrMessage m;
  m.header(t, names::kOpticalFrame[cam])
      << static_cast<std::uint32_t>(c.height) << static_cast<std::uint32_t>(c.width)
      << std::string("plumb_bob") << std::vector<double>(5, 0.0);
  m.array(std::array<double, 9>{c.fx, 0, c.cx, 0, c.fy, c.cy, 0, 0, 1});
  m.array(diagonal(1, 1, 1));
  m.array(std::array<double, 12>{c.fx, 0, c.cx, cam == 0 ? 0.0 : -c.fx * rig.baseline_m, 0, c.fy,
                                 c.cy, 0, 0, 0, 1, 0});
  m << std::uint32_t{0} << std::uint32_t{0}  // binning
    << std::uint32_t{0} << std::uint32_t{0} << std::uint32_t{0} << std::uint32_t{0}
    << false;  // roi: the whole image
  write(names::kCameraInfo[cam], "sensor_msgs/msg/CameraInfo", t, m);
}

void Ros2Sink::imu(const ImuSample& s, std::uint32_t, double gyro_var, double accel_var) {
  CdrMessage m;
  m.header(s.t_ns, names::kImuFrame).quat(Quat(0, 0, 0, 0));
  m.array(diagonal(-1, 0, 0));  // no orientation estimate
  m.vec3(s.gyro_rad_s).array(diagonal(gyro_var, gyro_var, gyro_var));
  m.vec3(s.accel_m_s2).array(diagonal(accel_var, accel_var, accel_var));
  write(names::kImu, "sensor_msgs/msg/Imu", s.t_ns, m);
}

void Ros2Sink::gps(const GpsRecord& g, std::uint32_t) {
  const Vec3 cov = g.covariance_enu_m2.value_or(Vec3::Zero());
  CdrMessage m;
  m.header(g.t_ns, "gps") << static_cast<std::int8_t>(g.fix ? 0 : -1) << std::uint16_t{1}
                          << g.latitude_deg << g.longitude_deg << g.height_m;
  m.array(diagonal(cov.x(), cov.y(), cov.z()));
  m << static_cast<std::uint8_t>(g.covariance_enu_m2 ? 1 : 0);  // APPROXIMATED or UNKNOWN
  write(names::kGps, "sensor_msgs/msg/NavSatFix", g.t_ns, m);
}

void Ros2Sink::compass(const CompassReading& r, std::uint32_t) {
  CdrMessage field;
  field.header(r.t_ns, "compass").vec3(r.field_S_nt * 1e-9).array(diagonal(0, 0, 0));
  write(names::kMag, "sensor_msgs/msg/MagneticField", r.t_ns, field);
  CdrMessage heading;
  heading.header(r.t_ns, names::kWorldFrame).quat(heading_quaternion(r.heading_rad));
  write(names::kHeading, "geometry_msgs/msg/QuaternionStamped", r.t_ns, heading);
}

void Ros2Sink::pose(TimeNs t, const SE3& T_W_S, std::uint32_t) {
  CdrMessage m;
  m.header(t, names::kWorldFrame).vec3(T_W_S.translation()).quat(T_W_S.quaternion());
  write(names::kGroundTruth, "geometry_msgs/msg/PoseStamped", t, m);
}

void Ros2Sink::tf_static(TimeNs t, const std::vector<TransformRecord>& transforms) {
  CdrMessage tf(256 * (transforms.size() + 1));  // a sequence of TransformStamped
  tf << static_cast<std::uint32_t>(transforms.size());
  for (const TransformRecord& r : transforms) {
    tf.header(t, r.parent) << r.child;
    tf.vec3(r.T_parent_child.translation()).quat(r.T_parent_child.quaternion());
  }
  write(names::kTfStatic, "tf2_msgs/msg/TFMessage", t, tf, true);
}

std::string Ros2Sink::metadata_yaml() const {
  std::string topics;
  for (const auto& [name, topic] : topics_)
    topics += fmt::format(
        "    - topic_metadata:\n        name: {}\n        type: {}\n"
        "        serialization_format: cdr\n        offered_qos_profiles: {}\n"
        "      message_count: {}\n",
        name, topic.type, quoted(qos_profiles(topic.transient_local)), topic.count);
  const std::string file = file_.filename().string();
  return fmt::format(
      "rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n"
      "  duration:\n    nanoseconds: {0}\n  starting_time:\n    nanoseconds_since_epoch: {1}\n"
      "  message_count: {2}\n  topics_with_message_count:\n{3}"
      "  compression_format: \"\"\n  compression_mode: \"\"\n"
      "  relative_file_paths:\n    - {4}\n  files:\n    - path: {4}\n      starting_time:\n"
      "        nanoseconds_since_epoch: {1}\n      duration:\n        nanoseconds: {0}\n"
      "      message_count: {2}\n",
      last_ - first_, first_, count_, topics, file);
}

void Ros2Sink::close() {
  exec("COMMIT; CREATE INDEX timestamp_idx ON messages (timestamp ASC);");
  check(sqlite3_finalize(insert_), "finalize");
  insert_ = nullptr;
  check(sqlite3_close(db_), "close");
  db_ = nullptr;
  write_file_atomic(folder_ / "metadata.yaml", metadata_yaml());
}

}  // namespace

std::unique_ptr<DatasetWriter> make_rosbag2_writer(const fs::path& root,
                                                   const ExportCalibration& calibration) {
  return make_bag_writer(root, calibration, std::make_unique<Ros2Sink>(root / names::kBag2Folder),
                         "rosbag2", std::string(names::kBag2Folder) + "/");
}

}  // namespace driftlab::dataset::detail
