#!/usr/bin/env bash
# docs/experiments/2026-11-27-league-captor-parity.md, second part: seed 0.
# Naive co-evolution (configs/league-naive-coevo.toml, seed 0) is run
# first: t2e-league run --config configs/league-naive-coevo.toml --dir runs/league/naive-s0
# Then the validated league's captors (run.sh's runs/goal3/s0-captors) and
# naive co-evolution's captors against every learned target of the two
# (and the rule-based target).
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=./target/release/t2e-league
out=runs/goal3b
mkdir -p $out
while pgrep -f "run --config configs/league-naive-coevo.toml" > /dev/null; do sleep 10; done
[ -d $out/naive-captors ] || $bin export captors-main --dir runs/league/naive-s0 --out $out/naive-captors > /dev/null
[ -d $out/naive-target ] || $bin export target-main --dir runs/league/naive-s0 --out $out/naive-target > /dev/null
for c in league:runs/goal3/s0-captors naive:$out/naive-captors; do
  for t in best:runs/val-eval/s0/best last:runs/val-eval/s0/last naive:$out/naive-target rule:heuristic; do
    tag=${c%%:*}-vs-${t%%:*}
    target=${t#*:}; [ "$target" = heuristic ] || target=ckpt:$target
    [ -f $out/$tag/summary.json ] || OMP_NUM_THREADS=1 $bin eval --captors ckpt:${c#*:} --target $target --maps small,medium,large --episodes 100 --seed 0 --out $out/$tag > /dev/null
  done
done
$bin table --cross $out/*-vs-* --out $out/table.md
echo done
