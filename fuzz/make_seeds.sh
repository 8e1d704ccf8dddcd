#!/usr/bin/env bash
# Writes the seeds of fuzz_mcap and fuzz_rosbag (fuzz/corpus/mcap, fuzz/corpus/rosbag): a tiny EuRoC folder (4 images
# of 16x12 px, the calibration fuzz/recording_fuzz_util.h gives, 0.15 s of IMU) exported by ovton in the forms the
# readers meet, each under the fuzzers' 16 kB input limit. Usage: fuzz/make_seeds.sh [OVTON_BINARY]
set -euo pipefail
cd "$(dirname "$0")/.."
OVTON=${1:-build/ovton}
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
python3 - "$tmp/f/mav0" <<'PY'
import os, struct, sys, zlib
root = sys.argv[1]
os.makedirs(f"{root}/cam0/data")
os.makedirs(f"{root}/imu0")
def png(path, seed):
    rows = b"".join(b"\x00" + bytes((x * 13 + y * 7 + seed * 31) % 256 for x in range(16)) for y in range(12))
    chunk = lambda t, d: struct.pack(">I", len(d)) + t + d + struct.pack(">I", zlib.crc32(t + d))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", 16, 12, 8, 0, 0, 0, 0))
                + chunk(b"IDAT", zlib.compress(rows)) + chunk(b"IEND", b""))
with open(f"{root}/cam0/data.csv", "w") as f:
    f.write("#timestamp [ns],filename\n")
    for i in range(4):
        t = 1050000000 + 50000000 * i
        f.write(f"{t},{t}.png\n")
        png(f"{root}/cam0/data/{t}.png", i)
with open(f"{root}/imu0/data.csv", "w") as f:
    f.write("#timestamp [ns],wx,wy,wz,ax,ay,az\n")
    for k in range(40):
        f.write(f"{1000000000 + 5000000 * k},0.01,0.02,0.03,0.1,0.2,9.81\n")
cam = open("fuzz/recording_fuzz_util.h").read()
for name, key in (("cam0", "cam0/sensor.yaml"), ("imu0", "imu0/sensor.yaml")):
    start = cam.index(f'"calib/mav0/{key}",') + len(f'"calib/mav0/{key}",')
    text = eval(cam[start:cam.index(");", start)].replace("\n", " "))
    with open(f"{root}/{key}", "w") as f:
        f.write(text)
PY
mkdir -p fuzz/corpus/mcap fuzz/corpus/rosbag
export_to() { "$OVTON" export -q --no-kalibr --dataset "$tmp/f" --out "$1" "${@:2}" >/dev/null; }
export_to "$tmp/zstd.mcap" && cp "$tmp/zstd.mcap" fuzz/corpus/mcap/zstd_raw
export_to "$tmp/lz4.mcap" --compression lz4 --image-format png && cp "$tmp/lz4.mcap" fuzz/corpus/mcap/lz4_png
export_to "$tmp/none.mcap" --compression none --chunk-kb 4 --no-summary && cp "$tmp/none.mcap" fuzz/corpus/mcap/none_cut
truncate -s -2000 fuzz/corpus/mcap/none_cut
export_to "$tmp/raw.bag" && cp "$tmp/raw.bag" fuzz/corpus/rosbag/raw
export_to "$tmp/lz4.bag" --compression lz4 --image-format png && cp "$tmp/lz4.bag" fuzz/corpus/rosbag/lz4_png
ls -l fuzz/corpus/mcap fuzz/corpus/rosbag
