#!/usr/bin/env python3
"""Scores scripts/experiments/calibrate_sweep.sh's cases: prints a markdown table (and one line per case to stderr).

Per case folder OUT/NAME: sim/sim.yaml (truth), cal/ (calibrate's yamls and calibration.txt with its sigma),
res_calib.csv (the filter's online calibration, last row), eval.json (APE).
Truth: R_true = Exp(planted) R_BC(declared cam.yaml), f_true = sim.yaml's true_intrinsics, t_d at the middle row
= td0 + readout/2. Rotation error = Log(R_est R_true^T) (body frame, as tests/test_calibrate.cpp; calibrate's
per-axis sigma is in the same frame). Bars: calibrate within 3 sigma on every quantity (each rotation axis on its
own sigma); after the filter: rotation <= 0.3 deg, focal <= 1 % (the worse of fx, fy), |t_d| <= 1 ms.
Usage: calibrate_sweep.py OUT
"""
import csv
import json
import math
import os
import re
import sys

import numpy as np


def so3_exp(r):
    th = np.linalg.norm(r)
    if th < 1e-12:
        return np.eye(3)
    k = r / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(th) * K + (1 - math.cos(th)) * K @ K


def so3_log(R):
    c = max(-1.0, min(1.0, (np.trace(R) - 1) / 2))
    th = math.acos(c)
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if th < 1e-9:
        return w / 2
    return th / (2 * math.sin(th)) * w


def yaml_block(text, key):
    """The number list after `key:` up to the closing bracket (flat or nested `data: [...]`)."""
    m = re.search(key + r"\s*:\s*\[([^\]]*)\]", text)
    return [float(x) for x in m.group(1).split(",")] if m else None


def yaml_scalar(text, key):
    m = re.search(r"^\s*" + key + r"\s*:\s*([-+0-9.eE]+)", text, re.M)
    return float(m.group(1)) if m else None


def T_BS_rot(path):
    text = open(path).read()
    d = yaml_block(text.split("T_BS", 1)[1], "data")
    return np.array(d).reshape(4, 4)[:3, :3]


def case(out, name, cam_yaml):
    d = os.path.join(out, name)
    sim = open(os.path.join(d, "sim", "sim.yaml")).read()
    cam = sim.split("\ncamera:", 1)[1]
    rot = np.array(yaml_block(cam, "extrinsic_rotation_error_rad"))
    f_true = yaml_block(cam, "true_intrinsics")[0]
    ro_true = yaml_scalar(cam, "rolling_shutter_readout_s")
    td0 = yaml_scalar(sim.split("\ntime_offset:", 1)[1], "td0_s")
    focal_err = yaml_scalar(cam, "focal_error")
    td_true = td0 + 0.5 * ro_true
    R_true = so3_exp(rot) @ T_BS_rot(cam_yaml)
    r = {"name": name, "rot_deg": np.degrees(rot), "focal_pct": 100 * focal_err, "td0_ms": 1e3 * td0,
         "ro_ms": 1e3 * ro_true, "f_true": f_true, "td_true_ms": 1e3 * td_true}

    # calibrate: estimates from its yamls (full precision), sigma from calibration.txt
    txt = open(os.path.join(d, "cal", "calibration.txt")).read()
    R_c = T_BS_rot(os.path.join(d, "cal", "mav0", "cam0", "sensor.yaml"))
    f_c = yaml_block(open(os.path.join(d, "cal", "mav0", "cam0", "sensor.yaml")).read(), "intrinsics")[0]
    cfg = open(os.path.join(d, "cal", "ovton_config.yaml")).read()
    td_c = yaml_scalar(cfg, "init_s")
    ro_c = yaml_scalar(cfg, "readout_s") or 0.0
    s_td = float(re.search(r"^t_d\s+\S+\s+±\s+([0-9.]+) ms", txt, re.M).group(1))
    s_f = float(re.search(r"^focal\s+\S+\s+±\s+([0-9.]+) px", txt, re.M).group(1))
    m = re.search(r"^readout\s+\S+\s+±\s+([0-9.]+) ms", txt, re.M)
    s_ro = float(m.group(1)) if m else float("nan")
    s_rot = np.array([float(x) for x in re.search(r"σ \(([^)]*)\) deg", txt).group(1).split(",")])
    e_rot = np.degrees(so3_log(R_c @ R_true.T))
    r["b_rot"] = np.linalg.norm(e_rot)
    r["b_rot_sig"] = max(abs(e_rot) / s_rot)
    r["b_f"] = 100 * (f_c / f_true - 1)
    r["b_f_sig"] = abs(f_c - f_true) / s_f
    r["b_td"] = 1e3 * td_c - r["td_true_ms"]
    r["b_td_sig"] = abs(r["b_td"]) / s_td
    r["b_ro"] = 1e3 * ro_c - r["ro_ms"]
    r["b_ro_sig"] = abs(r["b_ro"]) / s_ro
    r["b_pass"] = max(r["b_rot_sig"], r["b_f_sig"], r["b_td_sig"], r["b_ro_sig"]) <= 3

    # the filter's last online-calibration row
    rows = list(csv.DictReader(open(os.path.join(d, "res_calib.csv"))))
    r["run"] = open(os.path.join(d, "case.txt")).read()
    if not rows:
        r["after"] = None
        return r
    last = rows[-1]
    R_f = np.array([float(last["R_BC_%d%d" % (i, j)]) for i in range(3) for j in range(3)]).reshape(3, 3)
    r["a_rot"] = np.linalg.norm(np.degrees(so3_log(R_f @ R_true.T)))
    fx, fy = float(last["intr_0"]), float(last["intr_1"])
    r["a_fx"], r["a_fy"] = 100 * (fx / f_true - 1), 100 * (fy / f_true - 1)
    r["a_f"] = max(abs(r["a_fx"]), abs(r["a_fy"]))
    r["a_td"] = 1e3 * float(last["td_s"]) - r["td_true_ms"]
    r["a_ro"] = 1e3 * float(last["readout_s"]) - r["ro_ms"]
    r["a_pass_rot"], r["a_pass_f"], r["a_pass_td"] = r["a_rot"] <= 0.3, r["a_f"] <= 1.0, abs(r["a_td"]) <= 1.0
    r["after"] = True
    try:
        ev = json.load(open(os.path.join(d, "eval.json")))
        r["ape"] = ev.get("ape_rmse_m", ev.get("ape", {}).get("rmse") if isinstance(ev.get("ape"), dict) else None)
        if r["ape"] is None:
            r["ape_raw"] = ev
    except (OSError, ValueError):
        r["ape"] = None
    return r


def main():
    out = sys.argv[1]
    names = sorted((n for n in os.listdir(out) if os.path.isfile(os.path.join(out, n, "res_calib.csv"))),
                   key=lambda n: [int(t) if t.isdigit() else t for t in re.split(r"(\d+)", n)])
    cam_yaml = os.path.join(out, "cam.yaml")
    R = [case(out, n, cam_yaml) for n in names]
    yn = lambda b: "pass" if b else "**fail**"
    print("calibrate (before): error against the truth, in brackets |error|/σ (rotation: the largest axis)")
    print()
    print("| case | planted r [deg] | focal | t_d0 / t_r [ms] "
          "| rot [deg] | focal [%] | t_d [ms] | t_r [ms] | ≤ 3σ |")
    print("|---|---|---|---|---|---|---|---|---|")
    for r in R:
        rv = ", ".join("%g" % round(x, 2) + "" for x in r["rot_deg"])
        print("| %s | (%s) | %+.0f %% | %+.0f / %.0f "
              "| %.2f (%.1f) | %+.2f (%.1f) | %+.2f (%.1f) | %+.2f (%.1f) | %s |" % (
            r["name"], rv, r["focal_pct"], r["td0_ms"], r["ro_ms"], r["b_rot"], r["b_rot_sig"], r["b_f"],
            r["b_f_sig"], r["b_td"], r["b_td_sig"], r["b_ro"], r["b_ro_sig"], yn(r["b_pass"])))
    print()
    print("the filter's last online-calibration row (after): error against the truth")
    print()
    print("| case | rot [deg] | focal fx / fy [%] | t_d [ms] | t_r [ms] | ≤ 0.3° / 1 % / 1 ms | APE [m] |")
    print("|---|---|---|---|---|---|---|")
    for r in R:
        if not r["after"]:
            print("| %s | no calibration rows: %s | | | | | |" % (r["name"], r["run"].replace("\n", "; ")))
            continue
        ape = "%.3f" % r["ape"] if isinstance(r.get("ape"), float) else "?"
        print("| %s | %.2f | %+.2f / %+.2f | %+.2f | %+.2f | %s / %s / %s | %s |" % (
            r["name"], r["a_rot"], r["a_fx"], r["a_fy"], r["a_td"], r["a_ro"],
            yn(r["a_pass_rot"]), yn(r["a_pass_f"]), yn(r["a_pass_td"]), ape))
    n = len(R)
    a = [r for r in R if r["after"]]
    print()
    print("calibrate within 3σ on all quantities: %d of %d;\n"
          "after the filter: rotation ≤ 0.3° %d, focal ≤ 1 %% %d, "
          "t_d ≤ 1 ms %d, all three %d of %d" % (
              sum(r["b_pass"] for r in R), n, sum(r["a_pass_rot"] for r in a), sum(r["a_pass_f"] for r in a),
              sum(r["a_pass_td"] for r in a), sum(r["a_pass_rot"] and r["a_pass_f"] and r["a_pass_td"] for r in a), n))


if __name__ == "__main__":
    main()
