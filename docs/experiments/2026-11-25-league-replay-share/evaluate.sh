#!/usr/bin/env bash
# The Table V cells of the league with one replay share per side
# (docs/experiments/2026-11-25-league-replay-share.md), also used for
# docs/experiments/2026-11-25-league-ego.md: the league's captors and target
# against the held-out teams and the rule-based target, 100 greedy episodes
# of 500 steps per Gibson class, seed 0. Usage: evaluate.sh LEAGUE_DIR
# COOP_RUN OUT (COOP_RUN: a `t2e-league train --config
# docs/experiments/2026-11-25-league-4.8M/coop.toml --out runs/coop` run
# folder). Writes OUT/table-v.md.
set -euo pipefail
league=$1 coop=$2 out=$3
bin=${BIN:-./target/release/t2e-league}
mkdir -p "$out"
for p in target-main captors-main; do
  [ -d "$out/$p" ] || "$bin" export "$p" --dir "$league" --out "$out/$p"
done
pair() { # captors target name
  [ -f "$out/tv/$3/summary.json" ] && return
  OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 "$bin" eval --captors "$1" --target "$2" \
    --maps small,medium,large --episodes 100 --seed 0 --out "$out/tv/$3" > /dev/null
}
# Two chains of pairs, one per core (each eval runs on one thread).
{
  pair "ckpt:$out/captors-main" heuristic league-captors-rule-based
  pair "ckpt:$out/captors-main" "ckpt:$out/target-main" league-captors-league-target
  pair "ckpt:$coop" "ckpt:$out/target-main" coop-league-target
  pair "ckpt:$coop" heuristic coop-rule-based
} &
chain=$!
pair greedy:2 "ckpt:$out/target-main" greedy2-league-target
pair heuristic "ckpt:$out/target-main" expert-league-target
wait "$chain"
"$bin" table --cross "$out"/tv/* --out "$out/table-v.md"
