#!/usr/bin/env python3
"""Issue #15: a `perf record --call-graph dwarf` profile of `ovton run` folded into pipeline stages.

Usage: perf script -i perf.data | scripts/experiments/perf_stages.py
Each sample goes to the first stage (in the order below) whose function is on its call stack. Samples whose stack
could not be unwound to an ovton function (OpenCV and Eigen frames without unwind information, large Eigen stack
blocks) are attributed by the library or function they were taken in, and marked with *.
"""
import collections
import re
import sys

STAGES = [
    ("t_d search (its own decode + KLT of the first 8 s)", ["search_td"]),
    ("PNG decode", ["load_image", "load_gray_image"]),
    ("KLT optical flow", ["calcOpticalFlowPyrLK"]),
    ("pyramid", ["buildOpticalFlowPyramid"]),
    ("histogram equalisation", ["equalizeHist"]),
    ("detection + merge (FAST, masks)", ["merge_and_detect"]),
    ("RANSAC, undistortion, rest of tracking", ["TrackKLT::track"]),
    ("SLAM update + initialisation", ["slam_update", "UpdaterSLAM"]),
    ("MSCKF update", ["UpdaterMSCKF::update", "msckf_update"]),
    ("propagation + cloning", ["Propagator", "state_helper::clone", "propagate"]),
    ("marginalisation, rest of the filter", ["VioManager"]),
]
BY_LIBRARY = [("libpng", "PNG decode *"), ("libz.", "PNG decode *"), ("libdeflate", "PNG decode *"),
              ("opencv_video", "KLT optical flow *"), ("opencv_features2d", "detection + merge (FAST, masks) *"),
              ("opencv_imgproc", "pyramid, equalisation, masks *")]
OTHER = "other (start-up, CSV reading, evaluation, libc, kernel)"


def classify(stack):
    text = "\n".join(stack)
    for name, keys in STAGES:
        if any(k in text for k in keys):
            return name
    leaf = stack[0] if stack else ""
    if "Eigen::internal" in leaf:
        return "filter: Eigen matrix products, caller not unwound *"
    m = re.search(r"\((\S+)\)$", leaf)
    dso = m.group(1).split("/")[-1] if m else ""
    for key, name in BY_LIBRARY:
        if key in dso:
            return name
    return OTHER


def main():
    count = collections.Counter()
    stack = []
    for line in list(sys.stdin) + [""]:
        if not line.strip():
            if stack:
                count[classify(stack)] += 1
            stack = []
        elif line[0] in " \t":
            stack.append(line.strip())
        else:
            stack = []
    total = sum(count.values())
    print("| stage | share of CPU |")
    print("|---|---:|")
    for name, n in count.most_common():
        print(f"| {name} | {100.0 * n / total:.1f} % |")
    print(f"\n{total} samples")


if __name__ == "__main__":
    main()
