"""Sweeps from Python, as `driftlab sweep plan | run | merge` do them: plan a sweep file into a
folder, run its jobs (each a `driftlab run` child process), and merge them into pandas."""

import os

from driftlab import _driftlab, _paths


def plan(sweep_file, out, set=None, force=False):
    """Plans the sweep file into the folder `out` (sweep.json, scenario.yaml, manifest.jsonl);
    `set` overrides keys of every job ({key.path: value}). Returns a line saying what was
    written."""
    return _driftlab.plan_sweep(str(sweep_file), str(out), set, force)


def run(folder, jobs=1, force=False, job_timeout_s=0, driftlab=None):
    """Runs every job of the folder that is not done, `jobs` at once, each as
    `driftlab run --manifest ...` (the `driftlab` program: the argument, else $DRIFTLAB, else the
    build's or the installation's). Raises driftlab.Error naming the jobs that failed."""
    brief, failed = _driftlab.run_sweep(str(folder), jobs, driftlab or _paths.cli(), force,
                                        job_timeout_s)
    if failed:
        raise _driftlab.Error(f"{folder}: {brief}; failed: {', '.join(failed)} "
                              f"(see {os.path.join(str(folder), 'failed')})")
    return brief


def merge(folder, regress=(), plots=False, allow_missing=False):
    """Merges the sweep folder into FOLDER/summary and returns runs.csv as a pandas DataFrame:
    one row per run and algorithm, with the job, its seed, each axis and every run metric.

    The frame's attrs hold the rest: attrs["summary"], the typed record of
    summary/metrics.json (pooled sections, regressions, paired comparisons), and
    attrs["folder"], the summary folder (points.csv, sections.csv, summary.md; see
    `table`). `regress` takes `sweep merge --regress` specs
    (METRIC~AXIS[+AXIS...][@AXIS=VALUE,...])."""
    summary = _driftlab.merge_sweep(str(folder), list(regress), plots, allow_missing)
    frame = table(folder, "runs")
    frame.attrs["summary"] = summary
    return frame


def table(folder, name):
    """A merged sweep's table as a DataFrame: 'runs', 'points' or 'sections'."""
    import pandas

    if name not in ("runs", "points", "sections"):
        raise ValueError(f"table '{name}': expected 'runs', 'points' or 'sections'")
    frame = pandas.read_csv(os.path.join(str(folder), "summary", name + ".csv"),
                            float_precision="round_trip")
    frame.attrs["folder"] = os.path.join(str(folder), "summary")
    return frame
