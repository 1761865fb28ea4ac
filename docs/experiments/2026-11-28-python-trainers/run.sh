#!/usr/bin/env bash
# Stable-Baselines3 PPO through SuperSuit against the project's own PyTorch
# example, captors against the rule-based target, 1 M captor steps each
# (333.8 k env steps), seeds 0 and 1, one thread per run, two runs at a
# time; then both tested greedily on the same 500 starts per class of the
# Gibson test maps (and of their own training maps), and the figure.
#   bash docs/experiments/2026-11-28-python-trainers/run.sh
set -euo pipefail
cd "$(dirname "$0")/../../.."
here=docs/experiments/2026-11-28-python-trainers
py=.venv/bin/python
export RAYON_NUM_THREADS=1
for seed in 0 1; do
  $py python/examples/sb3_captors.py --captor-steps 1000000 --seed $seed --eval-episodes 500 --out runs/sb3-captors-s$seed &
done
wait
for seed in 0 1; do
  # 326 iterations of 16 worlds x 64 steps: 333,824 env steps, 1,001,472 captor steps.
  $py python/examples/ppo_captors.py --iterations 326 --seed $seed --out runs/py-ppo-s$seed &
done
wait
for seed in 0 1; do
  $py $here/evaluate_ppo.py runs/py-ppo-s$seed --episodes 500 &
done
wait
$py $here/report.py runs/sb3-captors-s0 runs/sb3-captors-s1 runs/py-ppo-s0 runs/py-ppo-s1 --out $here
