#!/usr/bin/env python3
"""A covariate study from Python: plan a small sweep, run it, merge it into pandas and plot a
run metric against a swept axis (mean and 95 % interval over the replicates, one series per
algorithm) with matplotlib.

    PYTHONPATH=build/python python3 examples/python/covariates.py --out out/yaw_py

The default is the river paper's yaw covariate (scenarios/sweeps/yaw_variability.yaml) on a
26 m survey stretch: 30 short jobs. Any sweep file, axis and run metric (a column of the merged
runs.csv) can be given instead; docs/python.md explains each step.
"""

import argparse
import os
import sys

import driftlab

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.normpath(os.path.join(HERE, "..", ".."))


def arguments():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sweep", default=os.path.join(SOURCE, "scenarios", "sweeps",
                                                   "yaw_variability.yaml"))
    p.add_argument("--set", action="append",
                   help="KEY.PATH=VALUE for every job (repeatable; default, for the default "
                        "sweep: mission.survey_length_m=26)")
    p.add_argument("--axis", default="weave_amplitude_deg", help="the swept column to plot on x")
    p.add_argument("--metric", default="p_m_per_m_mean", help="the run metric to plot on y")
    p.add_argument("--out", required=True, help="the sweep folder")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    return p.parse_args()


def main():
    a = arguments()
    if a.set is None:
        a.set = ["mission.survey_length_m=26"] if "yaw_variability" in a.sweep else []
    print(driftlab.sweep.plan(a.sweep, a.out, set=a.set))
    print(driftlab.sweep.run(a.out, jobs=a.jobs))
    runs = driftlab.sweep.merge(a.out)
    points = driftlab.sweep.table(a.out, "points")
    if a.axis not in points.columns or a.metric + "_mean" not in points.columns:
        sys.exit(f"--axis {a.axis} / --metric {a.metric}: expected a column of "
                 f"{points.attrs['folder']}/points.csv")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(6, 4))
    for algorithm, rows in points.groupby("algorithm"):
        rows = rows.sort_values(a.axis)
        mean = rows[a.metric + "_mean"]
        ax.errorbar(rows[a.axis], mean,
                    yerr=[mean - rows[a.metric + "_ci95_low"], rows[a.metric + "_ci95_high"] - mean],
                    marker="o", capsize=3, label=algorithm)
    ax.set_xlabel(a.axis)
    ax.set_ylabel(a.metric)
    ax.set_title(runs.attrs["summary"].sweep.name)
    ax.legend()
    figure = os.path.join(a.out, "summary", f"{a.axis}__{a.metric}_python.png")
    fig.savefig(figure, dpi=120, bbox_inches="tight")
    print(points[["algorithm", a.axis, "runs", a.metric + "_mean"]].to_string(index=False))
    print(f"wrote {figure}")


if __name__ == "__main__":
    main()
