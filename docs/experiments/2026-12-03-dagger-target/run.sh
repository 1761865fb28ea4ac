#!/usr/bin/env bash
# Learned targets fitted to the robust lookahead target by DAgger
# (dagger-*.toml), each 600 k env steps (3.2 M the more-data one) against the
# expert captors at 1.0:1.2 on generated maps; the test team with sight
# (cooperative MAPPO reading 12 wall rays, seed 0, 3.5 M env steps against
# the rule-based target, as ../2026-12-01-robust-target/sight.sh trains
# it); then the rule-based target, the robust target and the DAgger
# targets against teams the learners never met, on the same starts
# (evaluation seed 0), 500 episodes on the large Gibson maps. Held-out
# protocol, one thread per command.
#   bash run.sh BIN OUT STEP
# STEP: sight (the test team), w1, w10, w10-large-sight or
# w10-large-sight-more-data, w10-large-sight-one-model,
# w10-large-sight-then-rl (a DAgger target), play-TEAM (mappo-sight,
# expert7, greedy2, or team-r: cooperative MAPPO with the spec's inputs,
# the folder TEAM_R names, as ../2026-12-03-league-robust-member/run.sh
# trains it: every target against that team; VARIANTS, default "w1 w10
# w10-large-sight": the DAgger targets played).
set -euo pipefail
bin=$1
out=$2
step=$3
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../../.." && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
mkdir -p "$out"
train() { # CONFIG OUT_NAME [FLAGS...]
    local resume
    resume=$([ -f "$out/$2/state.json" ] && echo --resume || true)
    "$bin" train --config "$1" --out "$out/$2" --threads 1 --quiet $resume "${@:3}"
}
play() { # CAPTORS TEAM_NAME TARGET TARGET_NAME RATIO EPISODES
    "$bin" eval --captors "$1" --target "$3" --k 3 --speed-ratio "$5" --maps large \
        --episodes "$6" --episode-length 500 --seed 0 --soa-every 0 --quiet --resume \
        --out "$out/$2-$4-$5"
}
robust=robust:10:heuristic+expert:1+expert:2
targets() { # CAPTORS TEAM_NAME RATIO EPISODES
    play "$1" "$2" heuristic heuristic "$3" "$4"
    for variant in ${VARIANTS:-w1 w10 w10-large-sight}; do
        play "$1" "$2" "ckpt:$out/dagger-$variant" "dagger-$variant" "$3" "$4"
    done
    play "$1" "$2" "$robust" robust "$3" "$4"
}
case $step in
    sight) train "$root/configs/cpu-3v1-1.0-heldout-sight.toml" mappo-sight-s0 --total-env-steps 3500000 ;;
    w1 | w10 | w10-large-sight | w10-large-sight-more-data | w10-large-sight-one-model | w10-large-sight-then-rl)
        train "$here/dagger-$step.toml" "dagger-$step" ;;
    play-mappo-sight) for ratio in 1.2 1.0; do targets "ckpt:$out/mappo-sight-s0" mappo-sight "$ratio" 500; done ;;
    play-expert7) targets expert:7 expert7 1.2 500 ;;
    play-greedy2) targets greedy:2 greedy2 1.2 200 ;;
    play-team-r) targets "ckpt:$TEAM_R" team-r 1.2 500 ;;
    *) echo "run.sh: unknown step $step" >&2; exit 2 ;;
esac
