"""What a reader of a ternary bundle does, with polars, DuckDB, numpy and matplotlib only.

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
   the same potentials,
4. evaluates each kernel's model, of the whole and of its self part (`kernel_model`,
   `part` total and self: ln G a natural cubic spline in
   t = ln|du| + |du| / cutoff_scale, straight beyond its end knots) with numpy
   alone, with its error from `kernel_model_covariance`, and checks that its means
   over the fitted groups and their chi-square reproduce `kernel_model_groups` and
   `kernel_model_fit` (docs/kernel-model.md),
5. interpolates the models of the inverse power laws in 1/n to an n between the
   first two (Lagrange through every one, `ln G` at each du), with its error
   jackknifed over the randomizations the kernels share (`kernel_model_jackknife`:
   each model refitted without one randomization) and the interpolation's own
   estimate of its error (the same without the farthest node), as `ternary kernel
   --n` states them; it checks first that the jackknife replicates give each
   model's own error, as `kernel_model_covariance` does.

It exits with status 1 if a check fails. Units: velocities in v_th, rates in
rho^2 l v_th (docs/stages.md).
"""

import argparse
import json
import pathlib
import sys

import duckdb
import matplotlib
import numpy as np

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
    """{potential: {table name: path}} of the kernel tables (`kernel`, `kernel_log`),
    the `moments` table and the kernel model's tables of every potential at u' = 0,
    dilute."""
    found = {}
    for stage, instance, table, _, path in resources(bundle):
        if stage in ("kernel", "moments", "fit") and instance.endswith("_u0_rho0"):
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


class KernelModel:
    """One side of a kernel's model: ln G(x) at x = |u - u'| > 0, and its standard
    error, from the knots of `kernel_model` and their covariance; `part` "total" (G)
    or "self" (G_self; the bath part is the difference of the two)."""

    def __init__(self, knots_path, covariance_path, side="above", jackknife_path=None,
                 part="total"):
        ours = (pl.col("part") == part) & (pl.col("side") == side)
        knots = pl.read_parquet(knots_path).filter(ours).sort("knot")
        self.t = knots["t"].to_numpy()
        self.ln_g = knots["ln_G"].to_numpy()
        self.cutoff_scale = knots["cutoff_scale"][0]
        size = len(self.t)
        covariance = pl.read_parquet(covariance_path).filter(ours)
        self.covariance = np.zeros((size, size))
        self.covariance[covariance["knot_i"].to_numpy(), covariance["knot_j"].to_numpy()] = (
            covariance["covariance"].to_numpy())
        # The knots fitted without each randomization: [randomization, knot].
        self.left_out = None
        if jackknife_path is not None:
            rows = pl.read_parquet(jackknife_path).filter(ours)
            self.left_out = np.full((rows["randomization"].max() + 1, size), np.nan)
            self.left_out[rows["randomization"].to_numpy(), rows["knot"].to_numpy()] = (
                rows["ln_G"].to_numpy())

    def basis(self, x):
        """The natural cubic spline's cardinal basis at x (rows: points): S'' = 0 at
        the end knots, straight beyond them."""
        t, size = self.t, len(self.t)
        h = np.diff(t)
        system = np.zeros((size, size))
        system[0, 0] = system[-1, -1] = 1.0
        rhs = np.zeros((size, size))
        for k in range(1, size - 1):
            system[k, k - 1:k + 2] = h[k - 1] / 6, (h[k - 1] + h[k]) / 3, h[k] / 6
            rhs[k, k - 1:k + 2] = 1 / h[k - 1], -1 / h[k - 1] - 1 / h[k], 1 / h[k]
        curvature = np.linalg.solve(system, rhs)  # S'' at the knots per unit value
        s = np.log(x) + x / self.cutoff_scale
        k = np.clip(np.searchsorted(t, s) - 1, 0, size - 2)
        a = (t[k + 1] - np.clip(s, t[0], t[-1])) / h[k]
        b = 1 - a
        unit = np.eye(size)
        inside = (a[:, None] * unit[k] + b[:, None] * unit[k + 1]
                  + ((a ** 3 - a)[:, None] * curvature[k] + (b ** 3 - b)[:, None] * curvature[k + 1])
                  * (h[k] ** 2 / 6)[:, None])
        first = unit[1] / h[0] - unit[0] / h[0] - h[0] * (2 * curvature[0] + curvature[1]) / 6
        last = unit[-1] / h[-1] - unit[-2] / h[-1] + h[-1] * (curvature[-2] + 2 * curvature[-1]) / 6
        inside = np.where((s < t[0])[:, None], unit[0] + (s - t[0])[:, None] * first, inside)
        return np.where((s > t[-1])[:, None], unit[-1] + (s - t[-1])[:, None] * last, inside)

    def ln_G(self, x):
        return self.basis(np.atleast_1d(x)) @ self.ln_g

    def ln_G_stderr(self, x):
        b = self.basis(np.atleast_1d(x))
        return np.sqrt(np.einsum("pi,ij,pj->p", b, self.covariance, b))

    def ln_G_left_out(self, x):
        """ln G at x from the knots fitted without each randomization: [randomization, point]."""
        return self.left_out @ self.basis(np.atleast_1d(x)).T

    def group_means(self, inner, outer):
        """The model's mean over each group [inner, outer] (8-point Gauss-Legendre)."""
        nodes, weights = np.polynomial.legendre.leggauss(8)
        x = 0.5 * (inner + outer)[:, None] + 0.5 * (outer - inner)[:, None] * nodes
        values = np.exp(self.ln_G(x.ravel())).reshape(x.shape)
        return 0.5 * values @ weights


def check_kernel_model(potential, tables, part):
    """The model of `part` evaluated here against the fit stage's own group means and
    chi-square."""
    fit = (pl.read_parquet(tables["kernel_model_fit"]).filter(pl.col("part") == part)
           .row(0, named=True))
    if fit["status"] != "fitted":
        print(f"  {potential} {part}: no model ({fit['status']})")
        return True
    model = KernelModel(tables["kernel_model"], tables["kernel_model_covariance"], part=part)
    groups = (pl.read_parquet(tables["kernel_model_groups"])
              .filter((pl.col("part") == part) & (pl.col("du") > 0)))
    means = model.group_means(groups["du_inner"].to_numpy(), groups["du_outer"].to_numpy())
    stored = groups["G_model"].to_numpy()
    worst = np.max(np.abs(means / stored - 1))
    chi2 = np.sum(((groups["G"].to_numpy() - means) / groups["G_stderr"].to_numpy()) ** 2)
    if not fit["mirrored"]:
        chi2 = None  # the side below has a model of its own; its groups are not summed here
    x = 1e-3
    g, error = np.exp(model.ln_G(x)[0]), model.ln_G_stderr(x)[0]
    agrees = worst < 1e-9 and (chi2 is None or abs(chi2 / fit["chi2"] - 1) < 1e-9)
    symbol = "G" if part == "total" else "G_self"
    print(f"  {potential} {part}: {len(model.t)} knots, {symbol}(0 -> {x}) = {g:.5g} +- {g * error:.2g}; "
          f"group means within {worst:.1e} of the table's, chi2 {fit['chi2']:.1f} "
          f"(expected {fit['chi2_expected']:.1f}, p = {fit['p_value']:.3f}) "
          f"{'agrees' if agrees else 'DISAGREES'}")
    return agrees


def jackknife_stderr(left_out):
    """sqrt((R - 1)/R sum_r (v_r - mean)^2) over the first axis."""
    count = left_out.shape[0]
    return np.sqrt((count - 1) / count * np.sum((left_out - left_out.mean(axis=0)) ** 2, axis=0))


def lagrange_weights(nodes, at):
    """The weights of the values at `nodes` in the Lagrange polynomial at `at`."""
    return np.array([np.prod([(at - nodes[j]) / (nodes[i] - nodes[j])
                              for j in range(len(nodes)) if j != i])
                     for i in range(len(nodes))])


def interpolate_in_n(kernels, du):
    """G(0 -> du) at an n halfway in 1/n between the bundle's first two inverse
    power laws: ln G through every one's model (Lagrange in 1/n), its error
    jackknifed over the shared randomizations, and the interpolation's own estimate
    of its error (the polynomial less the one without the farthest node). Checks that
    each model's jackknife replicates give its covariance's error."""
    laws = sorted((float(p.removeprefix("ipp-")), p) for p in kernels
                  if p.startswith("ipp-") and float(p.removeprefix("ipp-")) > 2)
    if len(laws) < 3:
        print(f"  fewer than three inverse power laws with n > 2 ({[p for _, p in laws]}): none")
        return True
    models = [KernelModel(kernels[p]["kernel_model"], kernels[p]["kernel_model_covariance"],
                          jackknife_path=kernels[p]["kernel_model_jackknife"]) for _, p in laws]
    agrees = all(np.allclose(jackknife_stderr(m.ln_G_left_out(du)), m.ln_G_stderr(du),
                             rtol=1e-6) for m in models)
    nodes = np.array([1 / n for n, _ in laws])
    at = 0.5 * (nodes[0] + nodes[1])
    weights = lagrange_weights(nodes, at)
    ln_g = sum(w * m.ln_G(du)[0] for w, m in zip(weights, models))
    left_out = sum(w * m.ln_G_left_out(du)[:, 0] for w, m in zip(weights, models))
    error = jackknife_stderr(left_out[:, None])[0]
    kept = np.argsort(np.abs(nodes - at))[:-1]
    lower = sum(w * models[k].ln_G(du)[0]
                for w, k in zip(lagrange_weights(nodes[kept], at), kept))
    g = np.exp(ln_g)
    print(f"  n = {1 / at:.4g} from {[p for _, p in laws]} in 1/n: G(0 -> {du}) = {g:.5g} "
          f"+- {g * error:.2g} (interpolation {abs(ln_g - lower):.1%}); each model's "
          f"jackknife gives its covariance's error {'agrees' if agrees else 'DISAGREES'}")
    return agrees


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

    print("kernel model (the whole and its self part), evaluated here from its knots:")
    for potential, tables in two.items():
        for part in ("total", "self"):
            failed |= not check_kernel_model(potential, tables, part)
    print("kernel model between the computed inverse power laws:")
    failed |= not interpolate_in_n(kernels, 1e-3)
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
