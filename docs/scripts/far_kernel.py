"""The far Lennard-Jones kernel, group by group and summed over the band.

    python3 docs/scripts/far_kernel.py [store] [potential ...]   # default: data, every lj-*

For each potential's dilute kernel at u' = 0 (`kernel_log` and `kernel_replicates`
through the store's refs; pyarrow only): the median relative standard error of G,
G_self and G_bath (relative to G) over the log groups 0.01 <= |du| <= 0.05, the
bath part's chi-square against zero over those groups, and the relative standard
errors of the sums of the fine bins over [0.01, 0.05], [0.01, 0.02], [0.02, 0.035]
and [0.035, 0.05] from the randomizations' spread (docs/sampling.md, "Why the
median relative error stays high at theta = 50 and 100").
"""
import json
import math
import statistics
import sys
from pathlib import Path

import pyarrow.parquet as pq

BAND = (0.01, 0.05)
RANGES = [(0.01, 0.05), (0.01, 0.02), (0.02, 0.035), (0.035, 0.05)]


def table(store, instance, name):
    ref = json.loads((store / "refs" / "kernel" / f"{instance}.json").read_text())
    return pq.read_table(store / "artifacts" / "kernel" / ref["key"] / f"{name}.parquet")


def groups(store, instance):
    rows = table(store, instance, "kernel_log").to_pylist()
    rows = [r for r in rows if BAND[0] <= abs(r["du"]) <= BAND[1]]
    median = lambda c: statistics.median(r[c + "_stderr"] / abs(r["G"]) for r in rows)
    chi2 = sum((r["G_bath"] / r["G_bath_stderr"]) ** 2 for r in rows)
    return (
        f"{len(rows)} groups: median G {100 * median('G'):.2f}%, self {100 * median('G_self'):.2f}%,"
        f" bath {100 * median('G_bath'):.2f}%; bath chi2 against 0: {chi2:.1f}"
    )


def band_sums(store, instance):
    columns = table(store, instance, "kernel_replicates").to_pydict()
    cells = []
    for lo, hi in RANGES:
        sums = {}
        for du, r, g, s in zip(
            columns["du"], columns["randomization"], columns["G"], columns["G_self"]
        ):
            if lo <= abs(du) <= hi:
                total = sums.setdefault(r, [0.0, 0.0])
                total[0] += g
                total[1] += s
        whole = [sums[r][0] for r in sorted(sums)]
        own = [sums[r][1] for r in sorted(sums)]
        error = lambda values: (
            statistics.stdev(values) / math.sqrt(len(values)) / abs(statistics.mean(values))
        )
        cells.append(f"[{lo}, {hi}] G {100 * error(whole):.2f}% self {100 * error(own):.2f}%")
    return "; ".join(cells)


def main():
    store = Path(sys.argv[1] if len(sys.argv) > 1 else "data")
    potentials = sys.argv[2:] or sorted(
        p.stem.removesuffix("_u0_rho0")
        for p in (store / "refs" / "kernel").glob("lj-*_u0_rho0.json")
    )
    for potential in potentials:
        instance = f"{potential}_u0_rho0"
        print(f"{potential}: {groups(store, instance)}")
        print(f"  band sums: {band_sums(store, instance)}")


main()
