"""What a reader of a ternary bundle does, with polars, DuckDB and matplotlib only.

    python3 examples/bundle.py BUNDLE [--out kernels.png]

BUNDLE is a folder written by `ternary export` (docs/tutorial.md makes one). The
script finds its tables through `datapackage.json`, as any reader without our code
would, then

1. plots the kernel G(0 -> u) of two potentials against u - u' (log axes), from
   the kernel's log-spaced groups of bins (`kernel_log`),
2. recomputes a_n at the paper's truncation X = 0.04 by summing u^2 G_self over
   the kernel's bins and compares it with the `moments` table's own value, within
   the table's standard error plus the bins' discretization bound,
3. reads the `kernels` figure's `points.parquet` and checks that the figure shows
   the same potentials.

It exits with status 1 if a check fails. Units: velocities in v_th, rates in
rho^2 l v_th (docs/stages.md).
"""

import argparse
import json
import pathlib
import sys

import duckdb
import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import polars as pl  # noqa: E402

TRUNCATION = 0.04  # v_th, the paper's |u - u'| <= 0.04


def resources(bundle):
    """Every table of the bundle: (stage, instance, table name, parameters, path)."""
    descriptor = bundle / "datapackage.json"
    if not descriptor.is_file():
        sys.exit(f"{bundle}: no datapackage.json (is it a bundle `ternary export` wrote?)")
    package = json.loads(descriptor.read_text())
    for resource in package["resources"]:
        meta = resource.get("ternary", {})
        if resource.get("type") == "table":
            yield (meta["stage"], meta["instance"], meta.get("table"), meta.get("params", {}),
                   bundle / resource["path"])


def dilute_kernels_at_rest(bundle):
    """{potential: {table name: path}} of the kernel tables (`kernel`, `kernel_log`)
    and the `moments` table of every potential at u' = 0, dilute."""
    found = {}
    for stage, instance, table, _, path in resources(bundle):
        if stage in ("kernel", "moments") and instance.endswith("_u0_rho0"):
            potential = instance.removesuffix("_u0_rho0")
            found.setdefault(potential, {})[table or stage] = path
    return found


def natural(potential):
    """Sort key of a potential id: `ipp-6` before `ipp-10`."""
    family, _, value = potential.partition("-")
    try:
        return (family, float(value))
    except ValueError:
        return (family, float("inf"))


def plot_kernels(kernels, out):
    """G(0 -> u) above u' of each potential on its log groups, log axes, +- one
    standard error (groups whose error exceeds half their value left out)."""
    figure, axes = plt.subplots(figsize=(5, 3.5))
    for potential, tables in kernels.items():
        groups = (pl.read_parquet(tables["kernel_log"])
                  .filter((pl.col("du") > 0) & (pl.col("G_stderr") < 0.5 * pl.col("G"))))
        axes.errorbar(groups["du"], groups["G"], yerr=groups["G_stderr"], fmt="o",
                      markersize=3, linewidth=0.8, label=potential)
    axes.set(xscale="log", yscale="log", xlabel="u - u'  [v_th]",
             ylabel="G(0 -> u)  [rho^2 l v_th / v_th]")
    axes.legend()
    figure.tight_layout()
    figure.savefig(out, dpi=150)
    print(f"wrote {out}")


def a_n_by_summation(kernel_path):
    """sum u^2 G_self du over the bins with |u - u'| <= X (DuckDB), and the bound on
    what bins of finite width can change: each bin's u^2 ranges over the bin, and a
    bin that straddles X may lie wholly in or out."""
    row = duckdb.execute(f"""
        WITH bins AS (
            SELECT du, G_self, (SELECT min(du) FROM '{kernel_path}' WHERE du > 0) AS width
            FROM '{kernel_path}')
        SELECT sum(du * du * G_self * width) FILTER (WHERE abs(du) <= {TRUNCATION}),
               sum(((abs(du) + width / 2) ^ 2 - du * du) * abs(G_self) * width)
                   FILTER (WHERE abs(du) <= {TRUNCATION})
               + sum((abs(du) + width / 2) ^ 2 * abs(G_self) * width)
                   FILTER (WHERE abs(du) <= {TRUNCATION} AND abs(du) + width / 2 > {TRUNCATION})
        FROM bins""").fetchone()
    return row[0], row[1]


def a_n_from_moments(moments_path):
    """The moments table's self variance rate at truncation X, with its standard error."""
    row = (pl.read_parquet(moments_path)
           .filter((pl.col("truncation") - TRUNCATION).abs() < 1e-12)
           .row(0, named=True))
    return row["self_variance"], row["self_variance_stderr"]


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("bundle", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("kernels.png"))
    args = parser.parse_args()

    if args.out.exists():
        sys.exit(f"{args.out}: exists; give --out a new file (this script writes no file it did not make)")
    kernels = dilute_kernels_at_rest(args.bundle)
    if len(kernels) < 2:
        sys.exit(f"{args.bundle}: needs the dilute kernels at u' = 0 of two potentials, "
                 f"has {sorted(kernels)}")
    two = {p: kernels[p] for p in sorted(kernels, key=natural)[:2]}
    plot_kernels(two, args.out)

    failed = False
    print(f"a_n at |u - u'| <= {TRUNCATION}, rho^2 l v_th:")
    for potential, tables in two.items():
        summed, binning = a_n_by_summation(tables["kernel"])
        table, stderr = a_n_from_moments(tables["moments"])
        allowed = binning + 3 * stderr
        agrees = abs(summed - table) <= allowed
        failed |= not agrees
        print(f"  {potential}: bins summed {summed:.6e}, moments {table:.6e} +- {stderr:.1e}, "
              f"difference {summed - table:+.1e} (allowed {allowed:.1e}: binning "
              f"{binning:.1e} + 3 standard errors) {'agrees' if agrees else 'DISAGREES'}")

    figure_points = [p for s, i, t, _, p in resources(args.bundle)
                     if s == "figures" and i == "kernels" and t == "points"]
    points = pl.read_parquet(figure_points[0])
    series = points["series"].unique().sort().to_list()
    print(f"figure kernels: {points.height} points in series {series}")
    missing = [p for p in two if not any(p.removeprefix("ipp-") in s for s in series)]
    if missing:
        print(f"  the figure lacks {missing}")
        failed = True
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
