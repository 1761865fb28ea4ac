#!/usr/bin/env bash
# docs/experiments/2026-11-28-captors-vs-naive.md: for league seed S (the
# first argument), naive co-evolution with the same seed (3 M env steps per
# learner), then both sides' captors (the recommended league's captors-main,
# runs/exploit-eval/tshare-sS/captors, and naive co-evolution's captors-main)
# against both sides' learned targets (the league's validation-best target,
# runs/exploit-eval/tshare-sS/best, and naive co-evolution's target-main). Held-out
# protocol, 100 greedy episodes of 500 steps per Gibson class, 3:1 at
# 1.0:1.0, evaluation seed 0. Needs target-exploiter-share.sh S and
# target-exploiter-share-target.sh S (2026-11-27-league-exploitability) first.
# Usage: naive-vs-league.sh S
set -euo pipefail
cd "$(dirname "$0")/../../.."
s=$1
bin=${BIN:-./target/release/t2e-league}
case $s in
  0) config=configs/league-naive-coevo.toml ;;
  1) config=docs/experiments/2026-11-26-league-exploitability-seed1/naive-coevo-seed1.toml ;;
  2) config=docs/experiments/2026-11-27-league-captor-parity/naive-coevo-seed2.toml ;;
  *) echo "seed must be 0, 1 or 2" >&2; exit 2 ;;
esac
league=runs/exploit-eval/tshare-s$s naive=runs/league/naive-s$s out=runs/captors-eval/s$s
mkdir -p $out
if [ ! -f $out/naive-trained ]; then
  start=$(date +%s)
  $bin run --config $config --dir $naive > $naive.log 2>&1
  echo "wall-clock: $(( $(date +%s) - start )) s on $(nproc) cores, $(date -u +%F)" > $out/naive-trained
fi
[ -d $out/naive-target ] || $bin export target-main --dir $naive --out $out/naive-target
[ -d $out/naive-captors ] || $bin export captors-main --dir $naive --out $out/naive-captors
for target in $league/best $out/naive-target; do
  for team in $league/captors $out/naive-captors; do
    tag=$(basename $(dirname $team))-$(basename $team)-vs-$(basename $(dirname $target))-$(basename $target)
    [ -f $out/$tag/summary.json ] && continue
    OMP_NUM_THREADS=1 RAYON_NUM_THREADS=1 $bin eval --captors "ckpt:$team" --target "ckpt:$target" \
      --maps small,medium,large --episodes 100 --seed 0 --out $out/$tag --quiet > /dev/null
  done
done
$bin table --cross $out/*-vs-* --out $out/table.md
cat $out/table.md
echo "all done $(date -u +%T)"
