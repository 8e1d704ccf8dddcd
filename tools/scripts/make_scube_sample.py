#!/usr/bin/env python3
"""Writes datasets/scube_sample: a tiny folder in the SCube layout (datasets/README.md).

Stdlib only, deterministic. The content is synthetic (a slow pure-yaw turn, stationary translation, RTK-style
position-only ground truth, images of a fixed random texture shifted with the yaw); it exists to exercise the
SCube reader and the CLI on every machine, not to test accuracy.
"""
import math
import os
import random
import struct
import sys
import zlib

W, H = 320, 256
RATE_CAM, RATE_IMU = 20, 200
DURATION_S = 1.0
T0_NS = 1700000000000000000


def png_gray(path, rows):
    raw = b"".join(b"\x00" + bytes(r) for r in rows)

    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)

    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", W, H, 8, 0, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))


def main(out):
    rng = random.Random(7)
    tex_w = W + 200
    blocks = [[rng.randrange(256) for _ in range(tex_w // 8 + 1)] for _ in range(H // 8 + 1)]
    os.makedirs(os.path.join(out, "cam0", "data"), exist_ok=True)
    os.makedirs(os.path.join(out, "imu0"), exist_ok=True)
    os.makedirs(os.path.join(out, "groundtruth"), exist_ok=True)
    yaw_rate = 0.2  # rad/s
    fx = 400.0
    with open(os.path.join(out, "cam0", "data.csv"), "w") as f:
        f.write("#timestamp [ns],filename\n")
        for k in range(int(DURATION_S * RATE_CAM)):
            t = T0_NS + k * 1000000000 // RATE_CAM
            shift = int(round(fx * yaw_rate * k / RATE_CAM))
            rows = [[blocks[y // 8][(x + shift) // 8] for x in range(W)] for y in range(H)]
            png_gray(os.path.join(out, "cam0", "data", f"{t}.png"), rows)
            f.write(f"{t},{t}.png\n")
    with open(os.path.join(out, "imu0", "data.csv"), "w") as f:
        f.write("#timestamp [ns],w_x [rad s^-1],w_y [rad s^-1],w_z [rad s^-1],a_x [m s^-2],a_y [m s^-2],a_z [m s^-2]\n")
        for i in range(int(DURATION_S * RATE_IMU) + 1):
            t = T0_NS + i * 1000000000 // RATE_IMU
            f.write(f"{t},{rng.gauss(0, 1e-3):.9f},{rng.gauss(0, 1e-3):.9f},{yaw_rate + rng.gauss(0, 1e-3):.9f},"
                    f"{rng.gauss(0, 1e-2):.9f},{rng.gauss(0, 1e-2):.9f},{9.81 + rng.gauss(0, 1e-2):.9f}\n")
    with open(os.path.join(out, "groundtruth", "data.csv"), "w") as f:
        f.write("#timestamp_ns,px,py,pz\n")
        for i in range(int(DURATION_S * 10) + 1):  # RTK at 10 Hz, position only
            f.write(f"{T0_NS + i * 100000000},0.0,0.0,0.0\n")
    with open(os.path.join(out, "camchain-imucam.yaml"), "w") as f:
        f.write("""cam0:
  camera_model: pinhole
  intrinsics: [400.0, 400.0, 160.0, 128.0]
  distortion_model: radtan
  distortion_coeffs: [-0.1, 0.01, 0.0, 0.0]
  resolution: [320, 256]
  rate_hz: 20
  # Kalibr convention: T_cam_imu maps IMU-frame points into the camera frame (camera looks along IMU x).
  T_cam_imu:
  - [0.0, -1.0, 0.0, 0.0]
  - [0.0, 0.0, -1.0, 0.0]
  - [1.0, 0.0, 0.0, -0.05]
  - [0.0, 0.0, 0.0, 1.0]
  timeshift_cam_imu: 0.003
""")
    with open(os.path.join(out, "imu.yaml"), "w") as f:
        f.write("""imu0:
  model: calibrated
  update_rate: 200.0
  gyroscope_noise_density: 1.0e-3
  gyroscope_random_walk: 1.0e-5
  accelerometer_noise_density: 1.0e-2
  accelerometer_random_walk: 1.0e-4
""")


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else os.path.join(os.path.dirname(__file__), "..", "..", "datasets", "scube_sample"))
