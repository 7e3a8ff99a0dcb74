"""What the peers' stand-ins share (tests/data/peers/<system>/): each stand-in takes the place of
one system's program, checks the files driftlab's export hands it as that system reads them,
and writes its trajectory file in that system's own format, from the run's true left-camera
poses (the run's groundtruth.tum, three folders above the export), so that driftlab's reading
of it can be checked against the truth. The formats, from the systems' sources:
  OpenVINS ov_msckf/src/ros/ROSVisualizerHelper.cpp (sim_save_total_state_to_file);
  VINS-Fusion vins_estimator/src/utility/visualization.cpp (pubOdometry, vio.csv);
  Basalt src/vio.cpp (saveTrajectoryButton, --save-trajectory euroc)."""
import os
import sys

import cv2
import numpy as np


def fail(message):
    print("stand-in: " + message, file=sys.stderr)
    sys.exit(3)


def need(path):
    if not os.path.exists(path):
        fail(path + ": not found")
    return path


def truth_poses(export_root):
    """The run's true left-camera poses: [(t_ns, T_W_C 4x4)]."""
    path = need(os.path.join(export_root, "..", "..", "..", "groundtruth.tum"))
    poses = []
    for line in open(path):
        if line.startswith("#") or not line.strip():
            continue
        t, x, y, z, qx, qy, qz, qw = (float(v) for v in line.split())
        T = np.eye(4)
        T[:3, :3] = rotation(qw, qx, qy, qz)
        T[:3, 3] = (x, y, z)
        poses.append((round(t * 1e9), T))
    return poses


def rotation(w, x, y, z):
    n = np.sqrt(w * w + x * x + y * y + z * z)
    w, x, y, z = w / n, x / n, y / n, z / n
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])


def quaternion(R):
    """Hamilton (w, x, y, z) of a rotation matrix, w >= 0."""
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    return w, x, y, z


def opencv_matrix(node):
    """An OpenCV FileStorage node as a numpy array, failing with its name when it is empty."""
    m = node.mat()
    if m is None:
        fail("a matrix missing in an OpenCV YAML file")
    return m


def body_poses(cameras, T_C_B):
    """The body (IMU) poses T_W_B = T_W_C T_C_B in a world frame of the system's own: the
    truth turned by a rotation and moved, as a system's gravity-aligned world would be."""
    W = np.eye(4)
    W[:3, :3] = rotation(0.9, 0.1, -0.3, 0.2)
    W[:3, 3] = (5, -2, 1)
    return [(t, W @ T_W_C @ T_C_B) for t, T_W_C in cameras]
