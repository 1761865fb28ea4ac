#!/usr/bin/env bash
# The bar every target is measured against: a fresh best response of the
# same budget (1 M env steps; the captor learner of
# configs/league-recommended.toml, which league.toml copies) against each
# target, trained on generated maps, played on the large Gibson maps for
# 1,000 episodes: evaluation seed 0 (exploit's own evaluation) and seed 1
# (`eval` of the same best response). Held-out protocol, one thread.
#   bash run.sh BIN OUT
set -euo pipefail
bin=$1
out=$2
here=$(dirname "$0")
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
robust=robust:10:heuristic+expert:1+expert:2
[ -d "$out/league" ] || "$bin" run --config "$here/league.toml" --dir "$out/league"
for ratio in 1.2 1.0; do
    for player in rule-based-target "$robust-target"; do
        tag=$(echo "$player" | cut -d: -f1 | sed 's/-target//')
        "$bin" exploit "$player" --dir "$out/league" --budget 1000000 --seed 0 \
            --speed-ratio "$ratio" --maps large --episodes 1000 --threads 1 --quiet \
            | tee "$out/exploit-$tag-$ratio.txt"
    done
done
# Seed 1: each best response (the newest checkpoint of its run folder under
# exploits/) against the target it trained against, on new starts.
for ratio in 1.2 1.0; do
    for target in heuristic "$robust"; do
        key=$( [ "$target" = heuristic ] && echo rule-based-target || echo robust)
        for run in "$out"/league/exploits/"$key"*/run; do
            ratio_of_run=$(grep -o '^target_speed = [0-9.]*' "$run/config.toml" | cut -d' ' -f3)
            [ "$ratio_of_run" = "$ratio" ] || continue
            "$bin" eval --captors "ckpt:$run" --target "$target" --k 3 --speed-ratio "$ratio" \
                --maps large --episodes 1000 --episode-length 500 --seed 1 \
                --soa-every 0 --quiet --resume --out "$out/seed1-$(echo "$target" | cut -d: -f1)-$ratio"
        done
    done
done
