#!/usr/bin/env python3
"""A rosbag2 SQLite bag (a folder with metadata.yaml and .db3 files) made from an EuRoC-layout folder by a writer that
is not ovton's: Python's standard library only (sqlite3, zlib, struct), ROS 2 CDR written here from the message
definitions. Rows are stamped with a receive time a little after the header stamp and inserted in receive order, as
`ros2 bag record` does.

  python3 write_db3.py --folder DIR --out BAG [--images raw|png|jpeg] [--jpeg-from DIR] [--split-images N]
                       [--max-images N]

raw: sensor_msgs/msg/Image mono8 on /cam0/image_raw (the PNGs decoded here); png: sensor_msgs/msg/CompressedImage with
the folder's own PNG bytes; jpeg: CompressedImage with the JPEG files of --jpeg-from (named like the PNGs, .jpg; made
by write_mcap.mjs --dump-jpeg), both on /cam0/image_raw/compressed. --split-images: a new .db3 file after every N
images (a split bag). --max-images: the first N images only (the IMU log whole).
"""
import argparse
import os
import sqlite3
import struct
import sys
import zlib


class Cdr:
    """ROS 2 CDR, little-endian (encapsulation CDR_LE): each primitive aligned to its size from the end of the
    4-byte encapsulation header."""

    def __init__(self):
        self.b = bytearray(b"\x00\x01\x00\x00")

    def align(self, n):
        while (len(self.b) - 4) % n:
            self.b.append(0)

    def put(self, fmt, v):
        n = struct.calcsize(fmt)
        self.align(n)
        self.b += struct.pack("<" + fmt, v)

    def string(self, s):
        data = s.encode() + b"\x00"
        self.put("I", len(data))
        self.b += data

    def header(self, t_ns, frame):
        self.put("i", t_ns // 1000000000)
        self.put("I", t_ns % 1000000000)
        self.string(frame)

    def doubles(self, values):
        for v in values:
            self.put("d", v)

    def uint8_seq(self, data):
        self.put("I", len(data))
        self.b += data


def png_gray8(path):
    """The pixels of an 8-bit grayscale, non-interlaced PNG, and its size."""
    with open(path, "rb") as f:
        data = f.read()
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        sys.exit(f"write_db3: {path}: not a PNG")
    pos, idat = 8, bytearray()
    width = height = 0
    while pos + 8 <= len(data):
        length, kind = struct.unpack(">I4s", data[pos : pos + 8])
        body = data[pos + 8 : pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, colour, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or colour != 0 or interlace != 0:
                sys.exit(f"write_db3: {path}: not an 8-bit gray non-interlaced PNG")
        elif kind == b"IDAT":
            idat += body
        elif kind == b"IEND":
            break
        pos += 12 + length
    raw = zlib.decompress(bytes(idat))
    out = bytearray(width * height)
    prev = bytearray(width)
    for y in range(height):
        kind = raw[y * (width + 1)]
        row = bytearray(raw[y * (width + 1) + 1 : (y + 1) * (width + 1)])
        if kind == 1:  # Sub
            for x in range(1, width):
                row[x] = (row[x] + row[x - 1]) & 255
        elif kind == 2:  # Up
            row = bytearray((a + b) & 255 for a, b in zip(row, prev))
        elif kind == 3:  # Average
            row[0] = (row[0] + prev[0] // 2) & 255
            for x in range(1, width):
                row[x] = (row[x] + (row[x - 1] + prev[x]) // 2) & 255
        elif kind == 4:  # Paeth
            row[0] = (row[0] + prev[0]) & 255
            for x in range(1, width):
                a, b, c = row[x - 1], prev[x], prev[x - 1]
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                row[x] = (row[x] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        elif kind != 0:
            sys.exit(f"write_db3: {path}: unknown PNG filter {kind}")
        out[y * width : (y + 1) * width] = row
        prev = row
    return width, height, bytes(out)


def rows(path):
    with open(path, newline="") as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith("#"):
                yield [s.strip() for s in line.split(",")]


SCHEMA_SQL = """
CREATE TABLE schema(schema_version INTEGER PRIMARY KEY,ros_distro TEXT NOT NULL);
INSERT INTO schema VALUES(3,'humble');
CREATE TABLE metadata(id INTEGER PRIMARY KEY,metadata_version INTEGER NOT NULL,metadata TEXT NOT NULL);
CREATE TABLE topics(id INTEGER PRIMARY KEY,name TEXT NOT NULL,type TEXT NOT NULL,serialization_format TEXT NOT NULL,
                    offered_qos_profiles TEXT NOT NULL);
CREATE TABLE messages(id INTEGER PRIMARY KEY,topic_id INTEGER NOT NULL,timestamp INTEGER NOT NULL,data BLOB NOT NULL);
CREATE INDEX timestamp_idx ON messages (timestamp ASC);
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--folder", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--images", choices=["raw", "png", "jpeg"], default="raw")
    ap.add_argument("--jpeg-from")
    ap.add_argument("--split-images", type=int, default=0)
    ap.add_argument("--max-images", type=int, default=0)
    a = ap.parse_args()
    if a.images == "jpeg" and not a.jpeg_from:
        sys.exit("write_db3: --images jpeg needs --jpeg-from DIR")
    mav0 = os.path.join(a.folder, "mav0") if os.path.isdir(os.path.join(a.folder, "mav0")) else a.folder
    images = [(int(t), os.path.join(mav0, "cam0", "data", name)) for t, name in rows(os.path.join(mav0, "cam0", "data.csv"))]
    if a.max_images:
        images = images[: a.max_images]
    imu = [(int(r[0]), [float(v) for v in r[1:7]]) for r in rows(os.path.join(mav0, "imu0", "data.csv"))]
    # Receive times: IMU readings 1 ms after their stamp, images 25 ms after.
    events = sorted([(t + 1000000, 0, i) for i, (t, _) in enumerate(imu)] + [(t + 25000000, 1, i) for i, (t, _) in enumerate(images)])

    os.makedirs(a.out, exist_ok=False)
    name = os.path.basename(os.path.normpath(a.out))
    cam_topic = "/cam0/image_raw" if a.images == "raw" else "/cam0/image_raw/compressed"
    cam_type = "sensor_msgs/msg/Image" if a.images == "raw" else "sensor_msgs/msg/CompressedImage"
    topics = [(1, cam_topic, cam_type), (2, "/imu0", "sensor_msgs/msg/Imu")]
    files, counts, db, in_file = [], {1: 0, 2: 0}, None, 0

    def open_db():
        path = os.path.join(a.out, f"{name}_{len(files)}.db3")
        files.append(os.path.basename(path))
        conn = sqlite3.connect(path)
        conn.executescript(SCHEMA_SQL)
        for tid, topic, kind in topics:
            conn.execute("INSERT INTO topics VALUES(?,?,?,?,?)", (tid, topic, kind, "cdr", ""))
        return conn

    db = open_db()
    for receive_ns, kind, i in events:
        c = Cdr()
        if kind == 0:
            t, (wx, wy, wz, ax, ay, az) = imu[i]
            c.header(t, "imu0")
            c.doubles([0.0, 0.0, 0.0, 1.0] + [-1.0] + [0.0] * 8)
            c.doubles([wx, wy, wz] + [0.0] * 9 + [ax, ay, az] + [0.0] * 9)
            topic = 2
        else:
            t, path = images[i]
            if a.split_images and in_file == a.split_images:
                db.commit()
                db.close()
                db, in_file = open_db(), 0
            in_file += 1
            c.header(t, "cam0")
            if a.images == "raw":
                width, height, pixels = png_gray8(path)
                c.put("I", height)
                c.put("I", width)
                c.string("mono8")
                c.put("B", 0)
                c.put("I", width)
                c.uint8_seq(pixels)
            else:
                src = path if a.images == "png" else os.path.join(a.jpeg_from, os.path.basename(path)[:-4] + ".jpg")
                with open(src, "rb") as f:
                    c.string(a.images)
                    c.uint8_seq(f.read())
            topic = 1
        db.execute("INSERT INTO messages(topic_id,timestamp,data) VALUES(?,?,?)", (topic, receive_ns, bytes(c.b)))
        counts[topic] += 1
    db.commit()
    db.close()

    with open(os.path.join(a.out, "metadata.yaml"), "w") as m:
        m.write("rosbag2_bagfile_information:\n  version: 5\n  storage_identifier: sqlite3\n  relative_file_paths:\n")
        for f in files:
            m.write(f"    - {f}\n")
        m.write(f"  duration:\n    nanoseconds: {events[-1][0] - events[0][0]}\n")
        m.write(f"  starting_time:\n    nanoseconds_since_epoch: {events[0][0]}\n")
        m.write(f"  message_count: {len(events)}\n  topics_with_message_count:\n")
        for tid, topic, kind in topics:
            m.write(f"    - topic_metadata:\n        name: {topic}\n        type: {kind}\n")
            m.write(f"        serialization_format: cdr\n        offered_qos_profiles: \"\"\n")
            m.write(f"      message_count: {counts[tid]}\n")
        m.write("  compression_format: \"\"\n  compression_mode: \"\"\n")
    print(f'{{"out": "{a.out}", "files": {len(files)}, "images": {counts[1]}, "imu": {counts[2]}}}')


if __name__ == "__main__":
    main()
