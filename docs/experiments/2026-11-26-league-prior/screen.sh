#!/usr/bin/env bash
# Screen of a league's target (docs/experiments/2026-11-26-league-prior.md):
# greedy:2 and cooperative MAPPO (both held out) against target-main, 100
# greedy episodes of 500 steps per Gibson class, seed 0. Writes OUT/table.md.
# Usage: screen.sh LEAGUE_DIR COOP_RUN OUT (COOP_RUN: the cooperative MAPPO
# captors, t2e-league train --config
# docs/experiments/2026-11-25-league-ego/coop.toml --out runs/coop-ego)
set -euo pipefail
league=$1 coop=$2 out=$3
bin=${BIN:-./target/release/t2e-league}
mkdir -p "$out"
[ -d "$out/target-main" ] || "$bin" export target-main --dir "$league" --out "$out/target-main"
lt="ckpt:$out/target-main"
pair() {
  [ -f "$out/tv/$3/summary.json" ] && return
  OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 "$bin" eval --captors "$1" --target "$2" \
    --maps small,medium,large --episodes 100 --seed 0 --out "$out/tv/$3" > /dev/null
}
pair greedy:2 "$lt" greedy2-league-target &
pair "ckpt:$coop" "$lt" coop-league-target
wait
"$bin" table --cross "$out"/tv/* --out "$out/table.md"
grep -E "^\| (greedy|ckpt)" "$out/table.md" | head -4
