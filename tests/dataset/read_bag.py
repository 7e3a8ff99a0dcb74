#!/usr/bin/python3
"""Reads a ROS 1 bag with python3-rosbag (ROS's own Python reader, independent of the C++
rosbag_storage that driftlab writes with) and prints, as JSON, what tests/dataset/rosbag_test
checks: each topic's type, count and latching, and every message in time order with its record
time, header and fields. NaN becomes null (JSON has no NaN)."""
import json
import math
import sys

import rosbag


def num(x):
    return None if isinstance(x, float) and math.isnan(x) else x


def vec(v):
    return [num(v.x), num(v.y), num(v.z)]


def quat(q):
    return [q.w, q.x, q.y, q.z]


def fields(msg_type, m):
    if msg_type == "sensor_msgs/Image":
        return {"width": m.width, "height": m.height, "encoding": m.encoding, "step": m.step,
                "is_bigendian": m.is_bigendian, "data": list(bytearray(m.data))}
    if msg_type == "sensor_msgs/CameraInfo":
        return {"width": m.width, "height": m.height, "distortion_model": m.distortion_model,
                "D": list(m.D), "K": list(m.K), "R": list(m.R), "P": list(m.P)}
    if msg_type == "sensor_msgs/Imu":
        return {"w": vec(m.angular_velocity), "a": vec(m.linear_acceleration),
                "w_cov": list(m.angular_velocity_covariance),
                "a_cov": list(m.linear_acceleration_covariance),
                "q_cov0": m.orientation_covariance[0]}
    if msg_type == "sensor_msgs/NavSatFix":
        return {"status": m.status.status, "service": m.status.service,
                "lla": [num(m.latitude), num(m.longitude), num(m.altitude)],
                "cov": [num(c) for c in m.position_covariance],
                "cov_type": m.position_covariance_type}
    if msg_type == "sensor_msgs/MagneticField":
        return {"field": vec(m.magnetic_field)}
    if msg_type == "geometry_msgs/QuaternionStamped":
        return {"q": quat(m.quaternion)}
    if msg_type == "geometry_msgs/PoseStamped":
        return {"p": vec(m.pose.position), "q": quat(m.pose.orientation)}
    if msg_type == "tf2_msgs/TFMessage":
        return {"transforms": [{"parent": t.header.frame_id, "child": t.child_frame_id,
                                "stamp_ns": t.header.stamp.to_nsec(),
                                "t": vec(t.transform.translation),
                                "q": quat(t.transform.rotation)} for t in m.transforms]}
    return {}


def main():
    bag = rosbag.Bag(sys.argv[1])
    out = {"version": bag.version, "topics": {}, "messages": []}
    for topic, info in bag.get_type_and_topic_info().topics.items():
        out["topics"][topic] = {"type": info.msg_type, "count": info.message_count,
                                "latching": "0"}
    for c in bag._get_connections():
        latching = c.header.get("latching", "0")
        out["topics"][c.topic]["latching"] = \
            latching.decode() if isinstance(latching, bytes) else latching
    for topic, msg, t in bag.read_messages():
        m = {"topic": topic, "record_ns": t.to_nsec()}
        if hasattr(msg, "header"):
            m.update({"stamp_ns": msg.header.stamp.to_nsec(), "frame_id": msg.header.frame_id,
                      "seq": msg.header.seq})
        m.update(fields(msg._type, msg))
        out["messages"].append(m)
    print(json.dumps(out))


if __name__ == "__main__":
    main()
