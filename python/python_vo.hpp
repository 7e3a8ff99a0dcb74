// A VO written in Python, run in-process by the pipeline beside the C++ VOs and evaluated like
// them (driftlab.register_vo): an object with process(t, left, right) returning the left
// camera's 4x4 pose in its own world frame, or None when it has lost track. The adapter turns
// the poses into the motions the pipeline accumulates (river paper Eq. (3)), and what goes
// wrong into results without a motion whose reason the run record's tracking counts: a
// Python exception, a pose that is not a finite rigid 4x4 transform, a call past the timeout.
#pragma once

#include <pybind11/pybind11.h>

#include <memory>
#include <optional>
#include <string>

#include "core/camera.hpp"
#include "vo/stereo_odometry.hpp"

namespace driftlab::python {

namespace py = pybind11;

struct PythonVoSpec {
  std::string name;
  py::object factory;    // called with the rig (a driftlab.Record): the VO object
  double timeout_s = 0;  // a process() call past this raises TimeoutError in it; 0: none
};

/// Registers (or, for a name registered before, replaces) a Python VO under spec.name.
void register_python_vo(PythonVoSpec spec);

class PythonVo final : public vo::StereoOdometry {
 public:
  PythonVo(const PythonVoSpec& spec, const StereoRig& rig);
  ~PythonVo() override;

  vo::VoResult process(const vo::StereoFrame& frame) override;
  void reset() override;
  std::string name() const override { return name_; }

 private:
  // The pose the object returned for this frame, or why there is none.
  std::optional<SE3> call(const vo::StereoFrame& frame, std::string* reason);

  std::string name_;
  py::object factory_, rig_, object_;
  double timeout_s_;
  StereoRig rig_cpp_;
  std::optional<SE3> last_pose_;  // the last pose it returned since the first frame
  bool started_ = false;
};

}  // namespace driftlab::python
