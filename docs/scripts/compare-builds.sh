#!/usr/bin/env bash
# Two commits' cold builds on this machine, one after the other (docs/benchmarks.md):
#
#     docs/scripts/compare-builds.sh BASE NEW
#
# Checks each commit out into a scratch worktree, fetches its dependencies (so
# that downloads stay out of the timing), and builds its binary as a fresh
# machine would, `cargo build --release --bin ternary` into an empty target
# directory of its own, under /usr/bin/time. Prints for each build the wall
# time, user + system CPU and peak memory, and NEW's ratios to BASE. Nothing
# outside the scratch directory is written but cargo's download cache; the
# worktrees and target directories (~2 GB each) are removed at the end.
#
# The machine should be otherwise idle: the ratio is only as good as the two
# builds are alike. Each build takes 10-20 minutes on the 2-core VM.
set -euo pipefail

if [[ $# -ne 2 ]]; then
    sed -n '2,15p' "$0" | sed 's/^# \{0,1\}//' >&2
    exit 2
fi
base=$1 new=$2
repo=$(git rev-parse --show-toplevel)
scratch=$(mktemp -d "${TMPDIR:-/tmp}/ternary-builds.XXXXXX")
cleanup() {
    for name in base new; do
        git -C "$repo" worktree remove --force "$scratch/$name" 2>/dev/null || true
        rm -rf "$scratch/target-$name"
    done
}
trap cleanup EXIT
echo "scratch: $scratch (timings stay there)"

build() { # name commit
    local name=$1 commit=$2
    git -C "$repo" worktree add --quiet --detach "$scratch/$name" "$commit"
    (cd "$scratch/$name" && cargo fetch --quiet)
    (cd "$scratch/$name" &&
        CARGO_TARGET_DIR="$scratch/target-$name" /usr/bin/time -f '%e %U %S %M' \
            -o "$scratch/time-$name" cargo build --release --quiet --bin ternary)
}

build base "$base"
build new "$new"

read -r base_wall base_user base_system base_memory <"$scratch/time-base"
read -r new_wall new_user new_system new_memory <"$scratch/time-new"
printf '%-5s %-12s %9s %9s %9s %12s\n' "" commit "wall s" "user s" "system s" "peak MB"
printf '%-5s %-12s %9.0f %9.0f %9.0f %12.0f\n' base "$base" "$base_wall" "$base_user" \
    "$base_system" "$((base_memory / 1024))"
printf '%-5s %-12s %9.0f %9.0f %9.0f %12.0f\n' new "$new" "$new_wall" "$new_user" \
    "$new_system" "$((new_memory / 1024))"
awk -v bw="$base_wall" -v bu="$base_user" -v nw="$new_wall" -v nu="$new_user" \
    'BEGIN { printf "new / base: wall %.2fx, user CPU %.2fx\n", nw / bw, nu / bu }'
