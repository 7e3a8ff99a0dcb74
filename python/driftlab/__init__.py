"""driftlab from Python: load and run scenarios, evaluate trajectories and merge sweeps, with
the same checks and numbers as the `driftlab` command, and results as typed records.

    import driftlab
    scenario = driftlab.Scenario.load("scenarios/river_crossing.yaml",
                                      set={"pipeline.max_frames": 40})
    record = driftlab.run(scenario, out="out/crossing")
    print(record.algorithms["sparse"].evaluation.ape.trans_m.rmse)

docs/python.md is the manual; docs/metrics-reference.md names every field.
"""

from driftlab._record import Record, isnan
from driftlab import _driftlab, _paths

_paths.use_installed_assets()

Error = _driftlab.Error
Scenario = _driftlab.Scenario
__version__ = _driftlab.__version__


def run(scenario, out, replace=False, progress=False):
    """Runs a Scenario into the folder `out` (written atomically, as `driftlab run`) and returns
    its run record (metrics.json's, as a Record)."""
    return _driftlab.run(scenario, str(out), replace, progress)


def render(scenario, frames=0, depth=False, masks=False):
    """The frames `driftlab render` writes, as an iterator of Records with k (the frame's index),
    t_ns and t [s] (its stamp), left and right (uint8 arrays, height x width: the images the
    camera delivers), and with depth / masks also depth (float32 [m], 0 for sky) and mask
    (uint8, 255 on moving things). frames > 0 overrides pipeline.max_frames."""
    return _driftlab.render(scenario, frames, depth, masks)


def read_run(path):
    """The run record of a run folder or of its metrics.json."""
    return _driftlab.read_run(str(path))


def evaluate(gt, est, format="tum", options=None, name="estimate"):
    """Evaluates an estimate against ground truth as `driftlab eval` does.

    gt, est: trajectory files (in `format`: tum, kitti or euroc) or N x 8 arrays of t [s],
    x, y, z, qx, qy, qz, qw. options: keys of a scenario's `eval` section ({key: value}), with
    `driftlab eval`'s defaults (align: horn). Returns the evaluation record (the evaluation part
    of a run record's algorithms[NAME])."""
    given = dict(options or {})
    return _driftlab.evaluate(gt, est, format, {**_EVAL_DEFAULTS, **given}, name)


# What `driftlab eval` sets where its flags are not given and a scenario's `eval` section differs.
_EVAL_DEFAULTS = {"align": "horn"}


def register_vo(name, factory, timeout_s=0):
    """Adds a VO written in Python, which scenarios then select as `pipeline.vo: [NAME]` beside
    the built-in ones (register it before loading them). `factory(rig)` makes one: rig has fx,
    fy, cx, cy, width, height and baseline_m of the rectified stereo pair. Its
    `process(t, left, right)` gets the time [s] and the rectified images (uint8 arrays, height
    x width) and returns the left camera's 4x4 pose in its own world frame (the first frame's
    pose may be anything), or None when it has lost track. A raised exception, a pose that is
    not a finite rigid transform, or a call longer than `timeout_s` (0: no limit) is a frame
    without motion, counted by its reason in the run record's tracking. Registering a name
    again replaces its factory."""
    _driftlab.register_vo(name, factory, timeout_s)


def fields(kind="run"):
    """(key path, type, meaning) of every field of a record: 'run', 'evaluation' or 'sweep'."""
    return _driftlab.fields(kind)


from driftlab import sweep  # noqa: E402  (uses the names above)

__all__ = ["Error", "Record", "Scenario", "evaluate", "fields", "isnan", "read_run",
           "register_vo", "render", "run", "sweep", "__version__"]
