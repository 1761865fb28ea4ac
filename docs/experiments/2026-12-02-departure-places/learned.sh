#!/usr/bin/env bash
# The robust lookahead target with a learned captor team among its models:
# cooperative MAPPO of seed 1 (rule.toml of the captors-vs-robust
# experiment with seed = 1), beside the expert captors and two randomised
# expert teams. It plays the MAPPO team of seed 0 (run.sh's
# OUT/mappo-rule, which must be there), which it never modelled; the
# rule-based target plays the same starts. Large Gibson maps, 1.0:1.2,
# evaluation seed 0, one thread. Run after run.sh.
#   bash learned.sh BIN OUT
set -euo pipefail
bin=$1
out=$2
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
mkdir -p "$out"
sed 's/^seed = 0/seed = 1/; s/^name = "captors-vs-rule"/name = "captors-vs-rule-s1"/' \
    "$here/../2026-12-02-captors-vs-robust/rule.toml" > "$out/rule-s1.toml"
resume=$([ -f "$out/mappo-rule-s1/state.json" ] && echo --resume || true)
"$bin" train --config "$out/rule-s1.toml" --out "$out/mappo-rule-s1" --threads 1 --quiet $resume
robust=robust:10:heuristic+expert:1+expert:2
play() { # TARGET NAME EPISODES SOA_EVERY
    "$bin" eval --captors "ckpt:$out/mappo-rule" --target "$1" --k 3 --speed-ratio 1.2 \
        --maps large --episodes "$3" --episode-length 500 --seed 0 \
        --soa-every "$4" --quiet --resume --out "$out/pair-mappo-$2"
}
# The base, on run.sh's starts; run.sh's OUT/mappo-robust is the robust
# target without the learned model.
play heuristic heuristic 100 1
# About 25 ms a decision on a loaded core: 60 episodes, the first 60 of
# the others' starts (paired.py compares them on those).
play "$robust+ckpt:$out/mappo-rule-s1" robust-learned "${EPISODES:-60}" 0
