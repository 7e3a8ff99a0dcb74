#!/usr/bin/env python3
"""An ablation from Python: every scenario of a spec run with none of its mechanisms, with each
mechanism alone, and with all of them together, then one table of the spec's metrics.

    PYTHONPATH=build/python /usr/bin/python3 examples/ablation/ablation.py \\
        examples/ablation/basin.yaml --out out/ablation_basin

A spec (examples/ablation/*.yaml) names the scenarios, the keys every run sets, the baseline
(each mechanism's keys at "off"), the mechanisms (each a set of keys at its cited magnitude)
and the metrics (paths into the run record, metrics.json's keys). Runs go to OUT/SCENARIO/VARIANT;
a run whose resolved scenario is the one asked for is read back, not run again. The table goes
to OUT/ablation.md and its numbers, one per line, to OUT/ablation.csv.
"""

import argparse
import csv
import math
import os
import sys
import time

import yaml

import driftlab

NONE, ALL = "none", "all"


def load_spec(path):
    """The spec, checked: every mechanism sets keys the baseline turns off, no key twice, and
    every metric is a number of the run record."""
    try:
        with open(path) as f:
            spec = yaml.safe_load(f)
    except (OSError, yaml.YAMLError) as e:
        raise SystemExit(f"{path}: {e}")
    if not isinstance(spec, dict):
        raise SystemExit(f"{path}: expected a mapping of scenarios, baseline, mechanisms, metrics")
    for field in ("scenarios", "baseline", "mechanisms", "metrics"):
        if not spec.get(field):
            raise SystemExit(f"{path}: field '{field}': missing or empty; expected a mapping "
                             "(see examples/ablation/ablation.py)")
    for name, entry in spec["scenarios"].items():
        if not isinstance(entry, dict) or not entry.get("path"):
            raise SystemExit(f"{path}: scenarios.{name}: got {entry!r}; expected "
                             "{path: SCENARIO.yaml, set: {...}}")
    seen = {}
    for name, mechanism in spec["mechanisms"].items():
        if name in (NONE, ALL):
            raise SystemExit(f"{path}: mechanisms.{name}: the names '{NONE}' and '{ALL}' are the "
                             "ablation's own rows")
        for key in mechanism.get("set") or {}:
            if key not in spec["baseline"]:
                raise SystemExit(f"{path}: mechanisms.{name}.set.{key}: not in baseline; every "
                                 "mechanism's key needs its 'off' value there")
            if key in seen:
                raise SystemExit(f"{path}: mechanisms.{name}.set.{key}: also set by mechanism "
                                 f"'{seen[key]}'; 'all' could not hold both")
            seen[key] = name
    check_metrics(path, spec["metrics"])
    return spec


def check_metrics(path, metrics):
    """Each metric's path is a number of metrics.json (the metrics reference; NAME matches any
    algorithm's or track's name)."""
    numbers = [f.split(".") for f, kind, _ in driftlab.fields("run")
               if kind.startswith("number") or kind.startswith("integer")]
    for i, metric in enumerate(metrics):
        parts = str(metric.get("path", "")).split(".")
        if not any(len(f) == len(parts) and all(a in ("NAME", b) for a, b in zip(f, parts))
                   for f in numbers):
            raise SystemExit(f"{path}: metrics[{i}].path: got '{metric.get('path')}'; expected "
                             "the path of a number in metrics.json (docs/metrics-reference.md)")


def variants(spec):
    """(name, keys) for none, each mechanism alone, and all together, in that order."""
    base = dict(spec["baseline"])
    rows = [(NONE, base)]
    together = dict(base)
    for name, mechanism in spec["mechanisms"].items():
        rows.append((name, {**base, **mechanism["set"]}))
        together.update(mechanism["set"])
    rows.append((ALL, together))
    return rows


def run_one(path, keys, out):
    """The run record of one scenario with these keys, running it only if out holds another."""
    scenario = driftlab.Scenario.load(path, set=keys)
    resolved = os.path.join(out, "scenario.resolved.yaml")
    if os.path.exists(resolved) and os.path.exists(os.path.join(out, "metrics.json")):
        with open(resolved) as f:
            if f.read() == scenario.to_yaml():
                return driftlab.read_run(out), 0.0
    start = time.monotonic()
    record = driftlab.run(scenario, out, replace=True)
    return record, time.monotonic() - start


def value(record, path, scale):
    """The number at a dotted path of the record (dict keys and attributes), times scale."""
    node = record
    for part in path.split("."):
        node = node.get(part) if isinstance(node, dict) else getattr(node, part, None)
        if node is None:
            return math.nan
    return float(node) * scale


def cell(x):
    """A number as the table gives it; a metric the run has not, as a dash."""
    return "—" if math.isnan(x) else f"{x:.2f}" if abs(x) >= 0.1 else f"{x:.3f}"


def table(spec, results):
    """Markdown: a row per variant (and the paper's, if given), a column per scenario."""
    names = list(spec["scenarios"])
    labels = " / ".join(m["label"] for m in spec["metrics"])
    lines = [f"| variant ({labels}) | " + " | ".join(names) + " |",
             "|---|" + "---|" * len(names)]
    if spec.get("paper"):
        cells = [" / ".join(cell(v) for v in spec["paper"].get(n, [])) or "—" for n in names]
        lines.append("| paper | " + " | ".join(cells) + " |")
    for variant in [v for v, _ in variants(spec)]:
        cells = [" / ".join(cell(x) for x in results[(n, variant)]) for n in names]
        lines.append(f"| {variant} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("spec", help="an ablation spec (examples/ablation/*.yaml)")
    p.add_argument("--out", required=True, help="the ablation's folder")
    p.add_argument("--only", action="append", help="run only this scenario (repeatable)")
    a = p.parse_args()
    spec = load_spec(a.spec)
    try:
        run_all(a, spec)
    except driftlab.Error as e:
        raise SystemExit(str(e))


def run_all(a, spec):
    """Every run of the spec (or of --only's scenarios), then the table and the CSV."""
    for name in a.only or []:
        if name not in spec["scenarios"]:
            raise SystemExit(f"{a.spec}: --only {name}: no such scenario; expected one of "
                             + ", ".join(spec["scenarios"]))
    here = os.path.dirname(os.path.abspath(a.spec))
    results, rows = {}, []
    for name, entry in spec["scenarios"].items():
        if a.only and name not in a.only:
            continue
        path = os.path.normpath(os.path.join(here, entry["path"]))
        for variant, keys in variants(spec):
            keys = {**(spec.get("set") or {}), **(entry.get("set") or {}), **keys}
            record, seconds = run_one(path, keys, os.path.join(a.out, name, variant))
            results[(name, variant)] = [value(record, m["path"], m.get("scale", 1.0))
                                        for m in spec["metrics"]]
            print(f"{name} {variant}: " + ", ".join(f"{x:.3f}" for x in results[(name, variant)])
                  + (f"  ({seconds:.0f} s)" if seconds else "  (read back)"), flush=True)
            rows += [(name, variant, m["label"], x)
                     for m, x in zip(spec["metrics"], results[(name, variant)])]
    if a.only:
        spec["scenarios"] = {n: e for n, e in spec["scenarios"].items() if n in a.only}
    with open(os.path.join(a.out, "ablation.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["scenario", "variant", "metric", "value"])
        w.writerows(rows)
    with open(os.path.join(a.out, "ablation.md"), "w") as f:
        f.write(table(spec, results))
    sys.stdout.write(table(spec, results))


if __name__ == "__main__":
    main()
