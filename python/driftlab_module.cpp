// driftlab._driftlab: the C++ side of `import driftlab` (python/driftlab/__init__.py is the
// Python side). Scenarios load and run as on the command line, and their records come back
// typed (python/records.hpp); a driftlab UserError is a driftlab.Error.
#include <fmt/format.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>
#include <pybind11/stl/filesystem.h>

#include <filesystem>
#include <string>
#include <vector>

#include "core/error.hpp"
#include "core/trajectory_io.hpp"
#include "core/yaml_io.hpp"
#include "eval/evaluate.hpp"
#include "pipeline/render_stage.hpp"
#include "pipeline/run.hpp"
#include "pipeline/scenario.hpp"
#include "python/python_vo.hpp"
#include "python/records.hpp"
#include "record/run_record.hpp"
#include "study/sweep.hpp"
#include "study/sweep_merge.hpp"
#include "study/sweep_records.hpp"
#include "study/sweep_runner.hpp"

namespace driftlab::python {

namespace fs = std::filesystem;

py::object record_class() { return py::module_::import("driftlab._record").attr("Record"); }

namespace {

// KEY=VALUE assignments from a dict (each value as YAML: a str as it is, anything else as JSON,
// which YAML reads) or from a list of "KEY=VALUE" strings; None: none.
std::vector<std::string> assignments(const py::object& given) {
  std::vector<std::string> out;
  if (given.is_none()) return out;
  if (py::isinstance<py::dict>(given)) {
    const auto dumps = py::module_::import("json").attr("dumps");
    for (const auto& [key, value] : given.cast<py::dict>())
      out.push_back(py::str(key).cast<std::string>() + "=" +
                    (py::isinstance<py::str>(value) ? value : dumps(value)).cast<std::string>());
    return out;
  }
  for (const auto& item : given) out.push_back(py::str(item).cast<std::string>());
  return out;
}

// A trajectory given as a file (with its format) or as rows of t [s], x, y, z, qx, qy, qz, qw
// (TUM's columns).
Trajectory trajectory_of(const py::object& given, const std::string& format, const char* what) {
  if (py::isinstance<py::str>(given) || py::hasattr(given, "__fspath__"))
    return read_trajectory(
        py::str(py::module_::import("os").attr("fspath")(given)).cast<std::string>(),
        format_from_name(format));
  const auto rows = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(given);
  if (!rows || rows.ndim() != 2 || rows.shape(1) != 8)
    throw UserError(
        fmt::format("{}: expected a file name or an N x 8 array of t [s], x, y, z, "
                    "qx, qy, qz, qw",
                    what));
  Trajectory out;
  const auto r = rows.unchecked<2>();
  for (py::ssize_t i = 0; i < rows.shape(0); ++i) {
    const Quat q(r(i, 7), r(i, 4), r(i, 5), r(i, 6));
    if (!(q.norm() > 0.5))
      throw UserError(fmt::format("{}: row {}: quaternion of norm {}, expected a unit quaternion",
                                  what, i, q.norm()));
    out.push_back({static_cast<TimeNs>(std::llround(r(i, 0) * 1e9)),
                   SE3(q.normalized(), Vec3(r(i, 1), r(i, 2), r(i, 3)))});
  }
  return out;
}

// The evaluation's options: the scenario's `eval` section, each KEY=VALUE applied in order and
// checked as the scenario's are.
eval::EvalOptions eval_options(const std::vector<std::string>& assignments) {
  eval::EvalOptions options;
  for (const auto& a : assignments)
    yaml::read_into(yaml::override_document(a), {"driftlab.evaluate(options) " + a, false},
                    &options);
  yaml::validate_or_throw(options, "driftlab.evaluate");
  return options;
}

py::object evaluate(const py::object& gt, const py::object& est, const std::string& format,
                    const py::object& options, const std::string& name) {
  eval::EvaluationInput in;
  in.options = eval_options(assignments(options));
  in.gt = trajectory_of(gt, format, "gt");
  in.est = trajectory_of(est, format, "est");
  in.algorithm = name;
  const eval::Evaluation e = [&] {
    py::gil_scoped_release release;
    return eval::evaluate(in);
  }();
  return to_python(eval::evaluation_record(e, in.options));
}

py::object run(const pipeline::Scenario& scenario, const fs::path& out, bool replace,
               bool progress) {
  pipeline::RunOptions options;
  options.replace_existing = replace;
  options.progress = progress ? stderr : nullptr;
  options.frame_cache = pipeline::FrameCacheOptions::from_environment();
  const auto summary = [&] {
    py::gil_scoped_release release;
    return pipeline::run_scenario(scenario, out, options);
  }();
  return to_python(summary.run_record());
}

std::string plan_sweep(const fs::path& sweep_file, const fs::path& out, const py::object& set,
                       bool force) {
  study::Sweep sweep = study::load_sweep(sweep_file);
  study::apply_sets(&sweep, assignments(set));
  return study::write_plan(study::plan_sweep(sweep), out, force).brief();
}

py::tuple run_sweep(const fs::path& folder, std::size_t jobs, const fs::path& executable,
                    bool force, double job_timeout_s) {
  const auto manifest = study::read_manifest(folder);
  study::SweepRunOptions o;
  o.executable = executable;
  o.parallel = std::max<std::size_t>(1, jobs);
  o.force = force;
  o.job_timeout_s = job_timeout_s;
  const auto summary = [&] {
    py::gil_scoped_release release;
    return study::run_sweep_jobs(manifest, o);
  }();
  return py::make_tuple(summary.brief(), summary.failed_ids);
}

py::object merge_sweep(const fs::path& folder, const std::vector<std::string>& regress, bool plots,
                       bool allow_missing) {
  study::MergeOptions o;
  o.run_regressions = regress;
  o.plots = plots;
  o.allow_missing = allow_missing;
  const auto manifest = study::read_manifest(folder);
  const auto summary = [&] {
    py::gil_scoped_release release;
    return study::merge_sweep(manifest, o);
  }();
  return to_python(study::read_json_record<study::SweepSummaryRecord>(summary.dir / "metrics.json",
                                                                      "sweep summary"));
}

template <class Pixel>
py::array_t<Pixel> array_of(int width, int height, const std::vector<Pixel>& pixels) {
  py::array_t<Pixel> a({height, width});
  std::copy(pixels.begin(), pixels.end(), a.mutable_data());
  return a;
}

// driftlab.render(): the frames of `driftlab render` as numpy arrays, one at a time.
class RenderFrames {
 public:
  RenderFrames(const pipeline::Scenario& scenario, int frames, bool depth, bool masks)
      : sequence_(scenario, frames, depth, masks) {}

  py::object next() {
    std::optional<pipeline::RenderSequence::Frame> f;
    {
      py::gil_scoped_release release;
      f = sequence_.next();
    }
    if (!f) throw py::stop_iteration();
    py::object r = record_class()();
    const auto& im = f->images;
    py::setattr(r, "k", py::int_(f->k));
    py::setattr(r, "t_ns", py::int_(f->t_ns));
    py::setattr(r, "t", py::float_(static_cast<double>(f->t_ns) * 1e-9));
    py::setattr(r, "left", array_of(im.left.width, im.left.height, im.left.pixels));
    py::setattr(r, "right", array_of(im.right.width, im.right.height, im.right.pixels));
    py::setattr(r, "depth",
                im.depth_left.depth_m.empty()
                    ? py::object(py::none())
                    : array_of(im.depth_left.width, im.depth_left.height, im.depth_left.depth_m));
    py::setattr(r, "mask",
                im.moving_left.pixels.empty()
                    ? py::object(py::none())
                    : array_of(im.moving_left.width, im.moving_left.height, im.moving_left.pixels));
    py::setattr(r, "moving_px", py::float_(f->moving_px));
    return r;
  }

 private:
  pipeline::RenderSequence sequence_;
};

py::list fields(const std::string& kind) {
  if (kind == "run") return fields_to_python<record::RunRecord>();
  if (kind == "evaluation") return fields_to_python<eval::EvaluationRecord>();
  if (kind == "sweep") return fields_to_python<study::SweepSummaryRecord>();
  throw UserError(fmt::format("fields('{}'): expected 'run', 'evaluation' or 'sweep'", kind));
}

}  // namespace

}  // namespace driftlab::python

PYBIND11_MODULE(_driftlab, m) {
  using namespace driftlab;
  using namespace driftlab::python;
  m.doc() = "driftlab's C++ core; use the driftlab package";
  m.attr("__version__") = DRIFTLAB_VERSION;
  py::register_exception<UserError>(m, "Error", PyExc_ValueError);

  py::class_<pipeline::Scenario>(m, "Scenario",
                                 "A scenario, loaded and checked as `driftlab run` loads it")
      .def_static(
          "load",
          [](const fs::path& path, const py::object& set) {
            return pipeline::load_scenario(path, assignments(set));
          },
          py::arg("path"), py::arg("set") = py::none(),
          "Loads a scenario file with `set` applied ({key.path: value} or [\"key.path=value\"]), "
          "checked as `driftlab run` checks it; raises driftlab.Error naming the file, line and "
          "key")
      .def_property_readonly("name", [](const pipeline::Scenario& s) { return s.name; })
      .def_property_readonly("seed", [](const pipeline::Scenario& s) { return s.seed; })
      .def("to_yaml", &pipeline::resolved_yaml,
           "The resolved scenario as YAML: every key, defaults filled in")
      .def("__repr__", [](const pipeline::Scenario& s) {
        return fmt::format("<driftlab.Scenario {} seed={}>", s.name, s.seed);
      });
  py::class_<RenderFrames>(m, "RenderFrames")
      .def("__iter__", [](RenderFrames& r) -> RenderFrames& { return r; })
      .def("__next__", &RenderFrames::next);
  m.def(
      "render",
      [](const pipeline::Scenario& s, int frames, bool depth, bool masks) {
        return std::make_unique<RenderFrames>(s, frames, depth, masks);
      },
      py::arg("scenario"), py::arg("frames") = 0, py::arg("depth") = false,
      py::arg("masks") = false);
  m.def("run", &run, py::arg("scenario"), py::arg("out"), py::arg("replace") = false,
        py::arg("progress") = false);
  m.def(
      "read_run", [](const fs::path& path) { return to_python(record::read_run_record(path)); },
      py::arg("path"));
  m.def("evaluate", &evaluate, py::arg("gt"), py::arg("est"), py::arg("format") = "tum",
        py::arg("options") = py::none(), py::arg("name") = "estimate");
  m.def("plan_sweep", &plan_sweep, py::arg("sweep_file"), py::arg("out"), py::arg("set"),
        py::arg("force"));
  m.def("run_sweep", &run_sweep, py::arg("folder"), py::arg("jobs"), py::arg("executable"),
        py::arg("force"), py::arg("job_timeout_s"));
  m.def("merge_sweep", &merge_sweep, py::arg("folder"), py::arg("regress"), py::arg("plots"),
        py::arg("allow_missing"));
  m.def("fields", &fields, py::arg("kind"));
  m.def(
      "register_vo",
      [](const std::string& name, py::object factory, double timeout_s) {
        register_python_vo({name, std::move(factory), timeout_s});
      },
      py::arg("name"), py::arg("factory"), py::arg("timeout_s") = 0.0);
}
