#!/usr/bin/env bash
# Learned targets leaning on the robust lookahead target (planner-prior.toml,
# prior 10; planner-prior-w3.toml and -w6.toml, priors 3 and 6; 600 k env steps against the
# expert captors at 1.0:1.2 on generated maps), then played by `greedy:2`,
# a team they never met, on the large Gibson maps, evaluation seed 0, the
# starts the rule-based and robust targets were played on (folders
# greedy2-heuristic-R and greedy2-robust-R in OUT, from
# ../2026-12-01-robust-target's commands): 500 episodes at 1.0:1.0 and at
# 1.0:1.2 (prior 6: 1.0:1.0 only). The prior-10 target also against
# `expert:7` (200 episodes at 1.0:1.2, beside OUT/expert7-heuristic-1.2 and
# expert7-robust-1.2 from ../2026-12-01-robust-target/run.sh) and against
# cooperative MAPPO with sight (500 episodes at 1.0:1.2 and 1.0:1.0, beside
# the folders of ../2026-12-01-robust-target/sight.sh, whose team
# OUT/mappo-sight-s0 it plays). Held-out protocol, one thread per command.
#   bash run.sh BIN OUT STEP
# STEP: train, train-w3 or train-w6; play-1.0 or play-1.2 (prior 10);
# play-w3-1.0 or play-w3-1.2 (prior 3); play-w6-1.0 (prior 6);
# play-expert7, play-sight-1.0 or play-sight-1.2 (prior 10); train-w8 (prior
# 8); play-w6-sight-1.0, play-w6-sight-1.2, play-w8-sight-1.0 or
# play-w8-sight-1.2 (priors 6 and 8 against MAPPO with sight).
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
play() { # NAME RATIO [TEAM CAPTORS EPISODES]
    local team=${3:-greedy2} captors=${4:-greedy:2} episodes=${5:-500}
    "$bin" eval --captors "$captors" --target "ckpt:$out/$1" --k 3 --speed-ratio "$2" \
        --maps large --episodes "$episodes" --episode-length 500 --seed 0 --soa-every 0 --quiet --resume \
        --out "$out/$team-$1-$2"
}
case $step in
    train) train planner-prior ;;
    train-w3) train planner-prior-w3 ;;
    train-w6) train planner-prior-w6 ;;
    train-w8) train planner-prior-w8 ;;
    play-1.0) play planner-prior 1.0 ;;
    play-1.2) play planner-prior 1.2 ;;
    play-w3-1.0) play planner-prior-w3 1.0 ;;
    play-w3-1.2) play planner-prior-w3 1.2 ;;
    play-w6-1.0) play planner-prior-w6 1.0 ;;
    play-expert7) play planner-prior 1.2 expert7 expert:7 200 ;;
    play-sight-1.0) play planner-prior 1.0 mappo-sight "ckpt:$out/mappo-sight-s0" ;;
    play-sight-1.2) play planner-prior 1.2 mappo-sight "ckpt:$out/mappo-sight-s0" ;;
    play-w[68]-sight-1.[02])
        w=${step:5:2} ratio=${step: -3}
        play "planner-prior-$w" "$ratio" mappo-sight "ckpt:$out/mappo-sight-s0" ;;
    *) echo "run.sh: unknown step $step" >&2; exit 2 ;;
esac
