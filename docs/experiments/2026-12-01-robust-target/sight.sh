#!/usr/bin/env bash
# The test team with sight: cooperative MAPPO reading 12 wall rays
# (configs/cpu-3v1-1.0-heldout-sight.toml), seed 0, trained against the
# rule-based target for 3.5 M env steps on one thread; then the rule-based
# and the robust target against it on the same starts (evaluation seed 0),
# large Gibson maps, 500 episodes at 1.0:1.2 and at 1.0:1.0. Held-out
# protocol. Pair the results with paired.py.
#   bash sight.sh BIN OUT
set -euo pipefail
bin=$1
out=$2
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
root=$(cd "$(dirname "$0")/../../.." && pwd)
mkdir -p "$out"
resume=$([ -f "$out/mappo-sight-s0/state.json" ] && echo --resume || true)
"$bin" train --config "$root/configs/cpu-3v1-1.0-heldout-sight.toml" --out "$out/mappo-sight-s0" \
    --total-env-steps 3500000 --threads 1 --quiet $resume
for ratio in 1.2 1.0; do
    for target in heuristic robust:10:heuristic+expert:1+expert:2; do
        name=mappo-sight-$(echo "$target" | cut -d: -f1)-$ratio
        "$bin" eval --captors "ckpt:$out/mappo-sight-s0" --target "$target" --k 3 --speed-ratio "$ratio" \
            --maps large --episodes 500 --episode-length 500 --seed 0 --soa-every 0 --quiet --resume \
            --out "$out/$name"
    done
done
