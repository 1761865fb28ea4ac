#!/usr/bin/env bash
# A learned target distilled from the robust lookahead target, and its
# control, each trained for 1 M env steps against the expert captors at
# 1.0:1.2 on generated maps (teacher.toml, rule.toml); then both, the
# rule-based target and the robust target against teams the learners never
# met, on the same starts (evaluation seed 0), 500 episodes on the large
# Gibson maps. Held-out protocol, one thread per command.
#   bash run.sh BIN OUT SIGHT_TEAM
# VARIANTS (default "teacher rule"): the configs here to train and play;
# "teacher-no-prior rule-no-prior" are the same without the logit prior,
# "teacher-kl50" the distilled one with a KL ten times as strong,
# "teacher-departures100" (and -sight, and teacher-departures20) the KL 100
# (20) times as strong where the teacher departs from the rule.
# SIGHT_TEAM: the cooperative MAPPO team with sight that
# ../2026-12-01-robust-target/sight.sh trains (its OUT/mappo-sight-s0); its
# rule-based and robust rows are that script's, on the same starts.
set -euo pipefail
bin=$1
out=$2
sight=$3
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
mkdir -p "$out"
variants=${VARIANTS:-teacher rule}
for variant in $variants; do
    resume=$([ -f "$out/$variant/state.json" ] && echo --resume || true)
    "$bin" train --config "$here/$variant.toml" --out "$out/$variant" --threads 1 --quiet $resume
done
play() { # CAPTORS TEAM_NAME TARGET TARGET_NAME RATIO
    "$bin" eval --captors "$1" --target "$3" --k 3 --speed-ratio "$5" --maps large \
        --episodes 500 --episode-length 500 --seed 0 --soa-every 0 --quiet --resume \
        --out "$out/$2-$4-$5"
}
robust=robust:10:heuristic+expert:1+expert:2
for ratio in 1.2 1.0; do
    for variant in $variants; do
        play "ckpt:$sight" mappo-sight "ckpt:$out/$variant" "$variant" "$ratio"
    done
done
play expert:7 expert7 heuristic heuristic 1.2
play expert:7 expert7 "$robust" robust 1.2
for variant in $variants; do
    play expert:7 expert7 "ckpt:$out/$variant" "$variant" 1.2
done
