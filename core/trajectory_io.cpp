#include "core/trajectory_io.hpp"

#include <fmt/format.h>

#include <Eigen/SVD>
#include <array>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <string>
#include <system_error>

#include "core/atomic_file.hpp"
#include "core/csv.hpp"
#include "core/enum_names.hpp"
#include "core/error.hpp"
#include "core/number.hpp"

namespace driftlab {
namespace fs = std::filesystem;

namespace {

constexpr std::string_view kSpace = " \t\r\v\f";
constexpr std::size_t kMaxShown = 80;

// Long lines are cut so that a binary file given by mistake gives a readable message.
std::string shown(std::string_view text) {
  if (text.size() <= kMaxShown) return std::string(text);
  return std::string(text.substr(0, kMaxShown)) + "...";
}

std::string reason(int error_number) {
  if (error_number == 0) return "unknown error";
  return std::generic_category().message(error_number);
}

std::string read_all(const fs::path& path) {
  std::error_code ec;
  // An ifstream opens a directory without complaint and then reads nothing.
  if (fs::is_directory(path, ec))
    throw UserError(path.string() + ": cannot open for reading: " + reason(EISDIR));
  errno = 0;
  std::ifstream in(path, std::ios::in | std::ios::binary);
  if (!in) throw UserError(path.string() + ": cannot open for reading: " + reason(errno));
  std::string content;
  std::array<char, 1 << 16> buffer;
  while (in.read(buffer.data(), buffer.size()) || in.gcount() > 0)
    content.append(buffer.data(), static_cast<std::size_t>(in.gcount()));
  if (in.bad()) throw UserError(path.string() + ": cannot read: " + reason(errno));
  return content;
}

// Walks the data lines of a text file, keeping the 1-based line number for messages.
class LineCursor {
 public:
  explicit LineCursor(const fs::path& path) : name_(path.string()), content_(read_all(path)) {
    if (content_.starts_with("\xEF\xBB\xBF")) pos_ = 3;  // UTF-8 byte-order mark
  }

  /// Moves to the next line that is neither blank nor a '#' comment.
  bool next() {
    while (pos_ < content_.size()) {
      std::size_t end = content_.find('\n', pos_);
      if (end == std::string::npos) end = content_.size();
      const std::string_view line(content_.data() + pos_, end - pos_);
      pos_ = end + 1;
      ++number_;
      const std::size_t first = line.find_first_not_of(kSpace);
      if (first == std::string_view::npos || line[first] == '#') continue;
      line_ = line;
      return true;
    }
    return false;
  }

  std::string_view line() const { return line_; }
  int number() const { return number_; }
  const std::string& name() const { return name_; }

  [[noreturn]] void fail(std::string_view what, std::string_view got,
                         std::string_view expected) const {
    throw UserError(fmt::format("{}:{}: {}: got '{}', expected {}", name_, number_, what,
                                shown(got), expected));
  }

 private:
  std::string name_;
  std::string content_;
  std::size_t pos_ = 0;
  int number_ = 0;
  std::string_view line_;
};

std::string_view trim(std::string_view s) {
  const std::size_t first = s.find_first_not_of(kSpace);
  if (first == std::string_view::npos) return {};
  const std::size_t last = s.find_last_not_of(kSpace);
  return s.substr(first, last - first + 1);
}

void split_whitespace(std::string_view line, std::vector<std::string_view>* tokens) {
  tokens->clear();
  std::size_t pos = 0;
  while (true) {
    const std::size_t first = line.find_first_not_of(kSpace, pos);
    if (first == std::string_view::npos) return;
    std::size_t last = line.find_first_of(kSpace, first);
    if (last == std::string_view::npos) last = line.size();
    tokens->push_back(line.substr(first, last - first));
    pos = last;
  }
}

std::string join(const std::vector<std::string_view>& tokens, std::size_t first, std::size_t count,
                 std::string_view separator) {
  std::string out;
  for (std::size_t i = first; i < first + count; ++i) {
    if (i > first) out += separator;
    out += tokens[i];
  }
  return out;
}

// The column layout of one format, for the messages.
struct Columns {
  std::vector<std::string_view> names;
  bool at_least = false;  // further columns are allowed and ignored
  std::string_view separator;

  std::string describe() const {
    return fmt::format("{}{} columns ({})", at_least ? "at least " : "", names.size(),
                       join(names, 0, names.size(), separator));
  }
};

void check_column_count(const LineCursor& c, const std::vector<std::string_view>& tokens,
                        const Columns& columns) {
  const bool ok = columns.at_least ? tokens.size() >= columns.names.size()
                                   : tokens.size() == columns.names.size();
  if (!ok)
    c.fail(fmt::format("wrong number of columns ({})", tokens.size()), trim(c.line()),
           columns.describe());
}

NumberStatus parse_double(std::string_view s, double* v) { return read_number(s, v); }

bool parse_int64(std::string_view s, std::int64_t* v) {
  return read_number(s, v) == NumberStatus::kOk;
}

double column_double(const LineCursor& c, const std::vector<std::string_view>& tokens,
                     std::size_t i, const Columns& columns) {
  double v = 0.0;
  const std::string_view token = tokens[i];
  const std::string_view name = columns.names[i];
  switch (parse_double(token, &v)) {
    case NumberStatus::kOk:
      return v;
    case NumberStatus::kNotFinite:
      c.fail(fmt::format("column {} ({}) is not finite", i + 1, name), token, "a finite number");
    case NumberStatus::kOutOfRange:
      c.fail(fmt::format("column {} ({}) is out of range", i + 1, name), token,
             "a number within double range");
    case NumberStatus::kNotNumber:
      break;
  }
  c.fail(fmt::format("column {} ({}) is not a number", i + 1, name), token, "a decimal number");
}

Vec3 column_vec3(const LineCursor& c, const std::vector<std::string_view>& tokens,
                 std::size_t first, const Columns& columns) {
  return {column_double(c, tokens, first, columns), column_double(c, tokens, first + 1, columns),
          column_double(c, tokens, first + 2, columns)};
}

// parse_seconds is exact, also for scientific notation ("1.036630e-01", as
// KITTI's times.txt has); a double is parsed only to name NaN/Inf in the message.
TimeNs column_seconds(const LineCursor& c, const std::vector<std::string_view>& tokens,
                      std::size_t i, const Columns& columns) {
  const std::string_view token = tokens[i];
  TimeNs ns = 0;
  if (parse_seconds(std::string(token), &ns)) return ns;
  double s = 0.0;
  if (parse_double(token, &s) == NumberStatus::kNotFinite)
    c.fail(fmt::format("column {} ({}) is not finite", i + 1, columns.names[i]), token,
           "a finite time in seconds");
  c.fail(fmt::format("column {} ({}) is not a time", i + 1, columns.names[i]), token,
         "seconds such as 1403636579.758555650 (within +-292 years)");
}

TimeNs column_nanoseconds(const LineCursor& c, const std::vector<std::string_view>& tokens,
                          std::size_t i, const Columns& columns) {
  const std::string_view token = tokens[i];
  std::int64_t ns = 0;
  if (parse_int64(token, &ns)) return ns;
  double v = 0.0;
  if (parse_double(token, &v) == NumberStatus::kNotFinite)
    c.fail(fmt::format("column {} ({}) is not finite", i + 1, columns.names[i]), token,
           "an integer time stamp in nanoseconds");
  c.fail(fmt::format("column {} ({}) is not an integer time stamp", i + 1, columns.names[i]), token,
         "an integer number of nanoseconds such as 1403636579758555392");
}

// Rejects stamps that do not strictly increase, naming the earlier line.
class StrictOrder {
 public:
  void check(const LineCursor& c, TimeNs t_ns, std::string_view token) {
    if (has_previous_ && t_ns <= previous_ns_)
      c.fail("time stamp does not increase", token,
             fmt::format("a time after '{}' (line {})", previous_token_, previous_line_));
    has_previous_ = true;
    previous_ns_ = t_ns;
    previous_token_ = std::string(token);
    previous_line_ = c.number();
  }

 private:
  bool has_previous_ = false;
  TimeNs previous_ns_ = 0;
  std::string previous_token_;
  int previous_line_ = 0;
};

// q = (w, x, y, z); `token` is the quaternion as written, for the message.
Quat checked_quaternion(const LineCursor& c, double w, double x, double y, double z,
                        std::string_view token) {
  const Quat q(w, x, y, z);
  const double norm = q.norm();
  if (!(std::fabs(norm - 1.0) <= kUnitTolerance))
    c.fail(fmt::format("quaternion is not unit length (norm {:.6g})", norm), token,
           fmt::format("a norm within {} of 1", kUnitTolerance));
  return q;  // SE3 normalises the remaining deviation
}

// ---------------------------------------------------------------------------
// Writing

void append_double(std::string* out, double v) {
  char buffer[32];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  DRIFTLAB_DEMAND(ec == std::errc());
  out->append(buffer, ptr);
}

void append_int(std::string* out, std::int64_t v) {
  char buffer[24];
  const auto [ptr, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  DRIFTLAB_DEMAND(ec == std::errc());
  out->append(buffer, ptr);
}

void append_values(std::string* out, std::initializer_list<double> values, char separator) {
  for (const double v : values) {
    *out += separator;
    append_double(out, v);
  }
}

// What a writer emits must pass its reader; a NaN pose or a repeated stamp is a
// bug upstream (the filters guard NaN, docs/design.md "Non-finite values"), not a user
// error.
void demand_writable(const Trajectory& trajectory) {
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const SE3& T = trajectory[i].T_W_C;
    DRIFTLAB_DEMAND_MSG(T.translation().allFinite() && T.quaternion().coeffs().allFinite(),
                        fmt::format("pose {} (t = {} ns) is not finite", i, trajectory[i].t_ns));
    if (i > 0)
      DRIFTLAB_DEMAND_MSG(trajectory[i].t_ns > trajectory[i - 1].t_ns,
                          fmt::format("time stamps do not increase at pose {} ({} ns after {} ns)",
                                      i, trajectory[i].t_ns, trajectory[i - 1].t_ns));
  }
}

const Columns kTumColumns{{"t", "tx", "ty", "tz", "qx", "qy", "qz", "qw"}, false, " "};
const Columns kKittiColumns{
    {"r11", "r12", "r13", "tx", "r21", "r22", "r23", "ty", "r31", "r32", "r33", "tz"}, false, " "};
const Columns kKittiTimesColumns{{"t"}, false, " "};
const Columns kEurocGtColumns{{"#timestamp", "p_RS_R_x [m]", "p_RS_R_y [m]", "p_RS_R_z [m]",
                               "q_RS_w []", "q_RS_x []", "q_RS_y []", "q_RS_z []"},
                              true,
                              ","};
const Columns kEurocImuColumns{
    {"#timestamp [ns]", "w_RS_S_x [rad s^-1]", "w_RS_S_y [rad s^-1]", "w_RS_S_z [rad s^-1]",
     "a_RS_S_x [m s^-2]", "a_RS_S_y [m s^-2]", "a_RS_S_z [m s^-2]"},
    false,
    ","};

}  // namespace

// ---------------------------------------------------------------------------
// Format names

TrajectoryFormat format_from_name(std::string_view name) {
  if (const auto f = yaml::enum_from_name_any_case<TrajectoryFormat>(name)) return *f;
  throw UserError(fmt::format("unknown trajectory format: got '{}', expected one of: {}",
                              shown(name), yaml::enum_choices<TrajectoryFormat>()));
}

std::string_view format_name(TrajectoryFormat format) { return yaml::enum_name(format); }

// ---------------------------------------------------------------------------
// TUM

Trajectory read_tum(const fs::path& path) {
  LineCursor c(path);
  Trajectory out;
  std::vector<std::string_view> tokens;
  StrictOrder order;
  while (c.next()) {
    split_whitespace(c.line(), &tokens);
    check_column_count(c, tokens, kTumColumns);
    const TimeNs t_ns = column_seconds(c, tokens, 0, kTumColumns);
    const Vec3 p = column_vec3(c, tokens, 1, kTumColumns);
    const double qx = column_double(c, tokens, 4, kTumColumns);
    const double qy = column_double(c, tokens, 5, kTumColumns);
    const double qz = column_double(c, tokens, 6, kTumColumns);
    const double qw = column_double(c, tokens, 7, kTumColumns);
    const Quat q = checked_quaternion(c, qw, qx, qy, qz, join(tokens, 4, 4, " "));
    order.check(c, t_ns, tokens[0]);
    out.push_back({t_ns, SE3(q, p)});
  }
  return out;
}

void write_tum(const fs::path& path, const Trajectory& trajectory) {
  demand_writable(trajectory);
  std::string text = "# timestamp tx ty tz qx qy qz qw\n";
  for (const StampedPose& pose : trajectory) {
    const Vec3& p = pose.T_W_C.translation();
    const Quat& q = pose.T_W_C.quaternion();
    text += format_seconds(pose.t_ns);
    append_values(&text, {p.x(), p.y(), p.z(), q.x(), q.y(), q.z(), q.w()}, ' ');
    text += '\n';
  }
  write_file_atomic(path, text);
}

// ---------------------------------------------------------------------------
// KITTI

std::vector<TimeNs> read_kitti_times(const fs::path& path) {
  LineCursor c(path);
  std::vector<TimeNs> out;
  std::vector<std::string_view> tokens;
  StrictOrder order;
  while (c.next()) {
    split_whitespace(c.line(), &tokens);
    check_column_count(c, tokens, kKittiTimesColumns);
    const TimeNs t_ns = column_seconds(c, tokens, 0, kKittiTimesColumns);
    order.check(c, t_ns, tokens[0]);
    out.push_back(t_ns);
  }
  return out;
}

Trajectory read_kitti(const fs::path& path, const KittiTiming& timing) {
  LineCursor c(path);
  Trajectory out;
  std::vector<std::string_view> tokens;
  while (c.next()) {
    split_whitespace(c.line(), &tokens);
    check_column_count(c, tokens, kKittiColumns);
    Mat3 R;
    Vec3 t;
    for (int row = 0; row < 3; ++row) {
      for (int col = 0; col < 3; ++col)
        R(row, col) =
            column_double(c, tokens, static_cast<std::size_t>(4 * row + col), kKittiColumns);
      t(row) = column_double(c, tokens, static_cast<std::size_t>(4 * row + 3), kKittiColumns);
    }
    const double orthonormality = (R.transpose() * R - Mat3::Identity()).cwiseAbs().maxCoeff();
    const double det = R.determinant();
    if (!(orthonormality <= kUnitTolerance) || !(det > 0.0)) {
      const std::string rotation =
          fmt::format("{} {} {} {} {} {} {} {} {}", tokens[0], tokens[1], tokens[2], tokens[4],
                      tokens[5], tokens[6], tokens[8], tokens[9], tokens[10]);
      c.fail(fmt::format("rotation part is not a rotation matrix (max |R^T R - I| = {:.3g}, "
                         "det = {:.6g})",
                         orthonormality, det),
             rotation,
             fmt::format("an orthonormal matrix with determinant +1 (within {})", kUnitTolerance));
    }
    // Files written with 6 significant digits are orthonormal only to ~1e-6:
    // take the nearest rotation (polar decomposition) rather than Eigen's
    // matrix-to-quaternion on the raw entries, which ignores half of them.
    const Eigen::JacobiSVD<Mat3> svd(R, Eigen::ComputeFullU | Eigen::ComputeFullV);
    const Mat3 R_nearest = svd.matrixU() * svd.matrixV().transpose();
    out.push_back({0, SE3(Quat(R_nearest), t)});
  }

  std::vector<TimeNs> times;
  std::string times_source;
  if (!timing.times_ns.empty()) {
    times = timing.times_ns;
    times_source = "the given time stamps";
  } else if (!timing.times_path.empty()) {
    times = read_kitti_times(timing.times_path);
    times_source = timing.times_path.string();
  } else {
    if (timing.period_ns <= 0)
      throw UserError(
          fmt::format("{}: cannot assign time stamps: got period '{}' ns, expected a "
                      "period > 0",
                      path.string(), timing.period_ns));
    for (std::size_t i = 0; i < out.size(); ++i)
      out[i].t_ns = static_cast<TimeNs>(i) * timing.period_ns;
    return out;
  }
  if (times.size() != out.size())
    throw UserError(
        fmt::format("{}: pose count does not match the time stamps: got '{}' poses, "
                    "expected {} (one per time stamp in {})",
                    path.string(), out.size(), times.size(), times_source));
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (i > 0 && times[i] <= times[i - 1])
      throw UserError(fmt::format(
          "{}: time stamps do not increase at pose {}: got '{}', expected "
          "a time after {} ({})",
          path.string(), i, format_seconds(times[i]), format_seconds(times[i - 1]), times_source));
    out[i].t_ns = times[i];
  }
  return out;
}

void write_kitti(const fs::path& path, const Trajectory& trajectory) {
  demand_writable(trajectory);
  std::string text;
  for (const StampedPose& pose : trajectory) {
    const Mat3 R = pose.T_W_C.rotation();
    const Vec3& t = pose.T_W_C.translation();
    for (int row = 0; row < 3; ++row) {
      if (row > 0) text += ' ';
      append_double(&text, R(row, 0));
      append_values(&text, {R(row, 1), R(row, 2), t(row)}, ' ');
    }
    text += '\n';
  }
  write_file_atomic(path, text);
}

void write_kitti_times(const fs::path& path, const Trajectory& trajectory) {
  demand_writable(trajectory);
  std::string text;
  for (const StampedPose& pose : trajectory) text += format_seconds(pose.t_ns) + '\n';
  write_file_atomic(path, text);
}

// ---------------------------------------------------------------------------
// EuRoC

Trajectory read_euroc_groundtruth(const fs::path& path) {
  LineCursor c(path);
  Trajectory out;
  std::vector<std::string_view> tokens;
  StrictOrder order;
  while (c.next()) {
    const std::vector<std::string> cells = split_csv_line(c.line(), CsvTrim::kSpaces);
    tokens.assign(cells.begin(), cells.end());
    check_column_count(c, tokens, kEurocGtColumns);
    const TimeNs t_ns = column_nanoseconds(c, tokens, 0, kEurocGtColumns);
    const Vec3 p = column_vec3(c, tokens, 1, kEurocGtColumns);
    const double qw = column_double(c, tokens, 4, kEurocGtColumns);
    const double qx = column_double(c, tokens, 5, kEurocGtColumns);
    const double qy = column_double(c, tokens, 6, kEurocGtColumns);
    const double qz = column_double(c, tokens, 7, kEurocGtColumns);
    const Quat q = checked_quaternion(c, qw, qx, qy, qz, join(tokens, 4, 4, ","));
    order.check(c, t_ns, tokens[0]);
    out.push_back({t_ns, SE3(q, p)});
  }
  return out;
}

void write_euroc_groundtruth(const fs::path& path, const Trajectory& trajectory,
                             const std::vector<Vec3>& velocities_W_m_s,
                             const std::vector<ImuBias>& biases) {
  demand_writable(trajectory);
  const bool with_velocity = !velocities_W_m_s.empty(), with_bias = !biases.empty();
  DRIFTLAB_DEMAND_MSG(!with_velocity || velocities_W_m_s.size() == trajectory.size(),
                      "write_euroc_groundtruth: one velocity per pose");
  DRIFTLAB_DEMAND_MSG(!with_bias || (with_velocity && biases.size() == trajectory.size()),
                      "write_euroc_groundtruth: one bias per pose, after the velocities");
  std::string text =
      "#timestamp,p_RS_R_x [m],p_RS_R_y [m],p_RS_R_z [m],q_RS_w [],q_RS_x [],q_RS_y [],q_RS_z []";
  if (with_velocity) text += ",v_RS_R_x [m s^-1],v_RS_R_y [m s^-1],v_RS_R_z [m s^-1]";
  if (with_bias)
    text +=
        ",b_w_RS_S_x [rad s^-1],b_w_RS_S_y [rad s^-1],b_w_RS_S_z [rad s^-1],"
        "b_a_RS_S_x [m s^-2],b_a_RS_S_y [m s^-2],b_a_RS_S_z [m s^-2]";
  text += '\n';
  for (std::size_t i = 0; i < trajectory.size(); ++i) {
    const Vec3& p = trajectory[i].T_W_C.translation();
    const Quat& q = trajectory[i].T_W_C.quaternion();
    append_int(&text, trajectory[i].t_ns);
    append_values(&text, {p.x(), p.y(), p.z(), q.w(), q.x(), q.y(), q.z()}, ',');
    if (with_velocity) {
      const Vec3& v = velocities_W_m_s[i];
      DRIFTLAB_DEMAND_MSG(v.allFinite(), fmt::format("velocity {} is not finite", i));
      append_values(&text, {v.x(), v.y(), v.z()}, ',');
    }
    if (with_bias) {
      const ImuBias& b = biases[i];
      DRIFTLAB_DEMAND_MSG(b.gyro.allFinite() && b.accel.allFinite(),
                          fmt::format("bias {} is not finite", i));
      append_values(
          &text, {b.gyro.x(), b.gyro.y(), b.gyro.z(), b.accel.x(), b.accel.y(), b.accel.z()}, ',');
    }
    text += '\n';
  }
  write_file_atomic(path, text);
}

std::vector<ImuSample> read_euroc_imu(const fs::path& path) {
  LineCursor c(path);
  std::vector<ImuSample> out;
  std::vector<std::string_view> tokens;
  StrictOrder order;
  while (c.next()) {
    const std::vector<std::string> cells = split_csv_line(c.line(), CsvTrim::kSpaces);
    tokens.assign(cells.begin(), cells.end());
    check_column_count(c, tokens, kEurocImuColumns);
    ImuSample s;
    s.t_ns = column_nanoseconds(c, tokens, 0, kEurocImuColumns);
    s.gyro_rad_s = column_vec3(c, tokens, 1, kEurocImuColumns);
    s.accel_m_s2 = column_vec3(c, tokens, 4, kEurocImuColumns);
    order.check(c, s.t_ns, tokens[0]);
    out.push_back(s);
  }
  return out;
}

void write_euroc_imu(const fs::path& path, const std::vector<ImuSample>& samples) {
  std::string text =
      "#timestamp [ns],w_RS_S_x [rad s^-1],w_RS_S_y [rad s^-1],w_RS_S_z [rad s^-1],"
      "a_RS_S_x [m s^-2],a_RS_S_y [m s^-2],a_RS_S_z [m s^-2]\n";
  for (std::size_t i = 0; i < samples.size(); ++i) {
    const ImuSample& s = samples[i];
    DRIFTLAB_DEMAND_MSG(s.gyro_rad_s.allFinite() && s.accel_m_s2.allFinite(),
                        fmt::format("IMU sample {} (t = {} ns) is not finite", i, s.t_ns));
    if (i > 0)
      DRIFTLAB_DEMAND_MSG(s.t_ns > samples[i - 1].t_ns,
                          fmt::format("IMU time stamps do not increase at sample {}", i));
    append_int(&text, s.t_ns);
    append_values(&text,
                  {s.gyro_rad_s.x(), s.gyro_rad_s.y(), s.gyro_rad_s.z(), s.accel_m_s2.x(),
                   s.accel_m_s2.y(), s.accel_m_s2.z()},
                  ',');
    text += '\n';
  }
  write_file_atomic(path, text);
}

// ---------------------------------------------------------------------------
// Dispatch

Trajectory read_trajectory(const fs::path& path, TrajectoryFormat format,
                           const KittiTiming& kitti) {
  switch (format) {
    case TrajectoryFormat::kTum:
      return read_tum(path);
    case TrajectoryFormat::kKitti:
      return read_kitti(path, kitti);
    case TrajectoryFormat::kEuroc:
      return read_euroc_groundtruth(path);
  }
  DRIFTLAB_DEMAND_MSG(false, "unknown TrajectoryFormat value");
  return {};
}

void write_trajectory(const fs::path& path, const Trajectory& trajectory, TrajectoryFormat format) {
  switch (format) {
    case TrajectoryFormat::kTum:
      write_tum(path, trajectory);
      return;
    case TrajectoryFormat::kKitti:
      write_kitti(path, trajectory);
      return;
    case TrajectoryFormat::kEuroc:
      write_euroc_groundtruth(path, trajectory);
      return;
  }
  DRIFTLAB_DEMAND_MSG(false, "unknown TrajectoryFormat value");
}

}  // namespace driftlab
