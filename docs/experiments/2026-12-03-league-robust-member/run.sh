#!/usr/bin/env bash
# The league with the robust lookahead target as a target member
# (league.toml: configs/league-robust-member.toml at 2 M env steps per
# learner, a seed-1 cooperative MAPPO team on its validation panel), then
# its captors and its exported target against teams and targets it never
# met, beside cooperative MAPPO captors of the same budget (team R,
# ../2026-12-02-captors-vs-robust/rule.toml, seed 0). 500 greedy episodes
# of 500 steps on the large Gibson maps, evaluation seed 0, the same starts
# for every player. Held-out protocol.
#   bash run.sh BIN OUT [STEP]
# STEP: teams (team R and the panel team, side by side, one thread each),
# league, export, eval, or all (the default). Every step resumes.
set -euo pipefail
bin=$(realpath "$1")
out=$2
step=${3:-all}
here=$(cd "$(dirname "$0")" && pwd)
export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
mkdir -p "$out"
out=$(realpath "$out")

train() {  # CONFIG FOLDER
    local resume
    resume=$([ -f "$2/state.json" ] && echo --resume || true)
    "$bin" train --config "$1" --out "$2" --threads 1 --quiet $resume
}

play() {  # CAPTORS TARGET RATIO NAME
    "$bin" eval --captors "$1" --target "$2" --k 3 --speed-ratio "$3" \
        --maps large --episodes 500 --episode-length 500 --seed 0 --soa-every 0 --quiet \
        --resume --out "$out/$4-$3"
}

if [[ $step == teams || $step == all ]]; then
    train "$here/../2026-12-02-captors-vs-robust/rule.toml" "$out/rule" &
    train "$here/panel-mappo-s1.toml" "$out/panel-mappo-s1" &
    wait
fi
if [[ $step == league || $step == all ]]; then
    # The league resolves `ckpt:panel-mappo-s1` from where it runs.
    cd "$out"
    if [ -f league/league.db ]; then
        "$bin" run --dir league
    else
        "$bin" run --config "$here/league.toml" --dir league
    fi
    cd - > /dev/null
fi
if [[ $step == export || $step == all ]]; then
    [ -d "$out/captors" ] || "$bin" export captors-main --dir "$out/league" --out "$out/captors"
    [ -d "$out/target" ] || "$bin" export --best target --dir "$out/league" --out "$out/target"
fi
if [[ $step == eval || $step == all ]]; then
    robust="robust:10:heuristic+expert:1+expert:2"
    for ratio in 1.2 1.0; do
        for team in captors rule; do
            play "ckpt:$out/$team" heuristic "$ratio" "$team-vs-rule" &
            play "ckpt:$out/$team" "$robust" "$ratio" "$team-vs-robust" &
            wait
        done
    done
    play "ckpt:$out/rule" "ckpt:$out/target" 1.2 "rule-vs-target" &
    play greedy:2 heuristic 1.2 "greedy2-vs-rule" &
    wait
    play greedy:2 "ckpt:$out/target" 1.2 "greedy2-vs-target"
fi
