#include "python/python_vo.hpp"

#include <fmt/format.h>
#include <pybind11/numpy.h>

#include <chrono>
#include <condition_variable>
#include <cstring>
#include <map>
#include <mutex>
#include <thread>

#include "python/records.hpp"
#include "vo/registry.hpp"

namespace driftlab::python {

namespace {

// The Python factories by name: registering a name again replaces its factory (the C++
// registry keeps the first registration, which looks the factory up here).
std::mutex& specs_mutex() {
  static std::mutex m;
  return m;
}
std::map<std::string, PythonVoSpec>& specs() {
  static auto* s = new std::map<std::string, PythonVoSpec>();  // outlives the interpreter
  return *s;
}

py::object rig_record(const StereoRig& rig) {
  py::object r = record_class()();
  py::setattr(r, "fx", py::float_(rig.camera.fx));
  py::setattr(r, "fy", py::float_(rig.camera.fy));
  py::setattr(r, "cx", py::float_(rig.camera.cx));
  py::setattr(r, "cy", py::float_(rig.camera.cy));
  py::setattr(r, "width", py::int_(rig.camera.width));
  py::setattr(r, "height", py::int_(rig.camera.height));
  py::setattr(r, "baseline_m", py::float_(rig.baseline_m));
  return r;
}

py::array_t<std::uint8_t> image(const cv::Mat& m) {
  py::array_t<std::uint8_t> a({m.rows, m.cols});
  for (int r = 0; r < m.rows; ++r)
    std::memcpy(a.mutable_data(r, 0), m.ptr<std::uint8_t>(r), static_cast<std::size_t>(m.cols));
  return a;
}

// A 4x4 rigid transform from what process() returned, or why not.
std::optional<SE3> pose_of(const py::handle& value, std::string* reason) {
  const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(value);
  if (!a || a.ndim() != 2 || a.shape(0) != 4 || a.shape(1) != 4) {
    *reason = "python: process() returned " + py::repr(value).cast<std::string>().substr(0, 60) +
              ", expected a 4x4 pose or None";
    return std::nullopt;
  }
  Mat4 T;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) T(i, j) = *a.data(i, j);
  const Mat3 R = T.topLeftCorner<3, 3>();
  const double orthonormal = (R.transpose() * R - Mat3::Identity()).norm();
  if (!T.allFinite()) {
    *reason = "python: process() returned a pose that is not finite";
  } else if (orthonormal > 1e-6 || R.determinant() < 0 ||
             (T.bottomRows<1>() - Eigen::RowVector4d(0, 0, 0, 1)).norm() > 1e-12) {
    *reason = "python: process() returned a 4x4 that is not a rigid transform";
  } else {
    return SE3(Quat(R).normalized(), Vec3(T.topRightCorner<3, 1>()));
  }
  return std::nullopt;
}

// Raises TimeoutError in the calling Python thread if `call` has not returned within timeout_s:
// Python checks for it between bytecodes, so a VO stuck inside one C call is stopped when it
// returns from it.
class Watchdog {
 public:
  explicit Watchdog(double timeout_s) : ident_(PyThread_get_thread_ident()) {
    if (timeout_s <= 0) return;
    thread_ = std::thread([this, timeout_s] {
      std::unique_lock lock(mutex_);
      if (done_cv_.wait_for(lock, std::chrono::duration<double>(timeout_s), [&] { return done_; }))
        return;
      fired_ = true;
      lock.unlock();
      py::gil_scoped_acquire gil;
      PyThreadState_SetAsyncExc(ident_, PyExc_TimeoutError);
    });
  }
  ~Watchdog() {
    if (!thread_.joinable()) return;
    {
      std::lock_guard lock(mutex_);
      done_ = true;
    }
    done_cv_.notify_all();
    {
      py::gil_scoped_release release;  // the watchdog may be waiting for the GIL
      thread_.join();
    }
    // Fired as the call returned: the exception must not surface in later Python code.
    if (fired_) PyThreadState_SetAsyncExc(ident_, nullptr);
  }
  Watchdog(const Watchdog&) = delete;
  Watchdog& operator=(const Watchdog&) = delete;

 private:
  unsigned long ident_;
  std::thread thread_;
  std::mutex mutex_;
  std::condition_variable done_cv_;
  bool done_ = false;
  bool fired_ = false;
};

}  // namespace

void register_python_vo(PythonVoSpec spec) {
  const std::string name = spec.name;
  bool known = false;
  {
    const std::lock_guard lock(specs_mutex());
    known = specs().count(name) > 0;
    specs()[name] = std::move(spec);
  }
  if (known) return;
  vo::register_vo(name, [name](const StereoRig& rig, Rng) -> std::unique_ptr<vo::StereoOdometry> {
    py::gil_scoped_acquire gil;
    PythonVoSpec s;
    {
      const std::lock_guard lock(specs_mutex());
      s = specs().at(name);
    }
    return std::make_unique<PythonVo>(s, rig);
  });
}

PythonVo::PythonVo(const PythonVoSpec& spec, const StereoRig& rig)
    : name_(spec.name),
      factory_(spec.factory),
      rig_(rig_record(rig)),
      timeout_s_(spec.timeout_s),
      rig_cpp_(rig) {
  try {
    object_ = factory_(rig_);
  } catch (py::error_already_set& e) {
    throw UserError(fmt::format("python VO {}: creating it failed: {}", name_, e.what()));
  }
}

PythonVo::~PythonVo() {
  py::gil_scoped_acquire gil;
  object_ = py::object();
  rig_ = py::object();
  factory_ = py::object();
}

void PythonVo::reset() {
  py::gil_scoped_acquire gil;
  last_pose_.reset();
  started_ = false;
  object_ = factory_(rig_);  // a new object: its first frame again
}

std::optional<SE3> PythonVo::call(const vo::StereoFrame& frame, std::string* reason) {
  py::gil_scoped_acquire gil;
  try {
    py::object result;
    {
      Watchdog watchdog(timeout_s_);
      result = object_.attr("process")(static_cast<double>(frame.t_ns) * 1e-9, image(frame.left),
                                       image(frame.right));
    }
    if (result.is_none()) {
      *reason = "python: lost";
      return std::nullopt;
    }
    return pose_of(result, reason);
  } catch (py::error_already_set& e) {
    const bool timeout = e.matches(PyExc_TimeoutError);
    *reason = timeout ? fmt::format("python: process() ran past {} s", timeout_s_)
                      : "python: " + std::string(py::str(e.type().attr("__name__"))) + ": " +
                            std::string(py::str(e.value())).substr(0, 120);
    return std::nullopt;
  }
}

vo::VoResult PythonVo::process(const vo::StereoFrame& frame) {
  const auto t0 = vo::detail::begin_frame(frame, rig_cpp_.camera, "python VO");
  vo::VoResult r;
  std::string reason;
  const std::optional<SE3> pose = call(frame, &reason);
  const bool first = !started_;
  started_ = true;
  if (!pose) {
    vo::detail::end_without_motion(&r, first ? "first frame" : reason, t0);
    return r;
  }
  const std::optional<SE3> previous = last_pose_;
  last_pose_ = pose;
  if (first || !previous) {
    vo::detail::end_without_motion(&r, first ? "first frame" : "python: first pose after lost", t0);
    return r;
  }
  if (const char* bad = vo::detail::end_with_motion(&r, previous->inverse() * *pose, 0, t0))
    vo::detail::end_without_motion(&r, bad, t0);
  return r;
}

}  // namespace driftlab::python
