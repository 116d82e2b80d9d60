#!/usr/bin/env bash
# Two commits' studies on this machine, one after the other (docs/benchmarks.md):
#
#     docs/scripts/compare-commits.sh BASE NEW [CONFIG]
#
# Checks each commit out into a scratch worktree, builds its binary, runs CONFIG
# (default: each commit's own pipeline.toml; a relative path is taken in each
# worktree) into the worktree's own empty store under /usr/bin/time, and prints
# for each run the wall time, user + system CPU and peak memory, each stage's
# wall-time sum from the manifests, and NEW's ratios to BASE. Nothing outside the
# scratch directory is written but the build directory: CARGO_TARGET_DIR, else
# ~/.cache/ternary-target when it exists (.ci/run's), else one in the scratch
# directory (a cold build, ~11 minutes). The worktrees are removed at the end, so
# the build's records point at deleted sources and the clone's next build redoes
# its own crate instead of trusting the other commit's.
#
# The machine should be otherwise idle: the ratio is only as good as the two runs
# are alike. Run it twice, in both orders, to see the spread.
set -euo pipefail

if [[ $# -lt 2 || $# -gt 3 ]]; then
    sed -n '2,18p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
fi
base=$1 new=$2 config=${3:-pipeline.toml}
repo=$(git rev-parse --show-toplevel)
scratch=$(mktemp -d "${TMPDIR:-/tmp}/ternary-compare.XXXXXX")
if [[ -z "${CARGO_TARGET_DIR:-}" ]]; then
    if [[ -d "$HOME/.cache/ternary-target" ]]; then
        export CARGO_TARGET_DIR="$HOME/.cache/ternary-target"
    else
        export CARGO_TARGET_DIR="$scratch/target"
    fi
fi
cleanup() {
    for name in base new; do
        git -C "$repo" worktree remove --force "$scratch/$name" 2>/dev/null || true
    done
}
trap cleanup EXIT
echo "scratch: $scratch (stores and timings stay there); builds in $CARGO_TARGET_DIR"

build() { # name commit
    local name=$1 commit=$2
    git -C "$repo" worktree add --quiet --detach "$scratch/$name" "$commit"
    (cd "$scratch/$name" && cargo build --release --quiet --bin ternary)
    cp "$CARGO_TARGET_DIR/release/ternary" "$scratch/ternary-$name"
}

run() { # name
    local name=$1
    (cd "$scratch/$name" &&
        /usr/bin/time -f '%e %U %S %M' -o "$scratch/time-$name" \
            "$scratch/ternary-$name" --config "$config" run --quiet >"$scratch/run-$name.log" 2>&1)
}

build base "$base"
build new "$new"
run base
run new

python3 - "$scratch" "$base" "$new" <<'EOF'
import glob, json, os, sys
scratch, base, new = sys.argv[1:4]
runs = {}
for name in ('base', 'new'):
    wall, user, system, rss = open(f'{scratch}/time-{name}').read().split()
    stages = {}
    for path in glob.glob(f'{scratch}/{name}/**/artifacts/*/*/manifest.json', recursive=True):
        manifest = json.load(open(path))
        stage = manifest['stage']
        stages[stage] = stages.get(stage, 0.0) + manifest['wall_seconds']
    runs[name] = dict(wall=float(wall), cpu=float(user) + float(system), rss=int(rss) / 1e6, stages=stages)
b, n = runs['base'], runs['new']
print(f'| | {base} (base) | {new} (new) | new / base |')
print('|---|---|---|---|')
print(f"| wall | {b['wall']:.0f} s | {n['wall']:.0f} s | {n['wall'] / b['wall']:.2f} |")
print(f"| CPU (user + system) | {b['cpu']:.0f} s | {n['cpu']:.0f} s | {n['cpu'] / b['cpu']:.2f} |")
print(f"| peak resident | {b['rss']:.1f} GB | {n['rss']:.1f} GB | {n['rss'] / b['rss']:.2f} |")
for stage in sorted(set(b['stages']) | set(n['stages']), key=lambda s: -b['stages'].get(s, n['stages'].get(s))):
    sb, sn = b['stages'].get(stage), n['stages'].get(stage)
    ratio = f'{sn / sb:.2f}' if sb and sn else '-'
    text = lambda v: '-' if v is None else f'{v:.0f} s'
    print(f'| stage {stage} (wall sum) | {text(sb)} | {text(sn)} | {ratio} |')
EOF
