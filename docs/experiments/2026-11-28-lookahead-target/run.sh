#!/usr/bin/env bash
# The lookahead target as a controller, beside the rule-based target, on the
# same starts (evaluation seed 0) against three captor teams. Held-out
# protocol: nothing here trained on the Gibson maps. Each eval runs on one
# thread; run two at a time on a 2-core machine.
#   bash run.sh BIN OUT [TEAM...]   TEAM: expert, greedy2, mappo (default all)
# mappo needs OUT/mappo-heldout-s0, the CPU default (held-out) trained with
#   OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 BIN train \
#     --config configs/cpu-3v1-1.0-heldout.toml --out OUT/mappo-heldout-s0 \
#     --total-env-steps 3500000
set -euo pipefail
bin=$1
out=$2
shift 2
teams=${*:-expert greedy2 mappo}
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
for team in $teams; do
    case $team in
        expert) captors=heuristic; episodes=200 ;;
        greedy2) captors=greedy:2; episodes=100 ;;
        mappo) captors=ckpt:$out/mappo-heldout-s0; episodes=500 ;;
    esac
    for target in heuristic lookahead:10; do
        name=$team-${target//:/}
        # 1.0:1.0 on large maps; 1.0:1.2 on every class.
        "$bin" eval --captors "$captors" --target "$target" --k 3 --speed-ratio 1.0 \
            --maps large --episodes $episodes --episode-length 500 --seed 0 \
            --soa-every 0 --quiet --resume --out "$out/$name-1.0"
        "$bin" eval --captors "$captors" --target "$target" --k 3 --speed-ratio 1.2 \
            --maps small,medium,large --episodes $episodes --episode-length 500 --seed 0 \
            --soa-every 0 --quiet --resume --out "$out/$name-1.2"
    done
done
