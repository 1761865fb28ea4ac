#!/usr/bin/env bash
# The paper's Tables II and III, measured: for each cell (K:1, speed ratio),
# each learner and each protocol, train captors against the rule-based
# target for BUDGET env steps, evaluate them on the Gibson classes, and lay
# the results out beside the paper's numbers (`t2e-league table`).
#
#   BUDGET=30000000 EPISODES=500 scripts/paper-grid.sh          # the paper's budget
#   BUDGET=150000 EPISODES=100 CELLS="3:1.0" scripts/paper-grid.sh   # a CPU sample
#   FOR=4m JOBS=2 EPISODES=200 scripts/paper-grid.sh   # 4 minutes of one core per run
#
# Environment (defaults in brackets):
#   BIN        the t2e-league binary [target/release/t2e-league]
#   OUT        results folder [runs/paper-grid]
#   BUDGET     env steps per training run [30000000]
#   FOR        a wall-clock budget per training run instead (train --for:
#              90s, 4m, 1h), ending at BUDGET if that comes first; the
#              learning rate (lr_anneal) then anneals over the clock. Give
#              the runs the cores alone: a clock budget measures contention
#              as lost steps. A resumed run gets FOR again, so for a fair
#              cell let each finish in one go []
#   EPISODES   evaluation episodes per map class [500]
#   CELLS      "K:RATIO ..." [3:1.0 3:1.2 3:1.4 4:1.0 4:1.2 4:1.4]
#   LEARNERS   [mappo ippo maddpg maac]
#   PROTOCOLS  [paper]; "held-out" runs MAPPO only
#   ROLLOUT    rollout_steps per world and iteration [100]; every learner
#              gets it. The base config is configs/cpu-3v1-1.0.toml, the CPU
#              default (docs/results/cpu-default.md): its network for
#              every learner, its PPO settings for MAPPO and IPPO, its
#              [captors.maddpg] and [captors.maac] tables for those two
#   JOBS       runs in parallel, each with one thread [1]
#   DEVICE     auto, cpu or cuda [auto]
# Finished runs and evaluations are kept: run it again to resume.
set -euo pipefail
cd "$(dirname "$0")/.."
BIN=${BIN:-target/release/t2e-league}
OUT=${OUT:-runs/paper-grid}
BUDGET=${BUDGET:-30000000}
EPISODES=${EPISODES:-500}
CELLS=${CELLS:-"3:1.0 3:1.2 3:1.4 4:1.0 4:1.2 4:1.4"}
LEARNERS=${LEARNERS:-"mappo ippo maddpg maac"}
PROTOCOLS=${PROTOCOLS:-paper}
JOBS=${JOBS:-1}
DEVICE=${DEVICE:-auto}
ROLLOUT=${ROLLOUT:-100}
FOR=${FOR:-}
clock=()
[ -n "$FOR" ] && clock=(--for "$FOR")
mkdir -p "$OUT/configs"
export OMP_NUM_THREADS=${OMP_NUM_THREADS:-1} RAYON_NUM_THREADS=${RAYON_NUM_THREADS:-1}

one() { # protocol learner k ratio
    local protocol=$1 learner=$2 k=$3 ratio=$4
    local name="$protocol-$learner-${k}v1-$ratio"
    local maps="generated:20"
    [ "$protocol" = paper ] && maps="gibson"
    local cfg="$OUT/configs/$name.toml"
    sed -e "s/^name = .*/name = \"$name\"/" \
        -e "s/^protocol = .*/protocol = \"$protocol\"/" \
        -e "s/^maps = .*/maps = \"$maps\"/" \
        -e "s/^num_captors = .*/num_captors = $k/" \
        -e "s/^target_speed = .*/target_speed = $ratio/" \
        -e "s/^rollout_steps = .*/rollout_steps = $ROLLOUT/" \
        -e "s/^play = \"mappo\"/play = \"$learner\"/" \
        configs/cpu-3v1-1.0.toml > "$cfg"
    # The CPU config's tables are per learner ([captors.ppo], [captors.maddpg],
    # [captors.maac]); each learner reads its own and ignores the others.
    if [ ! -f "$OUT/runs/$name/.done" ]; then
        if [ -f "$OUT/runs/$name/state.json" ]; then
            "$BIN" train --resume --out "$OUT/runs/$name" --total-env-steps "$BUDGET" "${clock[@]}" --device "$DEVICE" --quiet
        else
            "$BIN" train --config "$cfg" --out "$OUT/runs/$name" --total-env-steps "$BUDGET" "${clock[@]}" --device "$DEVICE" --quiet
        fi
        touch "$OUT/runs/$name/.done"
    fi
    if [ ! -f "$OUT/evals/$name/summary.json" ]; then
        "$BIN" eval --captors "ckpt:$OUT/runs/$name" --target heuristic --k "$k" \
            --speed-ratio "$ratio" --maps small,medium,large --episodes "$EPISODES" \
            --episode-length 500 --seed 0 --soa-every 0 --quiet --out "$OUT/evals/$name"
    fi
}

running=0
for protocol in $PROTOCOLS; do
    for cell in $CELLS; do
        k=${cell%%:*}
        ratio=${cell##*:}
        for learner in $LEARNERS; do
            [ "$protocol" = held-out ] && [ "$learner" != mappo ] && continue
            one "$protocol" "$learner" "$k" "$ratio" > "$OUT/$protocol-$learner-${k}v1-$ratio.log" 2>&1 &
            running=$((running + 1))
            if [ "$running" -ge "$JOBS" ]; then
                wait -n || echo "a run failed: see its log in $OUT"
                running=$((running - 1))
            fi
        done
    done
done
wait || true
"$BIN" table "$OUT"/evals/* --out "$OUT/tables.md" --latex "$OUT/tables.tex"
