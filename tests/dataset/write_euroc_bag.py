#!/usr/bin/python3
"""Writes a bag laid out as EuRoC's published ones, with python3-rosbag (ROS's own Python
writer), and the same images as an EuRoC folder (PGM files), for tests/dataset/rosbag_test:
/cam0/image_raw and /cam1/image_raw (mono8, recorded 3 ms after their stamps), /imu0, the
Vicon room's /vicon/firefly_sbx/firefly_sbx (TransformStamped) and the machine hall's
/leica/position (PointStamped). Usage: write_euroc_bag.py OUT_DIR"""
import math
import os
import sys

import rosbag
import rospy
from geometry_msgs.msg import PointStamped, TransformStamped
from sensor_msgs.msg import Image, Imu

W, H = 96, 72
STAMPS = [1403715273262142976 + k * 50000000 for k in range(4)]


def pixels(cam, k):
    return bytes((x * 7 + y * 3 + 31 * k + 90 * cam + (x * y) % 13) % 256
                 for y in range(H) for x in range(W))


def stamp(t_ns):
    return rospy.Time(t_ns // 1000000000, t_ns % 1000000000)


def main():
    out = sys.argv[1]
    bag = rosbag.Bag(os.path.join(out, "euroc_like.bag"), "w")
    for cam in range(2):
        folder = os.path.join(out, "mav0", "cam%d" % cam)
        os.makedirs(os.path.join(folder, "data"))
        with open(os.path.join(folder, "data.csv"), "w") as index:
            index.write("#timestamp [ns],filename\n")
            for k, t in enumerate(STAMPS):
                data = pixels(cam, k)
                with open(os.path.join(folder, "data", "%d.pgm" % t), "wb") as f:
                    f.write(b"P5\n%d %d\n255\n" % (W, H) + data)
                index.write("%d,%d.pgm\n" % (t, t))
                m = Image(height=H, width=W, encoding="mono8", is_bigendian=0, step=W, data=data)
                m.header.stamp = stamp(t)
                m.header.frame_id = "cam%d" % cam
                bag.write("/cam%d/image_raw" % cam, m, stamp(t + 3000000))
    for k in range(40):
        t = STAMPS[0] - 20000000 + k * 5000000
        m = Imu()
        m.header.stamp = stamp(t)
        m.angular_velocity.x, m.angular_velocity.y, m.angular_velocity.z = 0.01 * k, -0.02, 0.5
        m.linear_acceleration.x, m.linear_acceleration.z = 0.1, 9.81 + 0.001 * k
        bag.write("/imu0", m, stamp(t))
        v = TransformStamped()
        v.header.stamp = stamp(t)
        v.transform.translation.x, v.transform.translation.y = 0.01 * k, 1.0
        v.transform.translation.z = 0.8
        yaw = 0.002 * k
        v.transform.rotation.w, v.transform.rotation.z = math.cos(yaw / 2), math.sin(yaw / 2)
        bag.write("/vicon/firefly_sbx/firefly_sbx", v, stamp(t))
        p = PointStamped()
        p.header.stamp = stamp(t)
        p.point.x = 0.01 * k
        bag.write("/leica/position", p, stamp(t))
    bag.close()


if __name__ == "__main__":
    main()
