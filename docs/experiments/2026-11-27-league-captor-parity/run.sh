#!/usr/bin/env bash
# docs/experiments/2026-11-27-league-captor-parity.md: the captors-main of
# the three validated leagues (docs/experiments/2026-11-26-league-validated)
# against the rule-based target on the Gibson maps, 100 greedy episodes of
# 500 steps per class, 3:1 at 1.0:1.0, evaluation seed 0, beside the
# cooperative MAPPO team's row (COOP_EVAL: its eval folder against the
# rule-based target, from the same experiment).
# Usage: run.sh COOP_EVAL OUT
set -euo pipefail
coop=$1 out=$2
bin=${BIN:-./target/release/t2e-league}
mkdir -p "$out"
for s in 0 1 2; do
  [ -d "$out/s$s-captors" ] || "$bin" export captors-main --dir "runs/league/val-s$s" --out "$out/s$s-captors" > /dev/null
  [ -f "$out/s$s-eval/summary.json" ] || OMP_NUM_THREADS=1 "$bin" eval --captors "ckpt:$out/s$s-captors" \
    --target heuristic --maps small,medium,large --episodes 100 --seed 0 --out "$out/s$s-eval" > /dev/null
done
"$bin" table --cross "$out"/s*-eval "$coop" --out "$out/table.md"
