#!/usr/bin/env bash
# The league with sight (league-sight.toml), tested against captor teams
# that never played in it, on the Gibson maps, on the same starts as the
# rule-based target (evaluation seed 0): the ASZ-greedy planner greedy:2,
# cooperative MAPPO with the spec's inputs and cooperative MAPPO with 12
# wall rays (the CPU default held-out cell, seed 0, 3.5 M env steps each,
# configs/cpu-3v1-1.0-heldout.toml and configs/cpu-3v1-1.0-heldout-sight.toml),
# and a fresh best response with sight for each target (`exploit`).
# Held-out protocol.
#   bash run.sh BIN LEAGUE OUT MAPPO_RUN MAPPO_SIGHT_RUN [STAGE...]
# STAGE: league (run or resume it), export, eval, exploit (default: all).
# Two league targets are tested: the one `export --best target` chooses on
# the validation panel (league-target) and the main learner as it stopped
# (league-final).
# EPISODES (default 200) episodes per setting; BUDGET (default 600000)
# env steps per best response; CONFIG (default league-sight.toml beside
# this script) the league's config for a new league.
set -euo pipefail
bin=$1
league=$2
out=$3
mappo=$4
mappo_sight=$5
shift 5
stages=${*:-league export eval exploit}
episodes=${EPISODES:-200}
budget=${BUDGET:-600000}
here=$(cd "$(dirname "$0")" && pwd)
config=${CONFIG:-$here/league-sight.toml}
mkdir -p "$out"
for stage in $stages; do
    case $stage in
    league)
        if [ -d "$league" ]; then
            "$bin" run --dir "$league"
        else
            "$bin" run --config "$config" --dir "$league"
        fi
        ;;
    export)
        "$bin" export --dir "$league" --best target --out "$out/league-target"
        "$bin" export --dir "$league" target-main --out "$out/league-final"
        "$bin" export --dir "$league" captors-main --out "$out/league-captors"
        ;;
    eval)
        export OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1
        for team in greedy2 mappo mappo-sight; do
            case $team in
                greedy2) captors=greedy:2 ;;
                mappo) captors=ckpt:$mappo ;;
                mappo-sight) captors=ckpt:$mappo_sight ;;
            esac
            for target in heuristic "ckpt:$out/league-target" "ckpt:$out/league-final"; do
                case $target in
                    heuristic) name=rule ;;
                    *league-target) name=league ;;
                    *) name=final ;;
                esac
                "$bin" eval --captors "$captors" --target "$target" --k 3 --speed-ratio 1.0 \
                    --maps large --episodes "$episodes" --episode-length 500 --seed 0 \
                    --soa-every 0 --quiet --resume --out "$out/eval-$team-$name"
            done
        done
        # The league's captors against the rule-based target, every class.
        "$bin" eval --captors "ckpt:$out/league-captors" --target heuristic --k 3 --speed-ratio 1.0 \
            --maps small,medium,large --episodes "$episodes" --episode-length 500 --seed 0 \
            --soa-every 0 --quiet --resume --out "$out/eval-league-captors"
        ;;
    exploit)
        # A best response with the league's learner settings (so with
        # sight) against the exported target and against the rule-based
        # target, the same budget each; its result goes to the store.
        for player in "$out/league-final" rule-based-target; do
            "$bin" exploit --dir "$league" --budget "$budget" --maps large \
                --episodes "$episodes" --speed-ratio 1.0 --threads 1 "$player"
        done
        ;;
    *) echo "unknown stage $stage" >&2; exit 2 ;;
    esac
done
python3 "$here/paired.py" "$out"
