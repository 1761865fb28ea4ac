#!/usr/bin/env bash
# The robust lookahead target beside the rule-based target, on the same
# starts (evaluation seed 0), on the large Gibson maps at 1.0:1.0 and
# 1.0:1.2. Held-out protocol: nothing here trained on the Gibson maps.
# Each eval runs on one thread.
#   bash run.sh BIN OUT TEAM...
# TEAM: expert (a model of the planner), expert7 (a randomised expert of a
# seed it never modelled), mappo (cooperative MAPPO, the CPU default under
# the held-out protocol, trained against the rule-based target:
#   OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 BIN train \
#     --config configs/cpu-3v1-1.0-heldout.toml --out OUT/mappo-heldout-s0 \
#     --total-env-steps 3500000 --threads 1), greedy2, and lomo (the
# leave-one-model-out check: planned against the expert captors and
# expert:1, played against expert:2).
set -euo pipefail
bin=$1
out=$2
shift 2
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
episodes=${EPISODES:-200}
# MAPS: a Gibson class other than large writes OUT/TEAM-TARGET-RATIO-CLASS;
# RATIOS: the target's speed over the captors' (1.0 is v_p:v_e 1.0:1.0).
maps=${MAPS:-large}
ratios=${RATIOS:-1.0 1.2}
robust=robust:10:heuristic+expert:1+expert:2
for team in "$@"; do
    targets="heuristic $robust"
    case $team in
        expert) captors=heuristic ;;
        expert7) captors=expert:7 ;;
        mappo) captors=ckpt:$out/mappo-heldout-s0 ;;
        greedy2) captors=greedy:2 ;;
        lomo) captors=expert:2; targets="heuristic robust:10:heuristic+expert:1" ;;
    esac
    for target in $targets; do
        name=$team-$(echo "$target" | cut -d: -f1)
        for ratio in $ratios; do
            folder=$out/$name-$ratio
            [ "$maps" = large ] || folder=$folder-$maps
            "$bin" eval --captors "$captors" --target "$target" --k 3 --speed-ratio "$ratio" \
                --maps "$maps" --episodes "$episodes" --episode-length 500 --seed 0 \
                --soa-every 0 --quiet --resume --out "$folder"
        done
    done
done
