#!/usr/bin/python3
"""Reads a ROS 2 bag in rosbag2's sqlite3 storage with a decoder of its own: Python's sqlite3
for the database, PyYAML for metadata.yaml, and the CDR decoding below, written from the
specifications (OMG DDS-XTypes 1.3, 7.4.3 "XCDR version 1": the 4-byte encapsulation header
00 01 00 00 for little endian, primitives aligned to their size counted from after that header,
strings as uint32 length including the NUL, then the bytes and the NUL; sequences as uint32
count then elements; fixed arrays without a count) and ROS 2's message definitions. Prints the
same JSON as read_bag.py, for tests/dataset/rosbag_test. NaN becomes null."""
import json
import math
import os
import sqlite3
import struct
import sys

import yaml


class Cdr:
    def __init__(self, data):
        if data[:4] != b"\x00\x01\x00\x00":
            raise ValueError("encapsulation %r, expected CDR little endian" % data[:4])
        self.data, self.at = data, 4

    def _take(self, fmt, size):
        self.at += (-(self.at - 4)) % size  # align, counted from after the header
        (v,) = struct.unpack_from("<" + fmt, self.data, self.at)
        self.at += size
        return v

    def u8(self): return self._take("B", 1)
    def i8(self): return self._take("b", 1)
    def u16(self): return self._take("H", 2)
    def i32(self): return self._take("i", 4)
    def u32(self): return self._take("I", 4)
    def f64(self): return self._take("d", 8)

    def string(self):
        n = self.u32()
        s = self.data[self.at:self.at + n]
        if n == 0 or s[-1:] != b"\x00":
            raise ValueError("a string without its NUL")
        self.at += n
        return s[:-1].decode()

    def f64s(self, n): return [self.f64() for _ in range(n)]
    def vec(self): return [num(x) for x in self.f64s(3)]

    def quat(self):
        x, y, z, w = self.f64s(4)
        return [w, x, y, z]

    def header(self):
        sec, nanosec = self.i32(), self.u32()
        return {"stamp_ns": sec * 10**9 + nanosec, "frame_id": self.string()}

    def done(self):
        if len(self.data) - self.at > 3:  # at most the padding to a multiple of 4
            raise ValueError("%d bytes left over" % (len(self.data) - self.at))


def num(x):
    return None if isinstance(x, float) and math.isnan(x) else x


def decode(msg_type, data):
    c = Cdr(data)
    if msg_type == "tf2_msgs/msg/TFMessage":
        transforms = []
        for _ in range(c.u32()):
            h = c.header()
            transforms.append({"parent": h["frame_id"], "stamp_ns": h["stamp_ns"],
                               "child": c.string(), "t": c.vec(), "q": c.quat()})
        c.done()
        return {"transforms": transforms}
    m = c.header()
    if msg_type == "sensor_msgs/msg/Image":
        m.update(height=c.u32(), width=c.u32(), encoding=c.string(), is_bigendian=c.u8(),
                 step=c.u32())
        n = c.u32()
        m["data"] = list(c.data[c.at:c.at + n])
        c.at += n
    elif msg_type == "sensor_msgs/msg/CameraInfo":
        m.update(height=c.u32(), width=c.u32(), distortion_model=c.string())
        m["D"] = c.f64s(c.u32())
        m.update(K=c.f64s(9), R=c.f64s(9), P=c.f64s(12), binning=[c.u32(), c.u32()],
                 roi=[c.u32(), c.u32(), c.u32(), c.u32(), c.u8()])
    elif msg_type == "sensor_msgs/msg/Imu":
        q = c.quat()
        m.update(q_cov0=c.f64s(9)[0], w=c.vec(), w_cov=c.f64s(9), a=c.vec(), a_cov=c.f64s(9))
        m["orientation"] = q
    elif msg_type == "sensor_msgs/msg/NavSatFix":
        m.update(status=c.i8(), service=c.u16())
        m["lla"] = [num(c.f64()), num(c.f64()), num(c.f64())]
        m.update(cov=[num(x) for x in c.f64s(9)], cov_type=c.u8())
    elif msg_type == "sensor_msgs/msg/MagneticField":
        m.update(field=c.vec(), field_cov=c.f64s(9))
    elif msg_type == "geometry_msgs/msg/QuaternionStamped":
        m["q"] = c.quat()
    elif msg_type == "geometry_msgs/msg/PoseStamped":
        m.update(p=c.vec(), q=c.quat())
    else:
        raise ValueError("no decoder for " + msg_type)
    c.done()
    return m


def main():
    folder = sys.argv[1]
    meta = yaml.safe_load(open(os.path.join(folder, "metadata.yaml")))["rosbag2_bagfile_information"]
    files = meta["relative_file_paths"]
    db = sqlite3.connect(os.path.join(folder, files[0]))
    topics = {}
    for tid, name, type_, fmt, qos in db.execute(
            "SELECT id, name, type, serialization_format, offered_qos_profiles FROM topics"):
        durability = yaml.safe_load(qos)[0]["durability"]
        topics[tid] = {"name": name, "type": type_, "format": fmt,
                       "latching": "1" if durability == 1 else "0", "count": 0}
    out = {"version": meta["version"], "storage": meta["storage_identifier"],
           "metadata_count": meta["message_count"], "topics": {}, "messages": [],
           "metadata_topics": {t["topic_metadata"]["name"]: t["message_count"]
                               for t in meta["topics_with_message_count"]}}
    for tid, stamp, data in db.execute(
            "SELECT topic_id, timestamp, data FROM messages ORDER BY timestamp, id"):
        t = topics[tid]
        t["count"] += 1
        m = {"topic": t["name"], "record_ns": stamp}
        m.update(decode(t["type"], bytes(data)))
        out["messages"].append(m)
    for t in topics.values():
        out["topics"][t["name"]] = {"type": t["type"], "count": t["count"],
                                    "latching": t["latching"], "format": t["format"]}
    print(json.dumps(out))


if __name__ == "__main__":
    main()
