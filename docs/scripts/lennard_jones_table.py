"""Prints docs/lennard-jones.md's table from a store of the default study.

    python3 docs/scripts/lennard_jones_table.py [store]   # default: data

Reads each stage's current artifact through the store's refs (pyarrow only):
`table/study/table.parquet` for `a`, `k_d` and the `a_n` of n = 6 and 12,
`moments` for the recombination rate of the atom at rest from the kernel's
scenes, `sweep/<lj>/recombination.parquet` for the sweep's own scenes and
`dissociation/<lj>/recombination.parquet` for detailed balance (`3 K_b k_d`
and its `R(u')`). The last column is the largest |z| of the four
comparisons the rates allow (three at rest, one thermal).
"""
import json
import math
import sys
from pathlib import Path

import pyarrow.parquet as pq


def table(store, stage, instance, name):
    ref = json.loads((store / "refs" / stage / f"{instance}.json").read_text())
    path = store / "artifacts" / stage / ref["key"] / f"{name}.parquet"
    return pq.read_table(path).to_pylist()


def rate(row):
    return row["recombination_rate"], row["recombination_rate_stderr"]


def rows_at(rows, u_prime):
    return next(r for r in rows if r["u_prime"] == u_prime)


def z(a, b):
    return (a[0] - b[0]) / math.hypot(a[1], b[1])


def text(estimate):
    mean, stderr = estimate
    digits = max(0, 1 - math.floor(math.log10(stderr))) if stderr > 0 else 4
    return f"{mean:.{digits}f} ± {stderr:.{digits}f}"


def main():
    store = Path(sys.argv[1] if len(sys.argv) > 1 else "data")
    summary = table(store, "table", "study", "table")
    a_of = {r["potential"]: r["a_n"] for r in summary}
    print(
        "| theta | a (free atoms) | R(0), kernel's scenes | R(0), sweep's scenes "
        "| R(0), detailed balance | R thermal, sweep's scenes | 3 K_b k_d | largest abs(z) "
        "| k_d [rho v_th] | a / a_6 | a / (a_12 theta^(1/12)) |"
    )
    print("|" + "---|" * 11)
    for row in summary:
        theta = row["theta"]
        if theta is None or math.isnan(theta):
            continue
        lj = row["potential"]
        kernel = rate(table(store, "moments", f"{lj}_u0_rho0", "moments")[0])
        sweep = table(store, "sweep", lj, "recombination")
        balance = table(store, "dissociation", lj, "recombination")
        at_rest = [kernel, rate(rows_at(sweep, 0.0)), rate(rows_at(balance, 0.0))]
        thermal = [rate(rows_at(sweep, None)), rate(rows_at(balance, None))]
        largest = max(
            abs(z(at_rest[0], at_rest[2])),
            abs(z(at_rest[1], at_rest[2])),
            abs(z(at_rest[0], at_rest[1])),
            abs(z(*thermal)),
        )
        a = (row["a_n"], row["a_n_stderr"])
        k_d = (row["dissociation_rate"], row["dissociation_rate_stderr"])
        cells = [f"{theta:g}", text(a)] + [text(r) for r in at_rest + thermal]
        cells += [f"{largest:.1f}", text(k_d), f"{a[0] / a_of['ipp-6']:.3g}"]
        cells.append(f"{a[0] / (a_of['ipp-12'] * theta ** (1 / 12)):.3g}")
        print("| " + " | ".join(cells) + " |")


main()
