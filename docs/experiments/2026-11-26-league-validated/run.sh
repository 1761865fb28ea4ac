#!/usr/bin/env bash
# docs/experiments/2026-11-26-league-validated.md: the three seeds of
# configs/league-validated.toml one after another, each league's target
# exported twice (the validation-best snapshot and the last weights), and
# both screened against the test teams: greedy:2 and cooperative MAPPO
# (held out), 100 greedy episodes of 500 steps per Gibson class, 3:1 at
# 1.0:1.0, evaluation seed 0. The screens of one seed run (at low
# priority) while the next seed's league trains.
# Usage: run.sh COOP_RUN OUT (COOP_RUN: t2e-league train --config
# docs/experiments/2026-11-25-league-ego/coop.toml --out runs/coop-ego)
set -euo pipefail
coop=$1 out=$2
here=$(cd "$(dirname "$0")" && pwd)
bin=${BIN:-./target/release/t2e-league}
mkdir -p "$out"
screen() { # seed
  local s=$1 d="$out/s$1"
  mkdir -p "$d"
  # The cooperative team must be finished: its folder's newest checkpoint
  # is what ckpt: plays.
  while pgrep -f "train --config .*coop.toml" > /dev/null; do sleep 20; done
  [ -d "$d/best" ] || "$bin" export --best target --dir "runs/league/val-s$s" --out "$d/best" > "$d/best.txt"
  [ -d "$d/last" ] || "$bin" export target-main --dir "runs/league/val-s$s" --out "$d/last" > /dev/null
  for which in best last; do
    for team in greedy:2 "ckpt:$coop"; do
      local tag; tag=$(echo "$team" | tr -c 'a-z0-9\n' '-' | cut -c1-12)
      [ -f "$d/tv/$which-$tag/summary.json" ] && continue
      OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 nice -n 10 "$bin" eval --captors "$team" \
        --target "ckpt:$d/$which" --maps small,medium,large --episodes 100 --seed 0 \
        --out "$d/tv/$which-$tag" > /dev/null
    done
  done
  "$bin" table --cross "$d"/tv/* --out "$d/table.md"
}
prev=
for s in 0 1 2; do
  [ -f "$out/s$s.trained" ] || {
    "$bin" run --config "$here/seed$s.toml" --dir "runs/league/val-s$s" &
    league=$!
    [ -n "$prev" ] && screen "$prev"
    wait $league
    touch "$out/s$s.trained"
  }
  prev=$s
done
screen 2
