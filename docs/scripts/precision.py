"""Precision of every quantity two studies share: the default study against the publication
study (docs/benchmarks.md, "The publication study"), or a study against itself at other
settings, each read from its own configuration's store.
usage: python3 docs/scripts/precision.py pipeline.toml publication.toml   (from the repository;
each artifact is the one `ternary show --config C 'stage[instance]'` names, in C's `store.path`;
$TERNARY names the binary, default ./target/release/ternary). Prints one markdown row per
quantity (values with standard errors, the error ratio default/publication, z of the
difference; kernels: median relative errors) and a summary per group."""
import json, os, sys, glob, subprocess, tomllib
import numpy as np, pyarrow.parquet as pq
rd, rp = sys.argv[1:3]

def store_of(config):
    with open(config, 'rb') as f:
        path = tomllib.load(f)['store']['path']
    return path if os.path.isabs(path) else os.path.join(os.path.dirname(config) or '.', path)

def table(config, stage, inst, f):
    out = subprocess.run([os.environ.get('TERNARY', './target/release/ternary'), 'show', '--config', config, f'{stage}[{inst}]'],
                         capture_output=True, text=True)
    if out.returncode != 0 or not out.stdout.startswith('{'):
        return None
    key = json.loads(out.stdout[:out.stdout.index('\n}') + 2])['key']
    path = f'{store_of(config)}/artifacts/{stage}/{key}/{f}'
    return pq.read_table(path).to_pandas() if os.path.exists(path) else None

rows = []  # (group, quantity, default value, default err, pub value, pub err)
def add(group, q, d, de, p, pe):
    rows.append((group, q, d, de, p, pe))

# 1. the paper table
P = {r: table(r, 'paper', 'study', 'paper.parquet') for r in (rd, rp)}
for (_, a), (_, b) in (zip(P[rd].iterrows(), P[rp].iterrows()) if P[rp] is not None else []):
    assert a.quantity == b.quantity
    add('paper', a.quantity, a.ours, a.ours_stderr, b.ours, b.ours_stderr)
    if a.converged == 'differs' and not np.isnan(a.ours_converged_stderr or np.nan):
        add('paper (converged)', a.quantity, a.ours_converged, a.ours_converged_stderr,
            b.ours_converged, b.ours_converged_stderr)

# 1b. the shape fit's statistical part (the paper protocol's row of each fit; the combined
# error above adds the fit-protocol spread, which no sample size shrinks)
for n in (4, 6, 8, 10, 12):
    fd, fp = (table(r, 'fit', f'ipp-{n}_u0_rho0', 'fit.parquet') for r in (rd, rp))
    if fd is None or fp is None:
        continue
    a, b = fd[fd.protocol == 'paper'].iloc[0], fp[fp.protocol == 'paper'].iloc[0]
    for q in ('alpha', 'beta', 'sigma'):
        add('shape fit, statistical', f'{q}, n = {n}', a[q], a[q + '_stderr'], b[q], b[q + '_stderr'])

# 2. the a_n table (every potential both studies hold)
T = {r: table(r, 'table', 'study', 'table.parquet') for r in (rd, rp)}
T = {r: (t.set_index('potential') if t is not None else None) for r, t in T.items()}
POTS = T[rp].index if T[rp] is not None else [p for p in T[rd].index if p in ('ipp-2','ipp-4','ipp-6','ipp-8','ipp-10','ipp-12','lj-0.1','lj-0.1052','lj-0.8','lj-10')]
for pot in (T[rp].index.intersection(T[rd].index) if T[rp] is not None else []):
    for col in ['a_n', 'recombination_rate', 'thermal_recombination_rate',
                'dissociation_rate']:
        a, b = T[rd].loc[pot], T[rp].loc[pot]
        if np.isnan(a[col]) or np.isnan(b[col]) or a[col + '_stderr'] == 0:
            continue
        add('table', f'{col} {pot}', a[col], a[col + '_stderr'], b[col], b[col + '_stderr'])

# 3. kernels at u' = 0: median relative error of near bins, far fine bins, far log groups
def med(k, lo, hi):
    s = k[(k.du.abs() >= lo) & (k.du.abs() <= hi) & (k.G != 0)]
    return float(np.median(s.G_stderr / s.G.abs()))
for pot in POTS:
    inst = f'{pot}_u0_rho0'
    kd, kp = (table(r, 'kernel', inst, 'kernel.parquet') for r in (rd, rp))
    ld, lp = (table(r, 'kernel', inst, 'kernel_log.parquet') for r in (rd, rp))
    if kd is None or kp is None:
        continue
    add('kernel median rel. err', f'{inst} near 1e-4..2e-3', 0, med(kd, 1e-4, 2e-3), 0, med(kp, 1e-4, 2e-3))
    add('kernel median rel. err', f'{inst} far fine 0.01..0.05', 0, med(kd, .01, .05), 0, med(kp, .01, .05))
    add('kernel median rel. err', f'{inst} far log groups 0.01..0.05', 0, med(ld, .01, .05), 0, med(lp, .01, .05))

# 4. spectrum gaps
for pot in POTS:
    sd, sp = (table(r, 'spectrum', pot, 'spectrum_summary.parquet') for r in (rd, rp))
    if sd is None or sp is None:
        continue
    for (_, a), (_, b) in zip(sd.iterrows(), sp.iterrows()):
        add('spectrum', f'gap/Gamma {pot} {a.generator}', a.gap_over_variance_rate,
            a.gap_over_variance_rate_stderr, b.gap_over_variance_rate, b.gap_over_variance_rate_stderr)

# 5. MD rings: window variance rate per estimator
for f in sorted(glob.glob(f'{store_of(rd)}/refs/md/*.json')):
    inst = os.path.basename(f)[:-5]
    md, mp = (table(r, 'md', inst, 'summary.parquet') for r in (rd, rp))
    if md is None or mp is None:
        continue
    for (_, a), (_, b) in zip(md.iterrows(), mp.iterrows()):
        add('md', f'{inst} {a.estimator} window variance', a.window_variance, a.window_variance_stderr,
            b.window_variance, b.window_variance_stderr)

first, second = (os.path.basename(r) for r in (rd, rp))
print(f"| group | quantity | {first} | {second} | error ratio | z (second - first) |")
print("|---|---|---|---|---|---|")
ratios = {}
for g, q, d, de, p, pe in rows:
    if de is None or pe is None or np.isnan(de) or np.isnan(pe) or pe == 0:
        continue
    ratio = de / pe
    ratios.setdefault(g, []).append(ratio)
    if g.startswith('kernel'):
        print(f"| {g} | {q} | {de:.2%} | {pe:.2%} | {ratio:.2f} | |")
    else:
        z = (p - d) / np.hypot(de, pe)
        print(f"| {g} | {q} | {d:.6g} +- {de:.2g} | {p:.6g} +- {pe:.2g} | {ratio:.2f} | {z:+.2f} |")
print()
for g, r in ratios.items():
    r = np.array(r)
    print(f"{g}: {len(r)} quantities, error ratio min {r.min():.2f}, median {np.median(r):.2f}, max {r.max():.2f}, below 3: {(r < 3).sum()}")
