"""Held-out kernels against the kernel model interpolated in n and theta (issue 59, item
2, a first measurement): the models of the default study's inverse power laws (n = 4..12,
u' = 0) interpolated to n = 7 and 9, and of its Lennard-Jones thetas (in ln theta, through
the nearest thetas at least 0.2 apart in ln theta) to theta = 0.3 and 3, against those
kernels computed by the validation study.

    cargo run --release -- run                                          # the default study
    cargo run --release -- run --config docs/studies/kernel-validation.toml
    python3 docs/scripts/kernel-interpolation.py pipeline.toml docs/studies/kernel-validation.toml

(The validation study keeps its store in docs/studies/data/; run both from the repository.)

At each log-spaced group, ln G (the model's group mean) is interpolated through the five
n by the Lagrange polynomial of degree 4 in 1/n (and, for comparison, in n and by
least-squares polynomials of lower degree); the prediction's error is the models' own
(ln_G_stderr at the group's middle, kernel_model_covariance) through the Lagrange weights,
the n taken as independent. a_n is interpolated the same way, as ln a_n.
Prints the largest and median |z| over the groups measured to better than a third, and
the relative difference of the interpolated a_n.
"""
import pathlib
import subprocess
import sys

import numpy as np
import pyarrow.parquet as pq

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[2] / "examples"))
from bundle import KernelModel  # noqa: E402

BINARY = pathlib.Path(__file__).resolve().parents[2] / "target/release/ternary"


def artifact(config, stage, instance):
    """The artifact directory of `stage[instance]` of a study, as `ternary show` lists it."""
    shown = subprocess.run([BINARY, "--config", config, "show", stage],
                           capture_output=True, text=True, check=True).stdout.splitlines()
    line = next(k for k, text in enumerate(shown) if text.startswith(f"{stage}[{instance}] "))
    return pathlib.Path(shown[line + 1].split()[0]).parent


def kernel(config, potential):
    """Above u': group middles, measured G and its pooled error, the model's group means
    and their errors (relative), and a_n untruncated (`potential`: an id, or n)."""
    potential = potential if isinstance(potential, str) else f"ipp-{potential}"
    fit = artifact(config, "fit", f"{potential}_u0_rho0")
    groups = pq.read_table(fit / "kernel_model_groups.parquet").to_pandas()
    groups = groups[(groups.part == "total") & (groups.du > 0)].sort_values("du")
    model = KernelModel(fit / "kernel_model.parquet", fit / "kernel_model_covariance.parquet")
    moments = pq.read_table(artifact(config, "moments", f"{potential}_u0_rho0") / "moments.parquet")
    moments = moments.to_pandas()
    # a_n untruncated (with a well: the free-atom rate, X = infinity row)
    a_n = moments[moments.truncation.isna()].self_variance.iloc[0]
    return (groups.du.to_numpy(), groups.G.to_numpy(), groups.G_stderr.to_numpy(),
            groups.G_model.to_numpy(), model.ln_G_stderr(groups.du.to_numpy()), a_n)


def weights(nodes, target, degree):
    """Linear weights of the values at `nodes` that give the fitted polynomial at `target`."""
    if degree == len(nodes) - 1:
        return np.array([np.prod([(target - nodes[j]) / (nodes[i] - nodes[j])
                                  for j in range(len(nodes)) if j != i])
                         for i in range(len(nodes))])
    design = np.vander(nodes, degree + 1)
    return np.vander([target], degree + 1)[0] @ np.linalg.pinv(design)


def held_out(label, target, nodes, models, measured):
    """Predictions of one held-out kernel from `models` at `nodes` (a coordinate each)."""
    du, g, g_error, _, _, a_target = measured
    resolved = g > 3 * g_error
    for degree in range(len(nodes) - 1, 1, -1):
        w = weights(np.array(nodes), target, degree)
        ln_g = sum(wi * np.log(m[3]) for wi, m in zip(w, models))
        ln_error = np.sqrt(sum((wi * m[4]) ** 2 for wi, m in zip(w, models)))
        predicted = np.exp(ln_g)
        z = (g - predicted) / np.hypot(g_error, predicted * ln_error)
        a_n = np.exp(w @ np.log([m[5] for m in models]))
        print(f"{label}, degree {degree}: |z| largest {np.max(np.abs(z[resolved])):.2f}, "
              f"median {np.median(np.abs(z[resolved])):.2f} ({resolved.sum()} groups); "
              f"a {a_n:.6e} against {a_target:.6e} ({a_n / a_target - 1:+.1e})")


def theta_nodes(thetas, target, count):
    """The `count` computed thetas nearest `target` in ln theta, each at least 0.2 from
    those taken (0.1 and 0.1052 are one node)."""
    taken = []
    for theta in sorted(thetas, key=lambda t: abs(np.log(t / target))):
        if all(abs(np.log(theta / t)) >= 0.2 for t in taken):
            taken.append(theta)
        if len(taken) == count:
            break
    return sorted(taken)


def main():
    default, validation = sys.argv[1], sys.argv[2]
    computed = [4, 6, 8, 10, 12]
    models = {n: kernel(default, n) for n in computed}
    for target in (7, 9):
        du, g, g_error, _, _, a_target = kernel(validation, target)
        resolved = g > 3 * g_error
        for variable in ("1/n", "n"):
            to = (lambda n: 1 / n) if variable == "1/n" else (lambda n: n)
            nodes = np.array([to(n) for n in computed])
            for degree in (4, 3, 2):
                w = weights(nodes, to(target), degree)
                ln_g = sum(wi * np.log(models[n][3]) for wi, n in zip(w, computed))
                ln_error = np.sqrt(sum((wi * models[n][4]) ** 2 for wi, n in zip(w, computed)))
                predicted = np.exp(ln_g)
                z = (g - predicted) / np.hypot(g_error, predicted * ln_error)
                a_n = np.exp(w @ np.log([models[n][5] for n in computed]))
                print(f"n = {target}, degree {degree} in {variable}: |z| largest "
                      f"{np.max(np.abs(z[resolved])):.2f}, median {np.median(np.abs(z[resolved])):.2f} "
                      f"({resolved.sum()} groups); a_n {a_n:.6e} against {a_target:.6e} "
                      f"({a_n / a_target - 1:+.1e})")


    thetas = [0.05, 0.1, 0.2, 0.5, 0.8, 1, 2, 5, 10, 20, 50, 100]
    for target in (0.3, 3):
        measured = kernel(validation, f"lj-{target:g}")
        for count in (5, 4):
            nodes = theta_nodes(thetas, target, count)
            models = [kernel(default, f"lj-{t:g}") for t in nodes]
            held_out(f"theta = {target} from {nodes} in ln theta", np.log(target),
                     [np.log(t) for t in nodes], models, measured)


if __name__ == "__main__":
    main()
