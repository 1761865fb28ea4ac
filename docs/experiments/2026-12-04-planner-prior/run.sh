#!/usr/bin/env bash
# Learned targets leaning on the robust lookahead target (planner-prior.toml,
# prior 10; planner-prior-w3.toml and -w6.toml, priors 3 and 6; 600 k env steps against the
# expert captors at 1.0:1.2 on generated maps), then played by `greedy:2`,
# a team they never met, on the large Gibson maps, evaluation seed 0, the
# starts the rule-based and robust targets were played on (folders
# greedy2-heuristic-R and greedy2-robust-R in OUT, from
# ../2026-12-01-robust-target's commands): 500 episodes at 1.0:1.0 and at
# 1.0:1.2 (prior 6: 1.0:1.0 only). Held-out protocol, one thread per command.
#   bash run.sh BIN OUT STEP
# STEP: train, train-w3 or train-w6; play-1.0 or play-1.2 (prior 10);
# play-w3-1.0 or play-w3-1.2 (prior 3); play-w6-1.0 (prior 6).
set -euo pipefail
bin=$1
out=$2
step=$3
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
mkdir -p "$out"
train() { # NAME
    local resume
    resume=$([ -f "$out/$1/state.json" ] && echo --resume || true)
    "$bin" train --config "$here/$1.toml" --out "$out/$1" --threads 1 --quiet $resume
}
play() { # NAME RATIO
    "$bin" eval --captors greedy:2 --target "ckpt:$out/$1" --k 3 --speed-ratio "$2" \
        --maps large --episodes 500 --episode-length 500 --seed 0 --soa-every 0 --quiet --resume \
        --out "$out/greedy2-$1-$2"
}
case $step in
    train) train planner-prior ;;
    train-w3) train planner-prior-w3 ;;
    train-w6) train planner-prior-w6 ;;
    play-1.0) play planner-prior 1.0 ;;
    play-1.2) play planner-prior 1.2 ;;
    play-w3-1.0) play planner-prior-w3 1.0 ;;
    play-w3-1.2) play planner-prior-w3 1.2 ;;
    play-w6-1.0) play planner-prior-w6 1.0 ;;
    *) echo "run.sh: unknown step $step" >&2; exit 2 ;;
esac
