"""Time of a study from its store: the stages' wall seconds of every fresh instance, summed
per stage from the artifacts' manifests (a sharded instance counts its shards or its merge,
whichever recorded more: a merge's wall includes the shards it ran itself).
usage: python3 docs/scripts/study_time.py CONFIG [SHARDS]   (from the repository, store `data`;
$TERNARY names the binary, default ./target/release/ternary)"""
import json, os, re, subprocess, sys, glob, collections
cfg = sys.argv[1]
shards = sys.argv[2] if len(sys.argv) > 2 else None
cmd = [os.environ.get('TERNARY', './target/release/ternary'), 'status', '--config', cfg] + (['--shards', shards] if shards else [])
run = subprocess.run(cmd, capture_output=True, text=True)
out = run.stdout + run.stderr
per_stage = collections.Counter(); count = collections.Counter(); stale = 0
shard_of = collections.defaultdict(float)
for stage_dir in glob.glob('data/artifacts/*.shard'):
    for m in glob.glob(f'{stage_dir}/*/manifest.json'):
        j = json.load(open(m)); shard_of[j['params']['of']] += j['wall_seconds']
for line in out.splitlines():
    m = re.match(r'(\S+)\[(.*)\]\s+fresh \(key ([0-9a-f]+)\)', line)
    if not m:
        if re.match(r'\S+\[', line): stale += 1
        continue
    stage, inst, short = m.groups()
    dirs = glob.glob(f'data/artifacts/{stage}/{short}*')
    assert len(dirs) == 1, (stage, inst, dirs)
    j = json.load(open(f'{dirs[0]}/manifest.json'))
    per_stage[stage] += max(j['wall_seconds'], shard_of.get(j['key'], 0.0))  # a merge's wall includes the shards it ran itself
    count[stage] += 1
tot = sum(per_stage.values())
for s, v in per_stage.most_common():
    print(f'{s:14s} {count[s]:4d} instances {v:9.0f} s  {v/tot:6.1%}')
print(f'total {tot:.0f} s = {tot/3600:.2f} h of stage wall time; not fresh: {stale}')
