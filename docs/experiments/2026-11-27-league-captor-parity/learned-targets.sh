#!/usr/bin/env bash
# docs/experiments/2026-11-27-league-captor-parity.md, second part, for
# seed S (the first argument; 0 by default). Naive co-evolution of that
# seed is run first: t2e-league run --config configs/league-naive-coevo.toml
# --dir runs/league/naive-s0 (seed 1: the config of
# docs/experiments/2026-11-26-league-exploitability-seed1, --dir runs/league/naive-s1).
# Then the validated league's captors (run.sh's runs/captors-eval/sS-captors) and
# naive co-evolution's captors against every learned target of the two
# (and the rule-based target).
set -euo pipefail
cd "$(dirname "$0")/../../.."
bin=./target/release/t2e-league
s=${1:-0}
out=runs/learned-targets-s$s
mkdir -p $out
while pgrep -f "run --config .*naive-coevo.*--dir runs/league/naive-s$s" > /dev/null; do sleep 10; done
[ -d $out/naive-captors ] || $bin export captors-main --dir runs/league/naive-s$s --out $out/naive-captors > /dev/null
[ -d $out/naive-target ] || $bin export target-main --dir runs/league/naive-s$s --out $out/naive-target > /dev/null
for c in league:runs/captors-eval/s$s-captors naive:$out/naive-captors; do
  for t in best:runs/val-eval/s$s/best last:runs/val-eval/s$s/last naive:$out/naive-target rule:heuristic; do
    tag=${c%%:*}-vs-${t%%:*}
    target=${t#*:}; [ "$target" = heuristic ] || target=ckpt:$target
    [ -f $out/$tag/summary.json ] || OMP_NUM_THREADS=1 $bin eval --captors ckpt:${c#*:} --target $target --maps small,medium,large --episodes 100 --seed 0 --out $out/$tag > /dev/null
  done
done
$bin table --cross $out/*-vs-* --out $out/table.md
echo done
