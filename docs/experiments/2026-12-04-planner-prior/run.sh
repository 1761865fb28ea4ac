#!/usr/bin/env bash
# A learned target leaning on the robust lookahead target (planner-prior.toml,
# 600 k env steps against the expert captors at 1.0:1.2 on generated maps),
# then played by `greedy:2`, a team it never met, on the large Gibson maps:
# 500 episodes at 1.0:1.0 and at 1.0:1.2, evaluation seed 0, the starts the
# rule-based and robust targets were played on (folders of the same names
# in OUT from ../2026-12-01-robust-target's commands). Held-out protocol,
# one thread per command.
#   bash run.sh BIN OUT STEP      STEP: train, play-1.0 or play-1.2
set -euo pipefail
bin=$1
out=$2
step=$3
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
mkdir -p "$out"
play() { # RATIO
    "$bin" eval --captors greedy:2 --target "ckpt:$out/planner-prior" --k 3 --speed-ratio "$1" \
        --maps large --episodes 500 --episode-length 500 --seed 0 --soa-every 0 --quiet --resume \
        --out "$out/greedy2-planner-prior-$1"
}
case $step in
    train)
        resume=$([ -f "$out/planner-prior/state.json" ] && echo --resume || true)
        "$bin" train --config "$here/planner-prior.toml" --out "$out/planner-prior" --threads 1 --quiet $resume ;;
    play-1.0) play 1.0 ;;
    play-1.2) play 1.2 ;;
    *) echo "run.sh: unknown step $step" >&2; exit 2 ;;
esac
