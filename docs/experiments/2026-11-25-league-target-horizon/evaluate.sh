#!/usr/bin/env bash
# Table V for docs/experiments/2026-11-25-league-target-horizon.md (also used
# for the exploiter and prior leagues): the league's, naive co-evolution's
# and cooperative training's captors, the held-out ASZ-greedy captors
# (greedy:2) and the expert heuristic, against the rule-based target and the
# two learned targets. 100 greedy episodes of 500 steps per Gibson class,
# 3:1 at 1.0:1.0, seed 0.
# Usage: evaluate.sh LEAGUE_DIR COOP_RUN COEVO_RUN OUT
#   LEAGUE_DIR: t2e-league run --config docs/experiments/2026-11-25-league-target-horizon/league.toml --dir runs/league/target-horizon
#   COOP_RUN:   t2e-league train --config docs/experiments/2026-11-25-league-ego/coop.toml --out runs/coop-ego
#   COEVO_RUN:  t2e-league train --config docs/experiments/2026-11-25-league-target-horizon/coevo.toml --out runs/coevo-target
# greedy:2 and the expert against the rule-based target are not re-run
# (planners: 47.3% pooled and 78.4 / 64.6 / 42.8%, docs/results/heuristics.md).
set -euo pipefail
league=$1 coop=$2 coevo=$3 out=$4
bin=${BIN:-./target/release/t2e-league}
mkdir -p "$out"
for p in target-main captors-main; do
  [ -d "$out/$p" ] || "$bin" export "$p" --dir "$league" --out "$out/$p"
done
lc="ckpt:$out/captors-main" lt="ckpt:$out/target-main"
cc="ckpt:$coevo" ct="ckpt:$coevo"
pair() { # captors target name
  [ -f "$out/tv/$3/summary.json" ] && return
  OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 "$bin" eval --captors "$1" --target "$2" \
    --maps small,medium,large --episodes 100 --seed 0 --out "$out/tv/$3" > /dev/null
}
# Two chains, one per core (each eval runs on one thread); the planners'
# pairs are the slow ones, split between them.
{
  pair greedy:2 "$lt" greedy2-league-target
  pair "$lc" heuristic league-captors-rule-based
  pair "$lc" "$lt" league-captors-league-target
  pair "$lc" "$ct" league-captors-coevo-target
  pair "ckpt:$coop" "$lt" coop-league-target
  pair heuristic "$lt" expert-league-target
} &
chain=$!
pair greedy:2 "$ct" greedy2-coevo-target
pair "$cc" heuristic coevo-captors-rule-based
pair "$cc" "$ct" coevo-captors-coevo-target
pair "$cc" "$lt" coevo-captors-league-target
pair "ckpt:$coop" "$ct" coop-coevo-target
pair "ckpt:$coop" heuristic coop-rule-based
pair heuristic "$ct" expert-coevo-target
wait "$chain"
"$bin" table --cross "$out"/tv/* --out "$out/table-v.md"
