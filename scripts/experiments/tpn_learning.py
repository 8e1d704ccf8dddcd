#!/usr/bin/python3
"""Summarise scripts/experiments/tpn_learning.sh: per run the t_d error RMS in 1-s windows against the folder's truth,
and when a mode's window error falls below the reference mode's (drift) for good. Usage: tpn_learning.py OUT COMMIT"""
import collections
import glob
import os
import re
import sys

import numpy as np

out, commit = sys.argv[1], sys.argv[2]
REF = "drift"
TOL = 0.1  # [ms] "within drift's": noise between two modes that both follow the offset


def load(run_csv, folder):
    e = np.genfromtxt(run_csv, delimiter=",", names=True)
    tru = np.genfromtxt(folder + "/mav0/td_truth/data.csv", delimiter=",", comments="#")
    t = e["timestamp_ns"].astype(float)
    err = (e["td_s"] - np.interp(t, tru[:, 0], tru[:, 1])) * 1e3
    return (t - t[0]) * 1e-9, err, e["td_sigma_s"] * 1e3


def windows(ts, err, n):
    k = np.floor(ts).astype(int)
    return np.array([np.sqrt(np.mean(err[k == i] ** 2)) if np.any(k == i) else np.nan for i in range(n)])


def stays_below(w, ref, tol=0.0):
    """First window index from which w < ref + tol in every later window (None: never)."""
    below = w < ref + tol
    if not below[-1]:
        return None
    i = len(w) - 1
    while i > 0 and below[i - 1]:
        i -= 1
    return i


tpn_lines = []
runs = collections.defaultdict(dict)  # (flight, rate, seed) -> mode -> record
for log in sorted(glob.glob(f"{out}/runs/*/*.log")):
    case, mode = os.path.basename(os.path.dirname(log)), os.path.basename(log)[:-4]
    flight, rate, seed = re.match(r"(\w+?)_r([0-9.]+)_s(\d+)$", case).groups()
    text = open(log).read()
    csv = log[:-4] + ".csv"
    rec = {"ok": "trajectory:" in text and os.path.exists(csv)}
    if rec["ok"]:
        ts, err, sig = load(csv, f"{out}/data/{case}")
        rec.update(ts=ts, err=err, sig=sig, final=err[-1], fsig=sig[-1], nees=float(np.mean((err[1:] / sig[1:]) ** 2)) if np.all(sig[1:] > 0) else np.nan)
        m = re.search(r"TPE ([0-9.]+) mm", text)
        rec["tpe"] = float(m.group(1)) if m else np.nan
        m = re.search(r"APE ([0-9.]+) m", text)
        rec["ape"] = float(m.group(1)) * 1e3 if m else np.nan
        m = re.search(r"switched to the drift state at ([0-9.]+) s", text)
        rec["switch"] = float(m.group(1)) if m else None
        m = re.search(r"TPN: labels from image (-?\d+), first prediction after image (-?\d+|\(none\)).*?(\d+) trainings, "
                      r"labels restarted (\d+) times; rate at its bound .*? in (\d+) of (\d+) propagations", text)
        if m:
            tpn_lines.append((flight, rate, seed, mode) + m.groups())
    runs[(flight, float(rate), int(seed))][mode] = rec

modes = sorted({m for r in runs.values() for m in r}, key=lambda m: (m != "sr", m != REF, m != "oracle", m))
learners = [m for m in modes if m.startswith(("tpn", "ton"))]
print("# How long TPN takes to learn: t_d error per 1-s window against the drift state\n")
print(f"Made by `scripts/experiments/tpn_learning.sh` (binary of {commit}). Per case (flight, drift rate "
      "[ms/s], seed): the first second from which the mode's t_d error RMS in every later 1-s window is below "
      f"`{REF}`'s (\"never\": it is not below in the last window; images = rows before that second), the share of "
      f"the last 10 windows in which it is below, the mean t_d error RMS over the last 10 s [ms] (mode / {REF}), "
      "final error / σ [ms], run-mean t_d NEES, TPE [mm], APE [mm] and when the model check switched t_d to the "
      "drift state.\n")
print("| flight | rate | seed | mode | below drift from [s] (images) | within drift + 0.1 ms from [s] (images) "
      "| last 10 s below | t_d RMS last 10 s (drift) "
      "| final err / σ [ms] | t_d NEES | TPE [mm] | APE [mm] | switched [s] |")
print("|---|---:|---:|---|---|---|---:|---|---|---:|---:|---:|---|")
agg = collections.defaultdict(list)
bins = collections.defaultdict(list)
BINS = [(0, 2), (2, 5), (5, 10), (10, 20), (20, 30), (30, 40)]
for key in sorted(runs):
    r = runs[key]
    ref = r.get(REF)
    if not ref or not ref["ok"]:
        continue
    n = int(np.floor(ref["ts"][-1])) + 1
    wref = windows(ref["ts"], ref["err"], n)
    for mode in modes:
        rec = r.get(mode)
        if rec is None:
            continue
        if not rec["ok"]:
            print(f"| {key[0]} | {key[1]:g} | {key[2]} | {mode} | stopped | | | | | | | | |")
            agg[(key[0], key[1], mode)].append(None)
            continue
        w = windows(rec["ts"], rec["err"], n)
        last = slice(n - 10, n)
        rms_last, rms_ref = np.sqrt(np.nanmean(w[last] ** 2)), np.sqrt(np.nanmean(wref[last] ** 2))
        frac = np.mean(w[last] < wref[last])
        if mode == REF or mode == "oracle":
            since = near = "–"
            i = j = None
        else:
            i, j = stays_below(w, wref), stays_below(w, wref, TOL)
            since = "never" if i is None else f"{i} ({int(np.sum(rec['ts'] < i))})"
            near = "never" if j is None else f"{j} ({int(np.sum(rec['ts'] < j))})"
        sw = "–" if rec["switch"] is None else f"{rec['switch']:.1f}"
        print(f"| {key[0]} | {key[1]:g} | {key[2]} | {mode} | {since} | {near} | {frac * 10:.0f}/10 | {rms_last:.2f} "
              f"({rms_ref:.2f}) | {rec['final']:+.2f} / {rec['fsig']:.2f} | {rec['nees']:.2f} | {rec['tpe']:.2f} | "
              f"{rec['ape']:.1f} | {sw} |")
        bins[(key[0], key[1], mode)].append([np.sqrt(np.nanmean(w[a:b] ** 2)) for a, b in BINS])
        agg[(key[0], key[1], mode)].append((i, frac, rms_last, rms_ref, abs(rec["final"]) / rec["fsig"] if rec["fsig"] > 0 else np.nan,
                                            rec["nees"], rec["tpe"], rec["ape"], rec["switch"], j))

print("\n## Per flight and rate (over seeds)\n")
print("| flight | rate [ms/s] | mode | below drift from [s] | within drift + 0.1 ms from [s] | last 10 s below | t_d RMS last 10 s [ms] (drift) "
      "| max final abs err / σ | t_d NEES | TPE [mm] | APE [mm] | switched |")
print("|---|---:|---|---|---|---:|---|---:|---:|---:|---:|---|")
for (flight, rate, mode), v in sorted(agg.items(), key=lambda kv: (kv[0][0], kv[0][1], modes.index(kv[0][2]))):
    ok = [x for x in v if x is not None]
    if not ok:
        print(f"| {flight} | {rate:g} | {mode} | stopped ({len(v)}) | | | | | | | | |")
        continue
    since = "–" if mode in (REF, "oracle") else ", ".join("never" if x[0] is None else str(x[0]) for x in ok)
    near = "–" if mode in (REF, "oracle") else ", ".join("never" if x[9] is None else str(x[9]) for x in ok)
    sw = sum(x[8] is not None for x in ok)
    fmax = np.nan if mode == "oracle" else np.nanmax([x[4] for x in ok])
    print(f"| {flight} | {rate:g} | {mode} | {since} | {near} | {np.mean([x[1] for x in ok]) * 10:.1f}/10 | "
          f"{np.mean([x[2] for x in ok]):.2f} ({np.mean([x[3] for x in ok]):.2f}) | {fmax:.1f} | "
          f"{np.mean([x[5] for x in ok]):.2f} | {np.mean([x[6] for x in ok]):.2f} | {np.mean([x[7] for x in ok]):.1f} | "
          f"{sw} of {len(ok)}{' (stopped ' + str(len(v) - len(ok)) + ')' if len(ok) < len(v) else ''} |")

print("\n## t_d error RMS by stretch of the run [ms] (windows' RMS, mean over seeds)\n")
print("| flight | rate [ms/s] | mode | " + " | ".join(f"{a}-{b} s" for a, b in BINS) + " |")
print("|---|---:|---|" + "---:|" * len(BINS))
for (flight, rate, mode), v in sorted(bins.items(), key=lambda kv: (kv[0][0], kv[0][1], modes.index(kv[0][2]))):
    if mode == "oracle":
        continue
    m = np.nanmean(np.array(v), axis=0)
    print(f"| {flight} | {rate:g} | {mode} | " + " | ".join(f"{x:.2f}" for x in m) + " |")

if tpn_lines:
    print("\n## TPN's start (the run's summary line; runs made by a binary that prints it)\n")
    print("| flight | rate | seed | mode | labels from image | first prediction after image | trainings | restarts "
          "| rate at rate_max |")
    print("|---|---:|---:|---|---:|---:|---:|---:|---:|")
    for f, r, sd, mode, a, b, n, rs, c, p in sorted(tpn_lines, key=lambda x: (x[0], float(x[1]), int(x[2]), x[3])):
        print(f"| {f} | {float(r):g} | {sd} | {mode} | {a} | {b} | {n} | {rs} | {100 * int(c) / max(int(p), 1):.0f} % |")
