#!/usr/bin/env bash
# Cooperative MAPPO captors trained against the rule-based target and
# against the robust lookahead target (rule.toml, robust.toml: 2 M env
# steps at 1.0:1.2 on generated maps, seed 0), then each team against the
# two targets it trained against and two it never met: another robust
# target (other models) and the best hand-made target of the ceiling probe.
# 500 greedy episodes of 500 steps on the large Gibson maps, evaluation
# seed 0, the same starts for every team and target; at 1.0:1.2 and 1.0:1.0.
# Held-out protocol, one thread per command.
#   bash run.sh BIN OUT
# TEAMS (default "rule robust"): the configs here to train and play.
set -euo pipefail
bin=$1
out=$2
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
mkdir -p "$out"
teams=${TEAMS:-rule robust}
for team in $teams; do
    resume=$([ -f "$out/$team/state.json" ] && echo --resume || true)
    "$bin" train --config "$here/$team.toml" --out "$out/$team" --threads 1 --quiet $resume
done
targets=(
    "heuristic rule"
    "robust:10:heuristic+expert:1+expert:2 robust"
    "robust:10:heuristic+expert:3 robust-other"
    "tuned:0.0988,0.4284,0.6137,-0.2019,0.1183 tuned-best"
)
for ratio in 1.2 1.0; do
    for team in $teams; do
        for entry in "${targets[@]}"; do
            read -r target name <<< "$entry"
            "$bin" eval --captors "ckpt:$out/$team" --target "$target" --k 3 --speed-ratio "$ratio" \
                --maps large --episodes 500 --episode-length 500 --seed 0 --soa-every 0 --quiet \
                --resume --out "$out/$team-vs-$name-$ratio"
        done
    done
done
