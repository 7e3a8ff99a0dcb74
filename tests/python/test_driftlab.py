"""`import driftlab`: each result checked against the driftlab command's own files, read by
Python's json and csv modules, or against a closed form. ctest runs this suite
(tests/CMakeLists.txt) with PYTHONPATH at BUILD/python and DRIFTLAB at the CLI."""

import csv
import json
import math
import os
import subprocess
import sys

import numpy
import pytest

import driftlab
from conftest import CLI, SOURCE, TINY, TINY_GRID


def same(a, b):
    """Equal, NaN equal to NaN, through dicts and lists."""
    if isinstance(a, dict) and isinstance(b, dict):
        return a.keys() == b.keys() and all(same(a[k], b[k]) for k in a)
    if isinstance(a, list) and isinstance(b, list):
        return len(a) == len(b) and all(same(x, y) for x, y in zip(a, b))
    if isinstance(a, float) and isinstance(b, float) and math.isnan(a) and math.isnan(b):
        return True
    return a == b


def test_a_scenario_loads_with_its_overrides_as_the_cli_resolves_it():
    scenario = driftlab.Scenario.load(TINY, set={"seed": 42, "pipeline.max_frames": 4})
    assert scenario.name == "tiny_base"
    assert scenario.seed == 42
    cli = subprocess.run([CLI, "scenario", "check", TINY, "--set", "seed=42", "--set",
                          "pipeline.max_frames=4"], check=True, capture_output=True, text=True)
    assert scenario.to_yaml() == cli.stdout
    assert driftlab.Scenario.load(TINY, set=["seed=42", "pipeline.max_frames=4"]).to_yaml() == \
        scenario.to_yaml()


def test_a_bad_scenario_raises_driftlab_error_naming_file_key_and_value(tmp_path):
    with pytest.raises(driftlab.Error) as e:
        driftlab.Scenario.load(TINY, set={"sensors.camera.rate_hz": -3})
    assert "sensors.camera.rate_hz" in str(e.value) and "-3" in str(e.value)
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: x\nmission:\n  speed_mps: fast\n")
    with pytest.raises(driftlab.Error) as e:
        driftlab.Scenario.load(bad)
    assert str(bad) + ":3" in str(e.value) and "mission.speed_mps" in str(e.value)
    assert isinstance(e.value, ValueError)
    with pytest.raises(driftlab.Error, match="no_such.yaml"):
        driftlab.Scenario.load(tmp_path / "no_such.yaml")


def test_run_returns_the_record_that_metrics_json_holds(tiny_run):
    out, record = tiny_run
    written = json.loads((out / "metrics.json").read_text())
    assert record.seed == written["seed"] == 7
    assert record.frames == written["frames"]
    sparse = record.algorithms["sparse"]
    assert sparse.ape.trans_m.rmse == written["algorithms"]["sparse"]["ape"]["trans_m"]["rmse"]
    assert sparse.sections.count == written["algorithms"]["sparse"]["sections"]["count"]
    assert record.algorithms["sparse_kf"].tracking.frames == \
        written["algorithms"]["sparse_kf"]["tracking"]["frames"]
    # Read back from the folder, the record is the same; timing aside, so is the file's JSON.
    assert same(driftlab.read_run(out).to_dict(), record.to_dict())
    # Every key the file has is a field of the record, with the same value (null is NaN).
    def check(in_file, in_record, at):
        if isinstance(in_file, dict):
            for k, v in in_file.items():
                check(v, in_record[k], at + "." + k)
        elif isinstance(in_file, list):
            assert len(in_file) == len(in_record), at
            for i, (v, r) in enumerate(zip(in_file, in_record)):
                check(v, r, f"{at}[{i}]")
        elif in_file is None:
            assert in_record is None or math.isnan(in_record), at
        else:
            assert in_file == in_record, at
    check(written, record.to_dict(), "")


def test_evaluate_gives_the_cli_numbers_for_files_and_for_arrays(tiny_run, tmp_path):
    out, _ = tiny_run
    gt, est = out / "groundtruth.tum", out / "estimates" / "sparse.tum"
    subprocess.run([CLI, "eval", "--gt", str(gt), "--est", str(est), "--section-length", "0.01",
                    "--out", str(tmp_path / "eval")], check=True, capture_output=True)
    cli = json.loads((tmp_path / "eval" / "metrics.json").read_text())
    from_files = driftlab.evaluate(gt, est, options={"section_length_m": 0.01}, name="sparse")
    assert from_files.ape.trans_m.rmse == cli["ape"]["trans_m"]["rmse"]
    assert from_files.rpe.trans_m.rmse == cli["rpe"]["trans_m"]["rmse"]
    assert from_files.sections.count == cli["sections"]["count"]
    # The same poses as arrays: TUM's columns, read by numpy.
    from_arrays = driftlab.evaluate(numpy.loadtxt(gt), numpy.loadtxt(est),
                                    options={"section_length_m": 0.01}, name="sparse")
    assert from_arrays.ape.trans_m.rmse == pytest.approx(from_files.ape.trans_m.rmse, rel=1e-9)
    with pytest.raises(driftlab.Error, match="N x 8"):
        driftlab.evaluate(numpy.zeros((3, 7)), est)
    with pytest.raises(driftlab.Error, match="section_length_m"):
        driftlab.evaluate(gt, est, options={"section_length_m": -1})


def test_an_estimate_equal_to_the_truth_has_no_error(tiny_run):
    out, _ = tiny_run
    gt = numpy.loadtxt(out / "groundtruth.tum")
    e = driftlab.evaluate(gt, gt, options={"section_length_m": 0.01})
    assert e.ape.trans_m.rmse == pytest.approx(0, abs=1e-12)
    assert e.association.pairs == len(gt)


def test_a_sweep_planned_and_run_from_python_is_the_clis(tmp_path):
    folder, cli_folder = tmp_path / "sweep", tmp_path / "cli"
    driftlab.sweep.plan(TINY_GRID, folder)
    subprocess.run([CLI, "sweep", "plan", TINY_GRID, "--out", str(cli_folder)], check=True,
                   capture_output=True)
    assert (folder / "manifest.jsonl").read_text() == (cli_folder / "manifest.jsonl").read_text()
    assert "4 jobs" in driftlab.sweep.run(folder, jobs=2)
    frame = driftlab.sweep.merge(folder, regress=["ape_trans_rmse_m~yaw_amp_deg"])
    with open(folder / "summary" / "runs.csv") as f:
        rows = list(csv.DictReader(f))
    assert len(frame) == len(rows) == 4 * 2  # 4 jobs x (sparse, its smoother sparse_ca)
    assert list(frame.columns) == list(rows[0].keys())
    assert frame["ape_trans_rmse_m"].tolist() == [float(r["ape_trans_rmse_m"]) for r in rows]
    summary = frame.attrs["summary"]
    written = json.loads((folder / "summary" / "metrics.json").read_text())
    assert summary.sweep.jobs == written["sweep"]["jobs"] == 4
    fit = summary.algorithms["sparse"].run_regressions["ape_trans_rmse_m~yaw_amp_deg"]
    assert fit.n == 4
    assert fit.coefficients["yaw_amp_deg"].estimate == written["algorithms"]["sparse"][
        "run_regressions"]["ape_trans_rmse_m~yaw_amp_deg"]["coefficients"]["yaw_amp_deg"][
        "estimate"]
    assert len(driftlab.sweep.table(folder, "points")) == 2 * 2  # 2 points x 2 algorithms
    with pytest.raises(driftlab.Error, match="no_such_axis"):
        driftlab.sweep.plan(TINY_GRID, tmp_path / "bad", set={"no_such_axis.x": 1})


def test_fields_are_the_metrics_reference(tmp_path):
    reference = open(os.path.join(SOURCE, "docs", "metrics-reference.md")).read()
    for kind in ("run", "evaluation", "sweep"):
        rows = driftlab.fields(kind)
        assert rows, kind
    for key, kind, doc in driftlab.fields("run"):
        assert f"| `{key}` |" in reference, key
    with pytest.raises(driftlab.Error, match="expected 'run'"):
        driftlab.fields("nope")


def test_the_covariates_example_plots_the_points_table(tmp_path):
    example = os.path.join(SOURCE, "examples", "python", "covariates.py")
    out = tmp_path / "example"
    done = subprocess.run([sys.executable, example, "--sweep", TINY_GRID, "--axis", "yaw_amp_deg",
                           "--metric", "ape_trans_rmse_m", "--out", str(out), "--jobs", "2"],
                          check=True, capture_output=True, text=True)
    figure = out / "summary" / "yaw_amp_deg__ape_trans_rmse_m_python.png"
    assert figure.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    with open(out / "summary" / "points.csv") as f:
        means = [float(r["ape_trans_rmse_m_mean"]) for r in csv.DictReader(f)]
    assert len(means) == 4
    for m in means:  # the printed table carries each point's mean
        assert f"{m:.6f}"[:6] in done.stdout


def test_render_gives_the_pngs_of_driftlab_render_byte_for_byte(tmp_path):
    import cv2

    subprocess.run([CLI, "render", TINY, "--frames", "5", "--depth", "--out",
                    str(tmp_path / "pngs")], check=True, capture_output=True)
    frames = list(driftlab.render(driftlab.Scenario.load(TINY), frames=5, depth=True))
    assert [f.k for f in frames] == list(range(5))
    with open(tmp_path / "pngs" / "times.csv") as f:
        stamps = [int(r["t_ns"]) for r in csv.DictReader(f)]
    assert [f.t_ns for f in frames] == stamps
    for f in frames:
        for side in ("left", "right"):
            png = cv2.imread(str(tmp_path / "pngs" / side / f"{f.k:06d}.png"), cv2.IMREAD_UNCHANGED)
            image = getattr(f, side)
            assert image.dtype == numpy.uint8 and image.shape == png.shape
            assert image.tobytes() == png.tobytes()
        pfm = cv2.imread(str(tmp_path / "pngs" / "depth" / f"{f.k:06d}.pfm"), cv2.IMREAD_UNCHANGED)
        assert f.depth.dtype == numpy.float32 and f.depth.tobytes() == pfm.tobytes()


def ablate(spec, out, check=False):
    """examples/ablation/ablation.py on a spec, as a user runs it."""
    example = os.path.join(SOURCE, "examples", "ablation", "ablation.py")
    return subprocess.run([sys.executable, example, str(spec), "--out", str(out)], check=check,
                          capture_output=True, text=True)


def ablation_spec(tmp_path, mechanisms):
    spec = {
        "scenarios": {"tiny": {"path": TINY, "set": {"pipeline.max_frames": 6}}},
        "set": {"pipeline.fusion": []},
        "baseline": {"sensors.camera.mount.rpy_deg": [0, 0, 0], "scene.river_reach.buildings": 1},
        "mechanisms": mechanisms,
        "metrics": [{"label": "APE [cm]", "path": "algorithms.sparse.ape.trans_m.rmse",
                     "scale": 100},
                    {"label": "frames", "path": "frames"},
                    {"label": "dense APE [m]", "path": "algorithms.dense.ape.trans_m.rmse"}],
    }
    path = tmp_path / "spec.yaml"
    path.write_text(json.dumps(spec))  # JSON is YAML
    return path


def test_the_ablation_example_runs_none_each_mechanism_and_all(tmp_path):
    spec = ablation_spec(tmp_path, {
        "tilt": {"set": {"sensors.camera.mount.rpy_deg": [0, -10, 0]}},
        "town": {"set": {"scene.river_reach.buildings": 3}}})
    out = tmp_path / "out"
    done = ablate(spec, out, check=True)
    expected = {"none": ([0, 0, 0], 1), "tilt": ([0, -10, 0], 1), "town": ([0, 0, 0], 3),
                "all": ([0, -10, 0], 3)}
    table = (out / "ablation.md").read_text()
    for variant, (rpy, buildings) in expected.items():
        run = out / "tiny" / variant
        resolved = driftlab.Scenario.load(run / "scenario.resolved.yaml")
        assert resolved.to_yaml() == (run / "scenario.resolved.yaml").read_text()
        written = json.loads((run / "metrics.json").read_text())
        assert written["frames"] == 6
        ape = written["algorithms"]["sparse"]["ape"]["trans_m"]["rmse"] * 100
        # the dense VO did not run: its cell is a dash
        assert f"| {variant} | {ape:.2f} / {6:.2f} / — |" in table or \
            f"| {variant} | {ape:.3f} / {6:.2f} / — |" in table
        text = (run / "scenario.resolved.yaml").read_text()
        assert f"rpy_deg: [{', '.join(str(v) for v in rpy)}]" in text
        assert f"buildings: {buildings}" in text
    with open(out / "ablation.csv") as f:
        assert len(list(csv.DictReader(f))) == 4 * 3
    # Run again: every run's resolved scenario is the one asked for, so each is read back.
    stamps = {v: (out / "tiny" / v / "metrics.json").stat().st_mtime_ns for v in expected}
    again = ablate(spec, out, check=True)
    assert again.stdout.count("(read back)") == 4
    assert stamps == {v: (out / "tiny" / v / "metrics.json").stat().st_mtime_ns for v in expected}
    assert (out / "ablation.md").read_text() == table
    assert done.stdout.endswith(table)


def test_the_ablation_example_refuses_a_mechanism_without_an_off_value(tmp_path):
    spec = ablation_spec(tmp_path, {"wind": {"set": {"water.wind.speed_mps": 4}}})
    done = ablate(spec, tmp_path / "out")
    assert done.returncode != 0
    assert "mechanisms.wind.set.water.wind.speed_mps: not in baseline" in done.stderr
    assert not (tmp_path / "out").exists()


def test_the_ablation_example_refuses_a_metric_that_is_not_a_number_of_the_record(tmp_path):
    spec = ablation_spec(tmp_path, {"tilt": {"set": {"sensors.camera.mount.rpy_deg": [0, -5, 0]}}})
    text = json.loads(spec.read_text())
    text["metrics"][0]["path"] = "algorithms.sparse.ape.trans_m.rsme"
    spec.write_text(json.dumps(text))
    done = ablate(spec, tmp_path / "out")
    assert done.returncode != 0
    assert "metrics[0].path: got 'algorithms.sparse.ape.trans_m.rsme'" in done.stderr
    assert not (tmp_path / "out").exists()


def test_the_ablation_example_reports_a_bad_scenario_key_as_the_cli_does(tmp_path):
    spec = ablation_spec(tmp_path, {"fast": {"set": {"sensors.camera.mount.rpy_deg": [0, 999, 0]}}})
    done = ablate(spec, tmp_path / "out")
    assert done.returncode != 0
    assert "sensors.camera.mount.rpy_deg" in done.stderr and "999" in done.stderr
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "out" / "tiny" / "fast").exists()


def test_the_yaw_example_sets_both_truths_against_the_paper(tmp_path):
    """examples/sweeps/yaw_variability.py on the tiny grid: the camera's pool is the merged
    sections, the prism's pool is `driftlab eval --reference-point` of each run, its Eq. (13) fit
    is the C++ regression's where both see the same sections, and the table carries each pool's
    halves."""
    import importlib.util
    path = os.path.join(SOURCE, "examples", "sweeps", "yaw_variability.py")
    spec = importlib.util.spec_from_file_location("yaw_variability", path)
    yaw = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(yaw)
    out = tmp_path / "yaw"
    done = subprocess.run([sys.executable, path, "--sweep", TINY_GRID, "--set",
                           "pipeline.max_frames=80", "--set", "eval.section_length_m=0.3", "--out",
                           str(out), "--jobs", "2"],
                          check=True, capture_output=True, text=True)
    for suffix in ("md", "csv"):
        assert (out / f"yaw_variability.{suffix}").stat().st_size > 0
    assert (out / "yaw_variability.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    import pandas
    pooled = pandas.read_csv(out / "yaw_variability.csv")
    merged = driftlab.sweep.table(out, "sections")
    camera = pooled[pooled["truth"] == "camera"]
    assert len(camera) == len(merged[merged["algorithm"] == "sparse"].dropna(
        subset=["p_m_per_m", *yaw.COVARIATES]))
    jobs = sorted(os.listdir(out / "prism"))
    assert jobs == sorted(merged["job"].unique())
    # A lever arm moves the truth in the turns: the prism's errors are not the camera's.
    prism = pooled[pooled["truth"] == "prism"]
    assert len(prism) > 0 and not numpy.allclose(
        sorted(prism["p_m_per_m"]), sorted(camera["p_m_per_m"]))
    # The hand-written OLS against the C++ regression of one run's sections (its metrics.json).
    folder = out / "prism" / jobs[-1]   # a job of the 20 deg weave: h varies
    sections = pandas.read_csv(folder / "sections.csv")
    fit, r2 = yaw.ols(sections.dropna(subset=["p_m_per_m", *yaw.COVARIATES]))
    with open(folder / "metrics.json") as f:
        regression = json.load(f)["algorithms"]["sparse"]["regression"]
    assert r2 == pytest.approx(regression["r2"], rel=1e-9)
    for name, (beta, se, t) in fit.items():
        c = regression["coefficients"][name]
        assert beta == pytest.approx(c["estimate"], rel=1e-6, abs=1e-12)
        assert t == pytest.approx(c["t"], rel=1e-6)
    # The table: the paper's row, then each pool's halves as halves() gives them.
    for name, pool in (("camera", camera), ("prism", prism)):
        low, high, _ = yaw.halves(pool)
        assert f"| twin, sparse, {name} | {len(pool)} |" in done.stdout
        assert f"{low:.3f} / {high:.3f}" in done.stdout


def test_the_yaw_example_reports_bad_input_without_a_traceback_or_half_written_files(tmp_path):
    path = os.path.join(SOURCE, "examples", "sweeps", "yaw_variability.py")
    # A key the base scenario does not have: the sweep's own message, nothing planned.
    out = tmp_path / "badkey"
    done = subprocess.run([sys.executable, path, "--sweep", TINY_GRID, "--set",
                           "pipeline.max_frame=8", "--out", str(out)],
                          capture_output=True, text=True)
    assert done.returncode != 0
    assert "Traceback" not in done.stderr
    assert "pipeline.max_frame" in done.stderr
    assert not (out / "manifest.jsonl").exists()
    # A prism that is not X,Y,Z: driftlab eval's message naming the flag and the value; no
    # prism evaluation and no table written.
    out = tmp_path / "badprism"
    done = subprocess.run([sys.executable, path, "--sweep", TINY_GRID, "--set",
                           "pipeline.max_frames=8", "--prism", "0.5,0.5", "--out", str(out),
                           "--jobs", "2"], capture_output=True, text=True)
    assert done.returncode != 0
    assert "Traceback" not in done.stderr
    assert "--reference-point" in done.stderr and "0.5,0.5" in done.stderr
    assert not (out / "prism").exists()
    assert not (out / "yaw_variability.md").exists()
