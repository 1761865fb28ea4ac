#!/usr/bin/env bash
# docs/experiments/2026-11-28-captors-vs-naive.md: the rule-based target
# against both sides' captors of seeds S... (the arguments), at 1.0:1.0 (naive
# co-evolution's captors; the league's were evaluated by
# target-exploiter-share.sh) and at 1.0:1.2 (both): a fixed target every
# best response should at least match. Held-out protocol, 100 greedy
# episodes of 500 steps per Gibson class, evaluation seed 0.
# Usage: rule-based-control.sh S...
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=${BIN:-./target/release/t2e-league}
for s in "$@"; do
  for run in "1.0 runs/captors-eval/s$s/naive-captors" "1.2 runs/captors-eval/s$s/naive-captors" "1.2 runs/exploit-eval/tshare-s$s/captors"; do
    read -r ratio team <<< "$run"
    out=runs/captors-eval/rule-$ratio/$(echo $team | tr / -)
    [ -f $out/summary.json ] && continue
    OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 $bin eval --captors ckpt:$team --target heuristic \
      --maps small,medium,large --episodes 100 --seed 0 --speed-ratio $ratio --out $out --quiet > /dev/null
  done
done
