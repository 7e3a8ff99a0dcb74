"""VOs written in Python, run by the pipeline beside the C++ VOs (driftlab.register_vo)."""

import time

import cv2
import numpy
import pytest

import driftlab
from conftest import TINY


def tum_poses(path):
    """t_ns -> 4x4 pose of a TUM file."""
    poses = {}
    for row in numpy.loadtxt(path):
        T = numpy.eye(4)
        x, y, z, w = row[4:8]
        T[:3, :3] = [[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]]
        T[:3, 3] = row[1:4]
        poses[round(row[0] * 1e9)] = T
    return poses


class Replay:
    """Gives back the poses of an earlier run's VO."""

    poses = {}

    def __init__(self, rig):
        self.rig = rig

    def process(self, t, left, right):
        assert left.shape == right.shape == (self.rig.height, self.rig.width)
        assert left.dtype == numpy.uint8
        return self.poses.get(round(t * 1e9))


def test_a_python_vo_replaying_the_sparse_vo_is_evaluated_as_the_sparse_vo(tiny_run, tmp_path):
    earlier, _ = tiny_run
    Replay.poses = tum_poses(earlier / "estimates" / "sparse.tum")
    driftlab.register_vo("replay", Replay)
    scenario = driftlab.Scenario.load(TINY, set={"pipeline.vo": ["sparse", "replay"],
                                                 "pipeline.fusion": []})
    record = driftlab.run(scenario, tmp_path / "replay")
    sparse = record.algorithms["sparse"]
    replay = record.algorithms["replay"]
    # The same poses, the motions between them accumulated again: equal to rounding.
    for a, b in [(sparse.ape.trans_m.rmse, replay.ape.trans_m.rmse),
                 (sparse.ape.rot_deg.rmse, replay.ape.rot_deg.rmse),
                 (sparse.rpe.trans_m.rmse, replay.rpe.trans_m.rmse),
                 (sparse.sections.p_m_per_m.mean, replay.sections.p_m_per_m.mean)]:
        assert b == pytest.approx(a, rel=1e-9, abs=1e-12)
    assert sparse.sections.count == replay.sections.count > 0
    # The other VOs' results do not depend on it.
    assert sparse.ape.trans_m.rmse == tiny_run[1].algorithms["sparse"].ape.trans_m.rmse


class Cv2Vo:
    """A small stereo VO with OpenCV: corners tracked by Lucas-Kanade into the right image (depth
    from disparity) and into the next left image, and the motion by PnP with RANSAC."""

    def __init__(self, rig):
        self.K = numpy.array([[rig.fx, 0, rig.cx], [0, rig.fy, rig.cy], [0, 0, 1]])
        self.fx_b = rig.fx * rig.baseline_m
        self.pose = numpy.eye(4)
        self.previous = None  # (left image, its corners, their 3D points)

    def stereo(self, left, right):
        corners = cv2.goodFeaturesToTrack(left, 400, 0.01, 5)
        if corners is None:
            return None
        moved, ok, _ = cv2.calcOpticalFlowPyrLK(left, right, corners, None)
        d = corners[:, 0, 0] - moved[:, 0, 0]
        keep = (ok[:, 0] == 1) & (d > 0.5) & (abs(corners[:, 0, 1] - moved[:, 0, 1]) < 1)
        c = corners[keep]
        z = self.fx_b / d[keep]
        x = (c[:, 0, 0] - self.K[0, 2]) * z / self.K[0, 0]
        y = (c[:, 0, 1] - self.K[1, 2]) * z / self.K[1, 1]
        return c, numpy.stack([x, y, z], axis=1)

    def process(self, t, left, right):
        current = self.stereo(left, right)
        if self.previous is not None and current is not None:
            image, corners, points = self.previous
            tracked, ok, _ = cv2.calcOpticalFlowPyrLK(image, left, corners, None)
            good = ok[:, 0] == 1
            if good.sum() >= 6:
                found, rvec, tvec, inliers = cv2.solvePnPRansac(
                    points[good], tracked[good], self.K, None, reprojectionError=1.0)
                if found and inliers is not None and len(inliers) >= 6:
                    T_curr_prev = numpy.eye(4)
                    T_curr_prev[:3, :3] = cv2.Rodrigues(rvec)[0]
                    T_curr_prev[:3, 3] = tvec[:, 0]
                    self.pose = self.pose @ numpy.linalg.inv(T_curr_prev)
        if current is not None:
            self.previous = (left, current[0], current[1])
        return self.pose


def test_a_small_opencv_vo_runs_beside_the_cpp_vos_and_beats_standing_still(tiny_run, tmp_path):
    driftlab.register_vo("cv2_lk_pnp", Cv2Vo)
    scenario = driftlab.Scenario.load(TINY, set={"pipeline.vo": ["sparse", "cv2_lk_pnp"],
                                                 "pipeline.fusion": [], "pipeline.max_frames": 60})
    record = driftlab.run(scenario, tmp_path / "cv2")
    mine = record.algorithms["cv2_lk_pnp"]
    assert mine.tracking.lost_frames == 0
    # A VO that never moves, evaluated as the run evaluates (unaligned): how far the truth went.
    gt = numpy.loadtxt(tmp_path / "cv2" / "groundtruth.tum")
    still = gt.copy()
    still[:, 1:] = gt[0, 1:]
    standing = driftlab.evaluate(gt, still, options={"section_length_m": 0.01, "align": "none"})
    assert mine.ape.trans_m.rmse < standing.ape.trans_m.rmse / 3


class Failing:
    """Fails in one of the ways a Python VO can, from its third frame on."""

    how = {}

    def __init__(self, rig):
        self.frames = 0

    def process(self, t, left, right):
        self.frames += 1
        pose = numpy.eye(4)
        if self.frames < 3:
            return pose
        kind = self.how[type(self).__name__]
        if kind == "raise":
            raise RuntimeError("my VO broke")
        if kind == "nan":
            pose[0, 3] = float("nan")
        if kind == "shape":
            return pose[:3]
        if kind == "hang":
            end = time.monotonic() + 30
            while time.monotonic() < end:  # Python code: the timeout stops it
                pass
        return pose


def test_a_failing_python_vo_is_reported_and_the_others_are_kept(tiny_run, tmp_path):
    kinds = {"raise": "python: RuntimeError: my VO broke",
             "nan": "python: process() returned a pose that is not finite",
             "shape": "python: process() returned",
             "hang": "python: process() ran past 0.2 s"}
    names = []
    for kind in kinds:
        cls = type(f"fail_{kind}", (Failing,), {})
        Failing.how[cls.__name__] = kind
        driftlab.register_vo(cls.__name__, cls, timeout_s=0.2)
        names.append(cls.__name__)
    scenario = driftlab.Scenario.load(TINY, set={"pipeline.vo": ["sparse"] + names,
                                                 "pipeline.fusion": []})
    started = time.monotonic()
    record = driftlab.run(scenario, tmp_path / "failing")
    assert time.monotonic() - started < 25  # the hanging VO was stopped
    for kind, reason in kinds.items():
        tracking = record.algorithms[f"fail_{kind}"].tracking
        assert tracking.lost_frames == tracking.frames - 1, kind  # all but its second frame
        assert any(r.startswith(reason) for r in tracking.reasons), (kind, tracking.reasons)
    assert record.algorithms["sparse"].ape.trans_m.rmse == \
        tiny_run[1].algorithms["sparse"].ape.trans_m.rmse
    with pytest.raises(driftlab.Error, match="sparse"):
        driftlab.register_vo("sparse", Failing)  # a built-in's name
