#!/usr/bin/env python3
"""The river paper's yaw covariate h (Eq. (13)) swept on the twin's survey, against the paper.

    PYTHONPATH=build/python /usr/bin/python3 examples/sweeps/yaw_variability.py --out out/yaw

Plans and runs examples/sweeps/yaw_variability.yaml (the survey flown with a heading weave of
0-30 deg, two periods, two replicates, with the paper's method alone, `sparse`), merges it,
evaluates every run's `sparse` a second time with the truth at the paper's prism (the total
station's target, no lever-arm correction: `driftlab eval --reference-point`), and sets the
pooled 6.5 m sections against the river paper's three statements on h:

- Sec. 4: the half of the sections with the lower h has a mean e'_p of 0.032 m/m, the half with
  the higher h 0.100 m/m (sparse);
- Table 3: Eq. (13)'s coefficient of h is 2.33e-3 m/m a degree (t 9.53) for sparse;
- Table 4: h spans 0.33-75.08 deg, median 10.45 deg.

Writes OUT/yaw_variability.md (the comparison), OUT/yaw_variability.csv (every section, both
truths) and OUT/yaw_variability.png (e'_p against h, the paper's halves and slope drawn in).
Finished jobs and evaluations are read back, not rerun.
"""

import argparse
import os
import subprocess
import sys

import numpy
import yaml

import driftlab
from driftlab import _paths

HERE = os.path.dirname(os.path.abspath(__file__))
SOURCE = os.path.normpath(os.path.join(HERE, "..", ".."))

# River paper (Kriechbaumer et al. 2015), sparse VO: Sec. 4's halves, Table 3's Eq. (13), Table 4.
PAPER_HALVES = (0.032, 0.100)          # mean e'_p [m/m] below / above the median h
PAPER_H = {"min": 0.33, "median": 10.45, "mean": 17.42, "max": 75.08}   # h [deg], Table 4
PAPER_MEAN_P = 0.067                   # mean e'_p [m/m], Table 1
PAPER_BETA_H = (2.33e-3, 9.53)         # beta of h [m/m per deg], its t (Table 3)
COVARIATES = ("v", "h", "f", "d")      # Eq. (13)
PRISM = "-0.35,-0.672,0.467"           # `driftlab paper`'s prism for the survey's camera mount


def arguments():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--sweep", default=os.path.join(HERE, "yaw_variability.yaml"))
    p.add_argument("--set", action="append", default=[],
                   help="KEY.PATH=VALUE for every job (repeatable)")
    p.add_argument("--prism", default=PRISM,
                   help="where the paper's truth was measured, X,Y,Z from the camera in its "
                        "optical frame [m] (default: %(default)s)")
    p.add_argument("--out", required=True, help="the sweep folder")
    p.add_argument("--jobs", type=int, default=os.cpu_count() or 1)
    return p.parse_args()


def prism_sections(folder, job, prism):
    """The job's `sparse` sections with the truth at the prism (evaluated once, then read)."""
    import pandas

    run = os.path.join(folder, "runs", job)
    out = os.path.join(folder, "prism", job)
    if not os.path.exists(os.path.join(out, "sections.csv")):
        with open(os.path.join(run, "scenario.resolved.yaml")) as f:
            e = yaml.safe_load(f)["eval"]
        command = [_paths.cli(), "eval", "--gt", os.path.join(run, "groundtruth.tum"),
                   "--est", os.path.join(run, "estimates", "sparse.tum"),
                   "--covariates", os.path.join(run, "frames.csv"), "--vo", "sparse",
                   "--align", e["align"], "--section-length", str(e["section_length_m"]),
                   "--reference-point", prism, "--name", "sparse", "--out", out, "--force"]
        done = subprocess.run(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                              text=True)
        if done.returncode != 0:   # driftlab eval names the flag and value; it writes nothing
            raise driftlab.Error(f"{run}: driftlab eval at the prism: {done.stderr.strip()}")
    return pandas.read_csv(os.path.join(out, "sections.csv"), float_precision="round_trip")


def ols(sections):
    """Eq. (13) by ordinary least squares: {name: (beta, se, t)} and R^2."""
    x = numpy.column_stack([numpy.ones(len(sections))] +
                           [sections[c].to_numpy(float) for c in COVARIATES])
    y = sections["p_m_per_m"].to_numpy(float)
    beta, _, _, _ = numpy.linalg.lstsq(x, y, rcond=None)
    residual = y - x @ beta
    dof = len(y) - x.shape[1]
    sigma2 = residual @ residual / dof
    se = numpy.sqrt(numpy.diag(sigma2 * numpy.linalg.inv(x.T @ x)))
    r2 = 1.0 - residual @ residual / numpy.sum((y - y.mean()) ** 2)
    names = ("Intercept",) + COVARIATES
    return {n: (b, s, b / s) for n, b, s in zip(names, beta, se)}, r2


def halves(sections):
    """Mean e'_p of the sections below and above the median h, and that median."""
    median = sections["h"].median()
    low = sections.loc[sections["h"] <= median, "p_m_per_m"].mean()
    high = sections.loc[sections["h"] > median, "p_m_per_m"].mean()
    return low, high, median


def report(pools):
    """The markdown comparison of each truth's pool with the paper."""
    lines = ["| | sections | h median / max [deg] | mean e'_p, lower / higher half of h [m/m] "
             "| Eq. (13) beta of h [m/m/deg] (t) | R^2 |", "|---|---|---|---|---|---|",
             f"| paper, sparse | 96 | {PAPER_H['median']:.2f} / {PAPER_H['max']:.2f} "
             f"| {PAPER_HALVES[0]:.3f} / {PAPER_HALVES[1]:.3f} "
             f"| {PAPER_BETA_H[0]:.2e} ({PAPER_BETA_H[1]:.2f}) | 0.56 |"]
    for name, sections in pools.items():
        low, high, median = halves(sections)
        fit, r2 = ols(sections)
        beta, _, t = fit["h"]
        lines.append(f"| twin, sparse, {name} | {len(sections)} | {median:.2f} / "
                     f"{sections['h'].max():.2f} | {low:.3f} / {high:.3f} | {beta:.2e} ({t:.2f}) "
                     f"| {r2:.2f} |")
    return "\n".join(lines) + "\n"


def plot(pools, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    for (name, sections), colour in zip(pools.items(), ("tab:blue", "tab:orange")):
        ax.scatter(sections["h"], sections["p_m_per_m"], s=8, alpha=0.35, color=colour,
                   label=f"twin sections, truth at the {name}")
        low, high, median = halves(sections)
        ax.plot([sections["h"].min(), median], [low, low], color=colour, lw=2.5)
        ax.plot([median, sections["h"].max()], [high, high], color=colour, lw=2.5)
    ax.plot([PAPER_H["min"], PAPER_H["median"]], [PAPER_HALVES[0]] * 2, "k-", lw=2.5,
            label="paper: mean of each half of h (Sec. 4)")
    ax.plot([PAPER_H["median"], PAPER_H["max"]], [PAPER_HALVES[1]] * 2, "k-", lw=2.5)
    h = numpy.array([PAPER_H["min"], PAPER_H["max"]])
    ax.plot(h, PAPER_MEAN_P + PAPER_BETA_H[0] * (h - PAPER_H["mean"]), "k--",
            label="paper: Eq. (13)'s slope of h through its means (Tables 1, 3, 4)")
    ax.set_xlabel("h: SD of the platform's yaw over a 6.5 m section [deg]")
    ax.set_ylabel("e'_p: sparse VO position error over displacement [m/m]")
    ax.set_ylim(0, max(0.3, max(s["p_m_per_m"].quantile(0.98) for s in pools.values())))
    ax.legend(fontsize=8, loc="upper left")
    fig.savefig(path, dpi=110, bbox_inches="tight")


def main():
    a = arguments()
    try:
        study(a)
    except driftlab.Error as e:   # a bad sweep, key or prism: the message, no traceback
        sys.exit(f"yaw_variability.py: {e}")


def study(a):
    print(driftlab.sweep.plan(a.sweep, a.out, set=a.set, force=True))
    print(driftlab.sweep.run(a.out, jobs=a.jobs))
    driftlab.sweep.merge(a.out)
    sections = driftlab.sweep.table(a.out, "sections")
    exact = sections[sections["algorithm"] == "sparse"]
    if exact.empty:
        raise driftlab.Error(f"{a.out}: no run has a `sparse` estimate (pipeline.vo); the "
                             "paper's h is the sparse VO's covariate")
    prism = [prism_sections(a.out, job, a.prism).assign(job=job) for job in exact["job"].unique()]
    import pandas
    pools = {"camera": exact.dropna(subset=["p_m_per_m", *COVARIATES]),
             "prism": pandas.concat(prism).dropna(subset=["p_m_per_m", *COVARIATES])}
    table = report(pools)
    with open(os.path.join(a.out, "yaw_variability.md"), "w") as f:
        f.write(table)
    pandas.concat([p.assign(truth=n) for n, p in pools.items()]).to_csv(
        os.path.join(a.out, "yaw_variability.csv"), index=False)
    plot(pools, os.path.join(a.out, "yaw_variability.png"))
    print(table)
    print(f"wrote {a.out}/yaw_variability.md, .csv and .png")


if __name__ == "__main__":
    sys.exit(main())
