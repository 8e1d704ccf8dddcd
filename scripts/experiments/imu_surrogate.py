#!/usr/bin/env python3
"""Transplanted and phase-randomised real IMU residuals in synthetic folders (issue 13; imu_surrogate.sh drives it).

The real V1_01 IMU log minus the ideal IMU along the simulator's spline of EuRoC's own ground truth is the log's
residual r(t): everything the real IMU adds to the motion the images follow (noise, biases, scale, vibration, and
whatever of the reference's own errors the IMU does not share). Writing ideal(span) + a variant of r into the
imu0/data.csv of a copy of a fully synthetic folder (same images, ground truth, stamps, declared noise) tells which
property of r makes the real log harder than the error model:
  S   the span's own residual (≈ the semi-real folder: a check of the construction)
  T   the residual of another span of the same log (all of the real IMU's own structure, not locked to this span)
  P   phase-randomised flight residual, one phase per frequency for all 6 channels (keeps every auto- and
      cross-spectrum incl. narrow lines; Gaussian, stationary)
  Pi  phase-randomised with independent phases per channel (keeps auto-spectra and lines, no cross-structure)
  U   the synthetic folder's own IMU (the error model) + u
and, with --fine, each of S T P Pi with u taken out of r first. u is the motion the folders' spline (EuRoC's 20 Hz
ground truth, knots 0.1 s) misses and the real IMU recorded: the ideal IMU along the 200 Hz V1_01_easy.txt (knots
0.03 s) minus the ideal IMU along the folders' spline, above 1.5 Hz.
The ground truth's bias columns (the filter's initial biases under ground-truth initialisation) are, unless
--bias euroc, the residual's flight mean: the synthetic model's convention (turn-on bias, the wander is noise).

  imu_surrogate.py prep  --real REAL_IMU_CSV --ideal-whole DIR --out NPZ          (residual of the whole log + report)
  imu_surrogate.py write --syn DIR --out DIR --ideal DIR --variant S|T|P|Pi|X --npz NPZ
                         [--src-ideal DIR --real CSV] [--seed N] [--bias const|euroc|syn --euroc-gt CSV]
  imu_surrogate.py prep-unres --npz NPZ --ideal-whole DIR --ideal-fine DIR         (u, the motion the spline misses)
  imu_surrogate.py write ... --fine (residual minus u) | --variant U [--u-part all|gyro|accel|lo|hi]
Needs numpy only.
"""
import argparse
import os
import shutil
import sys

import numpy as np

FLIGHT = (4.0, 143.0)  # s after the ground truth's first pose: V1_01 flies from ~3 s to the end of the log
BANDS = [(0.1, 0.2), (0.2, 0.5), (0.5, 2), (2, 10), (10, 20), (20, 40), (40, 60), (60, 100)]


def load_imu(path):
    return np.loadtxt(path, delimiter=",", comments="#", dtype=np.float64, ndmin=2), read_header(path)


def read_header(path):
    with open(path) as f:
        return f.readline()


def stamps_ns(path):  # exact int64 stamps
    out = []
    with open(path) as f:
        for line in f:
            if line.startswith("#") or not line.strip():
                continue
            out.append(int(line.split(",", 1)[0]))
    return np.array(out, dtype=np.int64)


def residual_against(ideal_dir, real_csv):
    """real - ideal at the ideal folder's stamps (the real log's stamps coincide with them to < 1 us)."""
    ip = os.path.join(ideal_dir, "mav0/imu0/data.csv")
    ts = stamps_ns(ip)
    ideal, _ = load_imu(ip)
    rts = stamps_ns(real_csv)
    real, _ = load_imu(real_csv)
    i0 = int(np.searchsorted(rts, ts[0] - 2500000))
    rr = real[i0:i0 + len(ts)]
    d = rts[i0:i0 + len(ts)] - ts
    if len(rr) != len(ts) or np.abs(d).max() > 100000:
        sys.exit(f"real stamps do not coincide with {ip} (max diff {np.abs(d).max()} ns)")
    return ts, rr[:, 1:] - ideal[:, 1:]


def band_levels(r, fs):
    """One-sided white-equivalent density per band, as imu_match reports them (sqrt(mean one-sided PSD))."""
    n = len(r)
    X = np.fft.rfft((r - r.mean(0)) * np.hanning(n)[:, None], axis=0)
    psd = 2.0 * np.abs(X) ** 2 / (fs * (np.hanning(n) ** 2).sum())
    f = np.fft.rfftfreq(n, 1 / fs)
    rows = []
    for lo, hi in BANDS:
        m = (f >= lo) & (f < hi)
        rows.append(np.sqrt(psd[m].mean(0)))
    return np.array(rows)


def cmd_prep(a):
    ts, r = residual_against(a.ideal_whole, a.real)
    t = (ts - ts[0]) * 1e-9
    fl = (t >= FLIGHT[0]) & (t < FLIGHT[1])
    rf = r[fl]
    np.savez(a.out, ts=ts, r=r, flight=fl, mean=rf.mean(0))
    fs = 200.0
    lv = band_levels(rf, fs)
    print(f"residual of the real log against the whole-log spline: {len(ts)} samples, flight {rf.shape[0]} samples")
    print("flight mean (bias columns of the const variants): gyro "
          + ", ".join(f"{v:.5f}" for v in rf.mean(0)[:3]) + "; accel " + ", ".join(f"{v:.4f}" for v in rf.mean(0)[3:]))
    print("\n| band [Hz] | gyro [rad/s/√Hz] x, y, z | accel [m/s²/√Hz] x, y, z |\n|---|---|---|")
    for (lo, hi), row in zip(BANDS, lv):
        print(f"| {lo}–{hi} | " + ", ".join(f"{v:.5f}" for v in row[:3]) + " | " + ", ".join(f"{v:.4f}" for v in row[3:]) + " |")
    # Cross-structure: coherence between channels in bands (Welch, 2 s segments).
    names = ["gx", "gy", "gz", "ax", "ay", "az"]
    seg = 400
    nseg = len(rf) // seg
    Xs = np.fft.rfft((rf[:nseg * seg].reshape(nseg, seg, 6) - rf[:nseg * seg].reshape(nseg, seg, 6).mean(1, keepdims=True))
                     * np.hanning(seg)[None, :, None], axis=1)
    f = np.fft.rfftfreq(seg, 1 / fs)
    S = np.einsum("kfi,kfj->fij", Xs, Xs.conj()) / nseg
    print("\nlargest magnitude-squared coherences per band (Welch, 2 s segments; |C|² of independent channels ~ 1/" + str(nseg) + "):")
    for lo, hi in [(0.5, 2), (2, 10), (10, 20), (20, 40), (40, 60), (60, 100)]:
        m = (f >= lo) & (f < hi)
        Sb = S[m].sum(0)
        C = np.abs(Sb) ** 2 / np.outer(np.diag(Sb).real, np.diag(Sb).real)
        pairs = sorted(((C[i, j], names[i] + "-" + names[j]) for i in range(6) for j in range(i + 1, 6)), reverse=True)[:4]
        print(f"  {lo}–{hi} Hz: " + ", ".join(f"{p} {c:.2f}" for c, p in pairs))
    # Narrow lines: peak-to-median of the Welch PSD in 10-100 Hz.
    P = np.einsum("fii->fi", S).real
    m = f >= 10
    print("\nnarrow lines 10–100 Hz (Welch 0.5 Hz bins): channel, top-3 peaks [Hz] and peak/median PSD:")
    for c in range(6):
        p = P[m, c]
        top = np.argsort(p)[::-1][:3]
        print(f"  {names[c]}: " + ", ".join(f"{f[m][k]:.1f} Hz ×{p[k] / np.median(p):.0f}" for k in top))
    # Non-Gaussianity: kurtosis of band-passed flight residual.
    print("\nexcess kurtosis of the band-passed flight residual (0 for Gaussian):")
    X = np.fft.rfft(rf - rf.mean(0), axis=0)
    f2 = np.fft.rfftfreq(len(rf), 1 / fs)
    for lo, hi in [(0.1, 2), (2, 20), (20, 100)]:
        Y = X.copy()
        Y[(f2 < lo) | (f2 >= hi)] = 0
        y = np.fft.irfft(Y, n=len(rf), axis=0)
        k = (y ** 4).mean(0) / (y ** 2).mean(0) ** 2 - 3
        print(f"  {lo}–{hi} Hz: " + ", ".join(f"{names[c]} {k[c]:.2f}" for c in range(6)))


def bandpass(x, fs, lo, hi):
    X = np.fft.rfft(x - x.mean(0), axis=0)
    f = np.fft.rfftfreq(len(x), 1 / fs)
    X[(f < lo) | (f >= hi)] = 0
    return np.fft.irfft(X, n=len(x), axis=0)


def cmd_prep_unres(a):
    """u: the motion the ground truth's spline misses - the ideal IMU along a finer spline (the 200 Hz V1_01_easy.txt,
    knots 0.03 s) minus the ideal IMU along the folders' spline (EuRoC's own 20 Hz ground truth, knots 0.1 s), above
    HP_HZ (below it the two references differ by their frames, not by motion). The real IMU follows it; a semi-real
    folder's images do not."""
    z = dict(np.load(a.npz))
    w, _ = load_imu(os.path.join(a.ideal_whole, "mav0/imu0/data.csv"))
    fi, _ = load_imu(os.path.join(a.ideal_fine, "mav0/imu0/data.csv"))
    ts = z["ts"]
    cover = (ts >= fi[0, 0]) & (ts <= fi[-1, 0])
    d = np.zeros((len(ts), 6))
    d[cover] = np.column_stack([np.interp(ts[cover].astype(np.float64), fi[:, 0], fi[:, c]) for c in range(1, 7)]) - w[cover, 1:]
    u = np.zeros_like(d)
    u[cover] = bandpass(d[cover], 200.0, a.hp_hz, 1e9)
    z["u"] = u
    np.savez(a.npz, **z)
    rf = (z["r"] - u)[z["flight"] & cover]
    print(f"u above {a.hp_hz} Hz, RMS over the covered log: gyro " + ", ".join(f"{v:.4f}" for v in u[cover].std(0)[:3])
          + " rad/s; accel " + ", ".join(f"{v:.3f}" for v in u[cover].std(0)[3:]) + " m/s²")
    print("\nresidual without u (the IMU's own, against the finer reference), flight:")
    print("| band [Hz] | gyro [rad/s/√Hz] x, y, z | accel [m/s²/√Hz] x, y, z |\n|---|---|---|")
    for (lo, hi), row in zip(BANDS, band_levels(rf, 200.0)):
        print(f"| {lo}–{hi} | " + ", ".join(f"{v:.5f}" for v in row[:3]) + " | " + ", ".join(f"{v:.4f}" for v in row[3:]) + " |")


def u_at(z, ts):
    return np.column_stack([np.interp(ts.astype(np.float64), z["ts"].astype(np.float64), z["u"][:, c]) for c in range(6)])


def surrogate(rf, seed, same_phase):
    """Phase-randomised copy of rf (n x 6): same periodogram per channel; same phases on all channels keeps the
    cross-periodograms too. DC and Nyquist kept."""
    rng = np.random.default_rng(seed)
    n = len(rf)
    X = np.fft.rfft(rf, axis=0)
    nf = X.shape[0]
    ph = rng.uniform(0, 2 * np.pi, size=(nf, 1 if same_phase else 6))
    ph[0] = 0
    if n % 2 == 0:
        ph[-1] = 0
    return np.fft.irfft(X * np.exp(1j * ph), n=n, axis=0)


def write_folder(syn, out, imu_rows, bias_rows):
    """Copy syn to out (images hard-linked) with imu0/data.csv and the ground truth's bias columns replaced."""
    if os.path.exists(out):
        shutil.rmtree(out)
    shutil.copytree(syn, out, copy_function=os.link)
    ip = os.path.join(out, "mav0/imu0/data.csv")
    header = read_header(os.path.join(syn, "mav0/imu0/data.csv"))
    ts = stamps_ns(os.path.join(syn, "mav0/imu0/data.csv"))
    os.remove(ip)  # hard link: never write through it
    with open(ip, "w") as f:
        f.write(header)
        for t, row in zip(ts, imu_rows):
            f.write(str(int(t)) + "," + ",".join("%.12g" % v for v in row) + "\n")
    gp = os.path.join(out, "mav0/state_groundtruth_estimate0/data.csv")
    lines = open(gp).read().splitlines()
    os.remove(gp)
    with open(gp, "w") as f:
        k = 0
        for line in lines:
            if line.startswith("#"):
                f.write(line + "\n")
                continue
            c = line.split(",")
            c[11:17] = ["%.9g" % v for v in bias_rows[k]]
            f.write(",".join(c) + "\n")
            k += 1


def euroc_bias_at(gt_csv, ts):
    g = np.loadtxt(gt_csv, delimiter=",", comments="#")
    gts = stamps_ns(gt_csv)
    idx = np.clip(np.searchsorted(gts, ts), 0, len(gts) - 1)  # as the simulator: first sample at or after t
    return g[idx, 11:17]


def cmd_write(a):
    z = np.load(a.npz)
    ideal, _ = load_imu(os.path.join(a.ideal, "mav0/imu0/data.csv"))
    ts = stamps_ns(os.path.join(a.ideal, "mav0/imu0/data.csv"))
    syn_ts = stamps_ns(os.path.join(a.syn, "mav0/imu0/data.csv"))
    if len(ts) != len(syn_ts) or np.any(ts != syn_ts):
        sys.exit("the ideal folder's stamps differ from the synthetic folder's")
    n = len(ts)
    src_ts = ts
    if a.variant in ("S", "T"):
        src_ts, r = residual_against(a.src_ideal, a.real)
        if a.fine:
            r = r - u_at(z, src_ts)
    elif a.variant == "U":  # the synthetic folder's own IMU + the motion the spline misses on this span
        syn_imu, _ = load_imu(os.path.join(a.syn, "mav0/imu0/data.csv"))
        u = u_at(z, ts)
        if a.u_part == "gyro":
            u[:, 3:] = 0
        elif a.u_part == "accel":
            u[:, :3] = 0
        elif a.u_part in ("lo", "hi"):  # u below / above 10 Hz (taken from the whole-log u, then cut)
            keep = bandpass(z["u"], 200.0, 0.0, 10.0) if a.u_part == "lo" else bandpass(z["u"], 200.0, 10.0, 1e9)
            u = np.column_stack([np.interp(ts.astype(np.float64), z["ts"].astype(np.float64), keep[:, c]) for c in range(6)])
        r = syn_imu[:, 1:] - ideal[:, 1:] + u
    elif a.variant in ("P", "Pi"):
        rf = (z["r"] - z["u"] if a.fine else z["r"])[z["flight"]]
        s = surrogate(rf, 1000 * a.seed + (1 if a.variant == "P" else 2), a.variant == "P")
        rng = np.random.default_rng(7919 * a.seed)
        k0 = int(rng.integers(1000, len(s) - n - 1000))  # away from the circular seam
        r = s[k0:k0 + n]
    else:
        sys.exit("unknown variant " + a.variant)
    r = np.asarray(r)[:n]
    if a.bias == "syn":  # keep the synthetic folder's ground truth (its bias columns)
        g = np.loadtxt(os.path.join(a.syn, "mav0/state_groundtruth_estimate0/data.csv"), delimiter=",", comments="#")
        bias = g[:, 11:17]
    elif a.bias == "euroc":
        bias = euroc_bias_at(a.euroc_gt, src_ts)
    else:
        bias = np.tile(z["mean"], (n, 1))
    write_folder(a.syn, a.out, ideal[:, 1:] + r, bias)
    print(f"{a.out}: variant {a.variant}, residual RMS gyro {np.sqrt((r[:, :3] ** 2).mean()):.4f} rad/s, "
          f"accel {np.sqrt((r[:, 3:] ** 2).mean()):.3f} m/s², bias columns {a.bias}")


def main():
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = p.add_subparsers(dest="cmd", required=True)
    q = sub.add_parser("prep")
    q.add_argument("--real", required=True)
    q.add_argument("--ideal-whole", required=True)
    q.add_argument("--out", required=True)
    q = sub.add_parser("write")
    q.add_argument("--syn", required=True)
    q.add_argument("--out", required=True)
    q.add_argument("--ideal", required=True)
    q.add_argument("--variant", required=True)
    q.add_argument("--npz", required=True)
    q.add_argument("--src-ideal")
    q.add_argument("--real")
    q.add_argument("--seed", type=int, default=1)
    q.add_argument("--bias", default="const", choices=["const", "euroc", "syn"])
    q.add_argument("--euroc-gt")
    q.add_argument("--fine", action="store_true", help="take u (prep-unres) out of the residual first")
    q.add_argument("--u-part", default="all", choices=["all", "gyro", "accel", "lo", "hi"], help="U: which part of u")
    q = sub.add_parser("prep-unres")
    q.add_argument("--npz", required=True)
    q.add_argument("--ideal-whole", required=True)
    q.add_argument("--ideal-fine", required=True)
    q.add_argument("--hp-hz", type=float, default=1.5)
    a = p.parse_args()
    {"prep": cmd_prep, "prep-unres": cmd_prep_unres, "write": cmd_write}[a.cmd](a)


if __name__ == "__main__":
    main()
