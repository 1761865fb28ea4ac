#!/usr/bin/env bash
# The robust lookahead target with a learned captor team among its models
# (cooperative MAPPO of seed 1, learned.sh's OUT/mappo-rule-s1), against
# the test teams it never modelled: the MAPPO team of seed 0 (run.sh's
# OUT/mappo-rule), expert:7 and greedy:2, beside the rule-based target and
# the robust target without the learned model on the same starts
# (evaluation seed 0). Large Gibson maps, one thread, batched learned
# models (one forward per simulated step for all moves). Run after run.sh
# and learned.sh; pair with paired.py (the rule-based target as base).
#   bash learned-teams.sh BIN OUT
set -euo pipefail
bin=$1
out=$2
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
robust=robust:10:heuristic+expert:1+expert:2
learned=$robust+ckpt:$out/mappo-rule-s1
# "CAPTORS TEAM RATIO EPISODES" per setting.
settings=${SETTINGS:-"ckpt:$out/mappo-rule mappo 1.2 200
ckpt:$out/mappo-rule mappo 1.0 200
expert:7 expert7 1.2 200
greedy:2 greedy2 1.2 100
greedy:2 greedy2 1.0 100"}
while read -r captors team ratio episodes; do
    for target in heuristic "$robust" "$learned"; do
        case $target in
            heuristic) name=heuristic ;;
            *ckpt:*) name=robust-learned ;;
            *) name=robust ;;
        esac
        "$bin" eval --captors "$captors" --target "$target" --k 3 --speed-ratio "$ratio" \
            --maps large --episodes "$episodes" --episode-length 500 --seed 0 \
            --soa-every 0 --quiet --resume --out "$out/teams/$team-$ratio-$name"
    done
done <<< "$settings"
