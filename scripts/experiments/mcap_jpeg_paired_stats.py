#!/usr/bin/env python3
"""Statistics of scripts/experiments/mcap_jpeg_paired_ape.sh's runs.csv (data,seed,arm,ape_m,wall_s), standard
library only. Per data set and JPEG arm, over the seeds that have both the raw and that arm:
  - the mean APE of each arm (sd);
  - the ratio of the means JPEG/raw with a 95 % interval from a paired bootstrap over seeds (20000 resamples of the
    seeds, each resample keeping a seed's raw and JPEG run together; percentile interval; fixed generator seed), and
    a delta-method interval on the log of the ratio (using the paired covariance) as a cross-check;
  - the per-seed ratio JPEG_k/raw_k: arithmetic mean with a Student-t interval, and geometric mean with a t interval
    on the log ratios;
  - the correlation of raw and JPEG APE over seeds (how much the pairing helps);
  - the verdict against the bar "JPEG APE within 5 % of raw": met when the ratio-of-means interval lies inside
    [0.95, 1.05], not met when it lies outside it, undecided when it straddles 0.95 or 1.05.
Prints a markdown table.  Usage: mcap_jpeg_paired_stats.py runs.csv"""
import csv
import math
import random
import statistics as st
import sys
from collections import defaultdict

Z975 = 1.959963984540054


def t975(df):
    """Student-t 97.5 % quantile (Cornish-Fisher expansion in 1/df; within 0.003 for df >= 5, 1e-4 for df >= 10)."""
    z = Z975
    return (z + (z**3 + z) / (4 * df) + (5 * z**5 + 16 * z**3 + 3 * z) / (96 * df**2)
            + (3 * z**7 + 19 * z**5 + 17 * z**3 - 15 * z) / (384 * df**3))


def verdict(lo, hi, bar=0.05):
    if lo >= 1 - bar and hi <= 1 + bar:
        return "met"
    if hi < 1 - bar or lo > 1 + bar:
        return "not met"
    return "undecided"


def main(path):
    ape = defaultdict(dict)  # (data, arm) -> seed -> ape
    wall = defaultdict(list)
    for r in csv.DictReader(open(path)):
        ape[(r["data"], r["arm"])][int(r["seed"])] = float(r["ape_m"])
        wall[(r["data"], r["arm"])].append(float(r["wall_s"]))
    rows = []
    for (data, a) in sorted(ape, key=lambda x: (x[0] != "moving", x[0], -int(x[1][1:]) if x[1] != "raw" else 0)):
        if a == "raw" or (data, "raw") not in ape:
            continue
        raw = ape[(data, "raw")]
        seeds = sorted(set(raw) & set(ape[(data, a)]))
        x = [raw[k] for k in seeds]
        y = [ape[(data, a)][k] for k in seeds]
        n = len(seeds)
        if n < 3:
            continue
        mx, my = st.mean(x), st.mean(y)
        ratio = my / mx
        rng = random.Random(1)
        boot = []
        for _ in range(20000):
            idx = [rng.randrange(n) for _ in range(n)]
            boot.append(sum(y[i] for i in idx) / sum(x[i] for i in idx))
        boot.sort()
        b_lo, b_hi = boot[int(0.025 * len(boot))], boot[int(0.975 * len(boot)) - 1]
        cov = sum((xi - mx) * (yi - my) for xi, yi in zip(x, y)) / (n - 1)
        var_log = (st.variance(y) / my**2 + st.variance(x) / mx**2 - 2 * cov / (mx * my)) / n
        d_lo, d_hi = ratio * math.exp(-Z975 * math.sqrt(var_log)), ratio * math.exp(Z975 * math.sqrt(var_log))
        r = [yi / xi for xi, yi in zip(x, y)]
        t = t975(n - 1)
        rm, rh = st.mean(r), t * st.stdev(r) / math.sqrt(n)
        lr = [math.log(v) for v in r]
        gm, gh = st.mean(lr), t * st.stdev(lr) / math.sqrt(n)
        corr = cov / (st.stdev(x) * st.stdev(y))
        rows.append(
            f"| {data} | q{a[1:]} | {n} | {mx:.5f} ± {st.stdev(x):.5f} | {my:.5f} ± {st.stdev(y):.5f} | "
            f"**{ratio:.3f}** [{b_lo:.3f}, {b_hi:.3f}] | [{d_lo:.3f}, {d_hi:.3f}] | "
            f"{rm:.3f} [{rm - rh:.3f}, {rm + rh:.3f}] | {math.exp(gm):.3f} [{math.exp(gm - gh):.3f}, "
            f"{math.exp(gm + gh):.3f}] | {corr:+.2f} | {st.median(wall[(data, 'raw')]):.1f} / "
            f"{st.median(wall[(data, a)]):.1f} | {verdict(b_lo, b_hi)} |")
    print("| data | JPEG | K | raw APE mean ± sd [m] | JPEG APE mean ± sd [m] | ratio of means [95 % paired bootstrap] "
          "| [95 % delta, log] | per-seed ratio: mean [95 % t] | geometric mean [95 % t] | corr raw–JPEG "
          "| s per run raw / JPEG | bar ±5 % |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    print("\n".join(rows))


if __name__ == "__main__":
    main(sys.argv[1])
