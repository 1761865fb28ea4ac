#!/usr/bin/env bash
# The CPU default held-out cell with and without sight (12 wall rays), two
# seeds, the same env-step budget as the CPU default's 10 minutes of one
# core (3.5 M env steps, the learning rate annealed over them), then the
# Gibson maps at 1.0:1.0, 500 greedy episodes per class, evaluation seed 0
# (the same starts for every team, so the comparison is paired).
#   bash run.sh BIN OUT
set -euo pipefail
bin=$1
out=$2
here=$(cd "$(dirname "$0")" && pwd)
repo=$(cd "$here/../../.." && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
mkdir -p "$out"
for seed in 0 1; do
    for inputs in spec sight; do
        cfg=$repo/configs/cpu-3v1-1.0-heldout.toml
        [ $inputs = sight ] && cfg=$repo/configs/cpu-3v1-1.0-heldout-sight.toml
        sed "s/^seed = 0/seed = $seed/" "$cfg" > "$out/$inputs-s$seed.toml"
        "$bin" train --config "$out/$inputs-s$seed.toml" --out "$out/$inputs-s$seed" \
            --total-env-steps 3500000 --quiet --resume
        "$bin" eval --captors "ckpt:$out/$inputs-s$seed" --target heuristic --k 3 \
            --speed-ratio 1.0 --maps small,medium,large --episodes 500 --episode-length 500 \
            --seed 0 --soa-every 0 --quiet --resume --out "$out/eval-$inputs-s$seed"
    done
done
python3 "$here/paired.py" "$out"
